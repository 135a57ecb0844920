"""Tiny LAMMPS runs of synthetic bead models (free motion with contact) for results tests."""

from __future__ import annotations

from pathlib import Path

from fabmd.engine import Engine
from fabmd.model.beads import bead_parameters
from fabmd.model.contact import ContactModel
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.common import DATA_FILE, run_folder, write_run_folder
from fabmd.results.trajectory import finalise
from fabmd.scene import blocks
from fabmd.scene.outputs import TrajectoryOutput
from fabmd.scene.templates import render

BOLTZMANN = 1.380649e-23  # J/K (LAMMPS units si)


def free_run(model, out: Path, steps: int = 200, trajectory: TrajectoryOutput | None = None,
             engine: Engine | None = None, kick_m_s: float = 0.5) -> Path:
    """Let ``model`` move for ``steps`` steps from a small random velocity; finalise."""
    trajectory = trajectory or TrajectoryOutput(frames=4)
    beads = [bead_parameters(VirtualFibre.solid(GLASS, float(model.diameters[0])))]
    contact = ContactModel()
    dt = 0.25 * min(b.critical_time_step_s(contact.normal_stiffness_n_per_m(beads))
                    for b in beads)
    temperature = float(model.masses.mean()) * kick_m_s**2 / BOLTZMANN
    text = "\n".join([
        blocks.setup(model, "free", DATA_FILE, dt),
        blocks.bonds(model),
        blocks.contact(model, contact, beads),
        "fix             integrate all nve",
        # a random thermal kick of about kick_m_s per bead ("loop geom": same on any ranks)
        f"velocity        all create {temperature:.6g} 4928 dist gaussian loop geom",
        blocks.guards(model, dt),
        trajectory.commands(steps),
        render("run", steps=steps),
        trajectory.final_commands(),
        render("finish", final_data="final.data"),
    ])
    run_dir = write_run_folder(out, "free", model, text, {})
    run_folder(engine or Engine(progress=False), run_dir, "free")
    finalise(run_dir, paraview=trajectory.paraview, model=model)
    return run_dir
