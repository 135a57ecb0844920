"""A cantilever in LAMMPS for the bending tests: a saved bead model, held at one end,
pushed across at its tip, relaxed by energy minimisation (seconds)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fabmd.model.bead_model import BeadModel


def tip_deflection(model: BeadModel, folder: Path, held: np.ndarray, tip: np.ndarray,
                   force_n: float, max_steps: int = 1_000_000,
                   force_tolerance_n: float = 1e-12) -> float:
    """Mean deflection [m] of the ``tip`` beads along −y under a total force ``force_n``
    shared by them, with the ``held`` beads fixed (no contact)."""
    from fabmd.engine.library import new_instance
    from fabmd.model.beads import model_critical_time_step_s
    from fabmd.scene import blocks

    model.save(folder, "model")
    lmp = new_instance(["-log", "none", "-screen", "none"])
    try:
        lmp.commands_string("\n".join([
            blocks.setup(model, "cantilever", str(folder / "model.data"),
                         0.5 * model_critical_time_step_s(model)),
            blocks.bonds(model),
            f"pair_style zero {float(model.diameters.max())}\npair_coeff * *",
            "group held id " + " ".join(str(i + 1) for i in held),
            "group tip id " + " ".join(str(i + 1) for i in tip),
            "fix hold held setforce 0 0 0",
            f"fix push tip addforce 0 {-float(force_n) / len(tip)!r} 0",
            "min_style fire",  # force-based: SI energies are too small for a line search
            f"minimize 0 {force_tolerance_n!r} {max_steps} {int(1.5 * max_steps)}",
        ]))
        pos = np.array(lmp.gather_atoms("x", 1, 3)).reshape(-1, 3)
    finally:
        lmp.close()
    return -float((pos[tip, 1] - model.positions[tip, 1]).mean())
