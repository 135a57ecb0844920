"""``fabmd validate capstan``: T_out/T_in against exp(μθ) for μ ∈ {0.1, 0.3}, θ ∈ {π/2, π}.

The fibre is softened to E = 1 GPa: at a fixed load strain T_in/(E·A) the ratio
does not depend on E (only the number of steps grows, as sqrt(E)), and the four
cases then run in seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from ..engine import Engine, mpi
from ..protocols.capstan import Capstan
from ..results.folder import prepare_run_folder
from ..schema import unit
from .settings import FibreSettings, read

TOLERANCE = 0.05
FRICTIONS = (0.1, 0.3)
WRAP_ANGLES = (math.pi / 2, math.pi)
#: the softened modulus of the check [Pa] (the ratio is independent of E)
MODULUS_PA = 1e9


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
    engine = engine or Engine()
    root = prepare_run_folder(out, overwrite=overwrite, prefix="capstan")
    cases, wall = [], 0.0
    for test in tests:
        name = f"mu{test.friction:g}-theta{math.degrees(test.wrap_angle_rad):.0f}"
        s = test.run(out=root / name, engine=engine).summary
        wall += s.get("wall_s", 0.0)
        cases.append({"mu": test.friction, "theta_rad": test.wrap_angle_rad,
                      "expected_ratio": s["expected_ratio"],
                      "measured_ratio": s["measured_ratio"], "rel_error": s["rel_error"],
                      "ratio_std": s["ratio_std"], "max_overlap_ratio": s["max_overlap_ratio"],
                      "n_beads": s["n_beads"], "steps": s["steps"]})
    worst = max(c["rel_error"] for c in cases)
    result = {
        "check": "capstan",
        "closed_form": "T_out/T_in = exp(mu*theta)",
        "modulus_pa": tests[0].fibre.material.modulus_pa,
        "tolerance": TOLERANCE,
        "max_rel_error": worst,
        "passed": worst <= TOLERANCE,
        "wall_s": wall,
        "run_dir": str(root),
        "cases": cases,
    }
    return mpi.bcast_json(result)
