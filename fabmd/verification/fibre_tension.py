"""``fabmd validate fibre-tension``: force at 1 % strain against E·A·ε."""

from __future__ import annotations

from pathlib import Path

from ..engine import Engine
from ..protocols.fibre_tension import FibreTension
from .settings import check_known, fibre_from

TOLERANCE = 0.01

#: settings ``--set KEY=VALUE`` may change, and where they go
SETTINGS = ("modulus_pa", "density_kg_m3", "diameter_m", "length_m", "spacing_ratio",
            "mass_scaling", "time_step_factor", "time_step_s", "max_strain", "speed_fraction",
            "trajectory_frames")


def from_settings(settings: dict[str, float]) -> FibreTension:
    """A :class:`FibreTension` with some defaults replaced (SI values)."""
    from ..model.beads import Discretisation, TimeStep
    from ..model.material import GLASS
    from ..scene.outputs import TrajectoryOutput

    check_known(settings, SETTINGS, "fibre-tension")
    get = settings.get
    fibre = fibre_from(settings, GLASS.modulus_pa, GLASS.name)
    disc = Discretisation(spacing_ratio=get("spacing_ratio", 0.5),
                          mass_scaling=get("mass_scaling", 1.0))
    step = TimeStep(factor=get("time_step_factor", 0.25), value_s=get("time_step_s"))
    return FibreTension(fibre=fibre, length_m=get("length_m", 0.01), discretisation=disc,
                        time_step=step, max_strain=get("max_strain", 0.015),
                        speed_fraction=get("speed_fraction", 1e-4),
                        trajectory=TrajectoryOutput(frames=get("trajectory_frames", 20)))


def check(out: Path | None = None, engine: Engine | None = None, overwrite: bool = False,
          settings: dict[str, float] | None = None) -> dict:
    """Run the single-fibre tension and compare the force at 1 % strain with E·A·ε."""
    test = from_settings(settings or {})
    result = test.run(out=out, engine=engine, overwrite=overwrite)
    s = result.summary
    return {
        "check": "fibre-tension",
        "strain": s.get("check_strain_pct", 1.0) / 100,
        "axial_stiffness_n": s.get("axial_stiffness_n"),
        "expected_force_n": s.get("expected_force_n"),
        "measured_force_n": s.get("measured_force_n"),
        "rel_error": s.get("rel_error"),
        "tolerance": TOLERANCE,
        "passed": bool(s) and s["rel_error"] <= TOLERANCE,
        "n_beads": s.get("n_beads"),
        "steps": s.get("steps"),
        "max_kinetic_to_strain_energy": s.get("max_kinetic_to_strain_energy"),
        "wall_s": s.get("wall_s"),
        "ranks": s.get("ranks"),
        "run_dir": str(result.run_dir),
    }
