"""Damping and the quasi-static stop criterion, shared by the relaxation stages.

Damping kinds:

* ``"cundall"`` — local non-viscous damping (``fix damping/cundall``): each force
  component is reduced by a fraction of its magnitude against the velocity. It
  damps every mode at the same rate per cycle and vanishes at equilibrium: the
  DEM choice for reaching a quasi-static state in few steps.
* ``"viscous"`` — ``fix viscous`` with γ = m/τ: drag proportional to velocity.
* ``"none"``.

Quasi-static criterion (checked every ``check_every`` steps): the kinetic energy
is below ``kinetic_ratio`` × (bond strain energy + a floor: the bonds' energy at
the reference force) AND the largest force on a free bead is below
``force_ratio`` × a reference force (the largest fibre tension the stage imposes).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .. import inputs
from .templates import render

DAMPING_KINDS = ("cundall", "viscous", "none")


@dataclass(frozen=True)
class Damping:
    """Numerical damping for quasi-static relaxation.

    Args:
        kind: ``"cundall"`` (default), ``"viscous"`` or ``"none"``.
        cundall_ratio: fraction of the force removed against the motion, in [0, 1).
        viscous_time_s: τ of viscous damping (γ = m/τ) [s], > 0.
    """

    kind: str = "cundall"
    cundall_ratio: float = 0.7
    viscous_time_s: float | None = None

    def __post_init__(self):
        inputs.one_of("damping.kind", self.kind, DAMPING_KINDS)
        inputs.in_range("damping.cundall_ratio", self.cundall_ratio, 0.0, 1.0, high_open=True)
        if self.viscous_time_s is not None:
            inputs.positive("damping.viscous_time_s", self.viscous_time_s)

    def commands(self, group: str, bead_mass_kg: float, default_time_s: float) -> str:
        """LAMMPS text for this damping acting on ``group``."""
        if self.kind == "none":
            return "# no numerical damping"
        if self.kind == "cundall":
            return f"fix             damping {group} damping/cundall {self.cundall_ratio:.6g} 0.0"
        tau = self.viscous_time_s or default_time_s
        return f"fix             damping {group} viscous {bead_mass_kg / tau:.10g}"


@dataclass(frozen=True)
class QuasiStatic:
    """When a relaxation is quasi-static (see the module docstring).

    Args:
        kinetic_ratio: KE / bond strain energy below which the state is at rest.
        force_ratio: largest free-bead force / reference force below which it is.
        check_every: steps between checks.
        max_steps: give up relaxing after this many steps (the summary then says
            the criterion was not met).
    """

    kinetic_ratio: float = 1e-4
    force_ratio: float = 2e-3
    check_every: int = 500
    max_steps: int = 200_000

    def __post_init__(self):
        inputs.positive("quasi_static.kinetic_ratio", self.kinetic_ratio)
        inputs.positive("quasi_static.force_ratio", self.force_ratio)
        inputs.positive_int("quasi_static.check_every", self.check_every)
        inputs.positive_int("quasi_static.max_steps", self.max_steps)

    def monitors(self, group: str, reference_force_n: float, reference_energy_j: float) -> str:
        """Computes and variables: ``v_qs_ke_ratio``, ``v_qs_force_ratio``, ``v_quasi_static``.

        Args:
            reference_force_n: the largest force the stage imposes on a fibre.
            reference_energy_j: an energy floor for the kinetic-energy ratio (the
                strain energy of the bonds at the reference force), so that a
                state with slack yarns can still be judged at rest.
        """
        return render("quasi_static", group=group, reference_force=reference_force_n,
                      reference_energy=reference_energy_j, kinetic_ratio=self.kinetic_ratio,
                      force_ratio=self.force_ratio)

    def stop_when_reached(self) -> str:
        """A ``fix halt`` that ends the next run once the criterion holds."""
        return (f"fix             settled all halt {self.check_every} v_quasi_static > 0.5 "
                f"error continue message yes")


#: what LAMMPS writes when the ``settled`` halt of a relaxation fires
SETTLED_MESSAGE = "Fix halt condition for fix-id settled met"


def relaxation_settled(log_path) -> bool | None:
    """Did the relaxation in this LAMMPS log reach the quasi-static criterion before its
    step limit? (None: no log to tell.) A relaxation that did not leaves a state still
    moving, and a test started from it mixes that motion into its curve."""
    path = Path(log_path)
    if not path.is_file():
        return None
    with path.open(errors="replace") as f:
        return any(SETTLED_MESSAGE in line for line in f)
