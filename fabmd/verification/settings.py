"""``--set KEY=VALUE`` settings of the checks, read through the one scene schema.

Each check declares what ``--set`` may change as a dataclass (:class:`FibreSettings`
and its subclasses in the check modules); :func:`read` builds it with
:func:`fabmd.schema.build`, as scene-file tables are built: unknown keys are refused
naming the allowed ones, values may carry units (``--set diameter_m="0.1 mm"``) and a
dotted key fills a sub-table (``--set time_step.factor=0.2``, the scene files'
``[<test>.time_step] factor``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .. import schema
from ..errors import InputError
from ..model.beads import TimeStep
from ..model.material import GLASS, FibreMaterial, VirtualFibre
from ..schema import unit

#: former ``--set`` names -> the one name (that of the scene files' tables)
RENAMED = {"time_step_factor": "time_step.factor", "time_step_s": "time_step.value_s"}


@dataclass(frozen=True)
class FibreSettings:
    """What every check lets ``--set`` change: a solid fibre (glass, 0.1 mm by default),
    its bead spacing, the loading speed and the time step.

    Args:
        modulus_pa: fibre modulus [Pa].
        density_kg_m3: fibre density [kg/m³].
        diameter_m: fibre diameter [m].
        spacing_ratio: bead spacing over diameter.
        speed_fraction: loading speed over the fibre's wave speed.
        time_step: time-step policy (``time_step.factor``, ``time_step.value_s``).
    """

    modulus_pa: float = field(default=GLASS.modulus_pa, metadata=unit("pressure"))
    density_kg_m3: float = field(default=GLASS.density_kg_m3, metadata=unit("density"))
    diameter_m: float = field(default=0.1e-3, metadata=unit("length"))
    spacing_ratio: float = 0.5
    speed_fraction: float = 1e-4
    time_step: TimeStep = field(default_factory=TimeStep)

    def fibre(self, name: str) -> VirtualFibre:
        """The solid virtual fibre of these settings."""
        return VirtualFibre.solid(FibreMaterial(self.modulus_pa, self.density_kg_m3, name),
                                  self.diameter_m)


def read(cls: type, settings: dict, check: str):
    """``cls`` (a :class:`FibreSettings`) from ``--set`` values (nested at the dots).

    Raises:
        InputError: an unknown or renamed key, or a value of the wrong kind (one line).
    """
    for old, new in RENAMED.items():
        if old in settings:
            raise InputError(f"--set {old} is now --set {new} (the scene files' "
                             f"[<test>.time_step] {new.split('.')[1]})")
    return schema.build(cls, settings, check)
