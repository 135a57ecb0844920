"""Output cadence as a small object: how often a protocol writes its trajectory.

A protocol holds a :class:`TrajectoryOutput` (``frames=0`` switches the
trajectory off) and asks it for the LAMMPS text of its outputs block and of the
final frame. After the run, :func:`fabmd.results.trajectory.finalise` turns the
LAMMPS dumps into ``trajectory.h5`` (H5MD) and ParaView files.
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import inputs
from ..errors import InputError
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


#: dump ids of the trajectory block (``undump`` them to close the files)
DUMP_IDS = ("fabmd_trajectory", "fabmd_bonds")


def trajectory_final(bond_forces: bool = True, close: bool = False) -> str:
    """After the last run: write the final step as the last frame (once).

    Args:
        close: then ``undump`` the trajectory (needed before a ``reset_timestep``,
            which LAMMPS refuses while a dump is active).
    """
    bond_every = ("dump_modify     fabmd_bonds every 1" if bond_forces
                  else "# no bond forces in this trajectory")
    ids = DUMP_IDS if bond_forces else DUMP_IDS[:1]
    close_text = ("\n".join(f"undump          {i}" for i in ids) if close
                  else "# the dumps stay open (LAMMPS closes them at the end)")
    return render("trajectory_final", bond_every=bond_every, close=close_text)


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

    def every(self, total_steps: int, multiple_of: int = 1) -> int:
        """Steps between frames for a run of ``total_steps`` steps.

        Args:
            multiple_of: round the interval up to a multiple of this (e.g. a driven
                test's output interval, so that frames fall on curve samples); an
                explicit ``every_steps`` is kept as it is.
        """
        if self.every_steps is not None:
            return self.every_steps
        raw = max(1, int(total_steps) // max(1, self.frames))
        m = max(1, int(multiple_of))
        return m * max(1, -(-raw // m))

    def commands(self, total_steps: int, multiple_of: int = 1) -> str:
        """The outputs-block text (a comment when disabled); see :meth:`every`."""
        if not self.enabled:
            return "# ---- output: no trajectory (trajectory.frames = 0)"
        return trajectory(self.every(total_steps, multiple_of), velocities=self.velocities,
                          bond_forces=self.bond_forces)

    def final_commands(self, close: bool = False) -> str:
        """Text to put after the last run of the trajectory, before ``finish`` (a comment
        when disabled). ``close``: also ``undump`` (before a ``reset_timestep``)."""
        if not self.enabled:
            return "# no trajectory: no final frame"
        return trajectory_final(self.bond_forces, close=close)


def check_trajectory(name: str, value) -> None:
    """Refuse anything but a :class:`TrajectoryOutput` for a protocol's ``trajectory``."""
    if not isinstance(value, TrajectoryOutput):
        raise InputError(f"{name} must be a TrajectoryOutput (e.g. TrajectoryOutput(frames=20); "
                         f"in a scene file a table [<protocol>.trajectory] frames = 20), "
                         f"got {value!r}")
