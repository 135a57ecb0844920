"""``fabmd validate fibre-tension``: force at 1 % strain against E·A·ε."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..engine import Engine
from ..protocols.fibre_tension import FibreTension
from ..schema import unit
from .settings import FibreSettings, read

TOLERANCE = 0.01


@dataclass(frozen=True)
class Settings(FibreSettings):
    """What ``--set KEY=VALUE`` may change (SI; units as text accepted); see
    :class:`~fabmd.verification.settings.FibreSettings` for the fibre.

    Args:
        length_m: fibre length [m].
        mass_scaling: bead mass scaling.
        max_strain: strain at the end of the pull.
        trajectory_frames: frames of the trajectory written.
    """

    length_m: float = field(default=0.01, metadata=unit("length"))
    mass_scaling: float = 1.0
    max_strain: float = 0.015
    trajectory_frames: int = 20


def from_settings(settings: dict) -> FibreTension:
    """A :class:`FibreTension` with some defaults replaced (``--set`` values)."""
    from ..model.beads import Discretisation
    from ..model.material import GLASS
    from ..scene.outputs import TrajectoryOutput

    s = read(Settings, settings, "fibre-tension")
    disc = Discretisation(spacing_ratio=s.spacing_ratio, mass_scaling=s.mass_scaling)
    return FibreTension(fibre=s.fibre(GLASS.name), length_m=s.length_m, discretisation=disc,
                        time_step=s.time_step, max_strain=s.max_strain,
                        speed_fraction=s.speed_fraction,
                        trajectory=TrajectoryOutput(frames=s.trajectory_frames))


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
