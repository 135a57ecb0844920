"""``fabmd validate capstan``: T_out/T_in against exp(μθ) for μ ∈ {0.1, 0.3}, θ ∈ {π/2, π}.

The fibre is softened to E = 1 GPa: at a fixed load strain T_in/(E·A) the ratio
does not depend on E (only the number of steps grows, as sqrt(E)), and the four
cases then run in seconds.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..engine import Engine
from ..protocols.capstan import Capstan
from .cases import run_cases
from .settings import check_known, fibre_from

TOLERANCE = 0.05
FRICTIONS = (0.1, 0.3)
WRAP_ANGLES = (math.pi / 2, math.pi)
#: the softened modulus of the check [Pa] (the ratio is independent of E)
MODULUS_PA = 1e9
#: summary keys reported for each case
CASE_KEYS = ("mu", "theta_rad", "expected_ratio", "measured_ratio", "rel_error", "ratio_std",
             "max_overlap_ratio", "n_beads", "steps")

#: settings ``--set KEY=VALUE`` may change
SETTINGS = ("modulus_pa", "density_kg_m3", "diameter_m", "spacing_ratio", "radius_m",
            "load_strain", "speed_fraction", "tool_stiffness_factor", "time_step_factor")


def from_settings(settings: dict[str, float], friction: float, wrap_angle_rad: float) -> Capstan:
    """A :class:`Capstan` case with some defaults replaced (SI values)."""
    from ..model.beads import Discretisation, TimeStep
    from ..model.contact import ToolContact

    check_known(settings, SETTINGS, "capstan")
    get = settings.get
    fibre = fibre_from(settings, MODULUS_PA, "glass, softened")
    return Capstan(fibre=fibre, wrap_angle_rad=wrap_angle_rad,
                   tool=ToolContact(friction=friction,
                                    stiffness_factor=get("tool_stiffness_factor", 0.1)),
                   radius_m=get("radius_m", 0.3e-3), load_strain=get("load_strain", 1e-3),
                   speed_fraction=get("speed_fraction", 0.03),
                   discretisation=Discretisation(spacing_ratio=get("spacing_ratio", 0.5)),
                   time_step=TimeStep(factor=get("time_step_factor", 0.25)))


def check(out: Path | None = None, engine: Engine | None = None, overwrite: bool = False,
          settings: dict[str, float] | None = None) -> dict:
    """Run the four capstan cases; each ratio must be within 5 % of exp(μθ)."""
    settings = settings or {}
    tests = [from_settings(settings, mu, theta) for mu in FRICTIONS for theta in WRAP_ANGLES]
    named = [(f"mu{t.friction:g}-theta{math.degrees(t.wrap_angle_rad):.0f}", t) for t in tests]
    head = {"check": "capstan", "closed_form": "T_out/T_in = exp(mu*theta)",
            "modulus_pa": tests[0].fibre.material.modulus_pa}
    return run_cases("capstan", named, CASE_KEYS, head, TOLERANCE, out, engine, overwrite)
