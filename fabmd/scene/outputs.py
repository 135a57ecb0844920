"""Output cadence as a small object: how often a protocol writes its trajectory.

A protocol holds a :class:`TrajectoryOutput` (``frames=0`` switches the
trajectory off) and asks it for the LAMMPS text of its outputs block and of the
final frame. After the run, :func:`fabmd.results.trajectory.finalise` turns the
LAMMPS dumps into ``trajectory.h5`` (H5MD) and ParaView files.
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import inputs
from .templates import render

#: binary LAMMPS dump of the beads (id mol type xu yu zu [vx vy vz]), sorted by id
DUMP_FILE = "trajectory.bin"
#: text LAMMPS ``dump local`` of the bonds (batom1 batom2 force)
BOND_DUMP_FILE = "bonds.dump"


def trajectory(every: int, *, velocities: bool = False, bond_forces: bool = True,
               dump_file: str = DUMP_FILE, bond_file: str = BOND_DUMP_FILE) -> str:
    """Outputs block: dump beads (and bond forces) every ``every`` steps.

    Args:
        every: steps between frames (>= 1).
        velocities: also write bead velocities.
        bond_forces: also write the axial force of every bond.
    """
    every = inputs.positive_int("trajectory.every", every)
    bond_dump = (render("trajectory_bonds", every=every, bond_file=bond_file) if bond_forces
                 else "# no bond forces in this trajectory")
    return render("trajectory_dump", every=every, dump_file=dump_file,
                  velocity_columns=" vx vy vz" if velocities else "", bond_dump=bond_dump)


def trajectory_final(bond_forces: bool = True) -> str:
    """After the last run: write the final step as the last frame (once)."""
    bond_every = ("dump_modify     fabmd_bonds every 1" if bond_forces
                  else "# no bond forces in this trajectory")
    return render("trajectory_final", bond_every=bond_every)


@dataclass(frozen=True)
class TrajectoryOutput:
    """How a protocol writes its trajectory.

    Args:
        frames: about how many frames over the run (>= 0; 0 writes no trajectory).
            The first and the last step are always frames. For a run that may stop
            early (a quasi-static criterion), :meth:`every` is asked with the steps
            the protocol expects, or ``every_steps`` is given.
        every_steps: steps between frames; overrides ``frames`` when given (>= 1).
        velocities: store bead velocities [m/s].
        bond_forces: store the axial force [N] of every bond.
        paraview: write ParaView files (``trajectory.pvd`` + ``paraview/*.vtu``)
            beside ``trajectory.h5``.
    """

    frames: int = 50
    every_steps: int | None = None
    velocities: bool = False
    bond_forces: bool = True
    paraview: bool = True

    def __post_init__(self):
        object.__setattr__(self, "frames",
                           inputs.positive_int("trajectory.frames", self.frames, minimum=0))
        if self.every_steps is not None:
            object.__setattr__(self, "every_steps",
                               inputs.positive_int("trajectory.every_steps", self.every_steps))

    @property
    def enabled(self) -> bool:
        return self.every_steps is not None or self.frames > 0

    def every(self, total_steps: int) -> int:
        """Steps between frames for a run of ``total_steps`` steps."""
        if self.every_steps is not None:
            return self.every_steps
        return max(1, int(total_steps) // max(1, self.frames))

    def commands(self, total_steps: int) -> str:
        """The outputs-block text (a comment when disabled)."""
        if not self.enabled:
            return "# ---- output: no trajectory (trajectory.frames = 0)"
        return trajectory(self.every(total_steps), velocities=self.velocities,
                          bond_forces=self.bond_forces)

    def final_commands(self) -> str:
        """Text to put after the last run, before ``finish`` (empty when disabled)."""
        if not self.enabled:
            return "# no trajectory: no final frame"
        return trajectory_final(self.bond_forces)
