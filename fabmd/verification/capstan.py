"""``fabmd validate capstan``: T_out/T_in against exp(μθ) for μ ∈ {0.1, 0.3}, θ ∈ {π/2, π}.

The fibre is softened to E = 1 GPa: at a fixed load strain T_in/(E·A) the ratio
does not depend on E (only the number of steps grows, as sqrt(E)), and the four
cases then run in seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..engine import Engine
from ..protocols.capstan import Capstan
from ..schema import unit
from .cases import run_cases
from .settings import FibreSettings, read

TOLERANCE = 0.05
FRICTIONS = (0.1, 0.3)
WRAP_ANGLES = (math.pi / 2, math.pi)
#: the softened modulus of the check [Pa] (the ratio is independent of E)
MODULUS_PA = 1e9
#: summary keys reported for each case
CASE_KEYS = ("mu", "theta_rad", "expected_ratio", "measured_ratio", "rel_error", "ratio_std",
             "max_overlap_ratio", "n_beads", "steps")


@dataclass(frozen=True)
class Settings(FibreSettings):
    """What ``--set KEY=VALUE`` may change (SI; units as text accepted); see
    :class:`~fabmd.verification.settings.FibreSettings` for the fibre (here softened).

    Args:
        radius_m: capstan radius [m].
        load_strain: end load over E·A.
        tool_stiffness_factor: the capstan's contact stiffness factor.
    """

    modulus_pa: float = field(default=MODULUS_PA, metadata=unit("pressure"))
    speed_fraction: float = 0.03
    radius_m: float = field(default=0.3e-3, metadata=unit("length"))
    load_strain: float = 1e-3
    tool_stiffness_factor: float = 0.1


def from_settings(settings: dict, friction: float, wrap_angle_rad: float) -> Capstan:
    """A :class:`Capstan` case with some defaults replaced (``--set`` values)."""
    from ..model.beads import Discretisation
    from ..model.contact import ToolContact

    s = read(Settings, settings, "capstan")
    return Capstan(fibre=s.fibre("glass, softened"), wrap_angle_rad=wrap_angle_rad,
                   tool=ToolContact(friction=friction, stiffness_factor=s.tool_stiffness_factor),
                   radius_m=s.radius_m, load_strain=s.load_strain,
                   speed_fraction=s.speed_fraction,
                   discretisation=Discretisation(spacing_ratio=s.spacing_ratio),
                   time_step=s.time_step)


def check(out: Path | None = None, engine: Engine | None = None, overwrite: bool = False,
          settings: dict[str, float] | None = None) -> dict:
    """Run the four capstan cases; each ratio must be within 5 % of exp(μθ)."""
    settings = settings or {}
    tests = [from_settings(settings, mu, theta) for mu in FRICTIONS for theta in WRAP_ANGLES]
    named = [(f"mu{t.friction:g}-theta{math.degrees(t.wrap_angle_rad):.0f}", t) for t in tests]
    head = {"check": "capstan", "closed_form": "T_out/T_in = exp(mu*theta)",
            "modulus_pa": tests[0].fibre.material.modulus_pa}
    return run_cases("capstan", named, CASE_KEYS, head, TOLERANCE, out, engine, overwrite)
