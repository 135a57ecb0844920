"""Errors fabmd raises at its boundary.

Every error a user can cause or meet is a :class:`FabmdError`; the command line
prints its message as one line. The subclasses say where it came from:

* :class:`InputError` — a description or parameter is wrong; raised when the
  object is built, before LAMMPS starts.
* :class:`EngineUnavailable` — the LAMMPS library cannot be loaded, or lacks a
  package or style fabmd needs.
* :class:`SimulationFailed` — LAMMPS stopped with an error; names the run folder
  and the LAMMPS error line.
* :class:`UnstableRun` — the run was stopped by fabmd's stability guard; names
  the likely cause and the remedy.
* :class:`OutputExists` — a results folder would be overwritten.

Warnings (Python ``warnings``, not errors): :class:`OverlapWarning` — beads of
different fibres (or a bead and a tool) overlapped more than the contact model's
stated limit; the results may be soft.
"""

from __future__ import annotations

from pathlib import Path


class FabmdError(Exception):
    """Base class of every error fabmd raises on purpose."""


class InputError(FabmdError, ValueError):
    """A parameter or description is not valid (raised before LAMMPS starts)."""


class EngineUnavailable(FabmdError, RuntimeError):
    """LAMMPS cannot be loaded or misses a package/style fabmd needs."""


class OutputExists(FabmdError, FileExistsError):
    """A results folder exists already and overwriting was not asked for."""


class SimulationFailed(FabmdError, RuntimeError):
    """LAMMPS stopped with an error.

    Attributes:
        run_dir: the run folder (input, log and partial outputs are kept there).
        lammps_error: the LAMMPS ``ERROR: ...`` line.
    """

    def __init__(self, message: str, run_dir: Path | None = None, lammps_error: str = ""):
        self.run_dir = Path(run_dir) if run_dir is not None else None
        self.lammps_error = lammps_error
        where = f" (run folder: {self.run_dir})" if self.run_dir is not None else ""
        super().__init__(f"{message}{where}")


class UnstableRun(SimulationFailed):
    """A run went numerically unstable and was stopped.

    Attributes:
        cause: short name of the detected symptom (``"kinetic_energy"``,
            ``"bond_stretch"``, ``"overlap"``, ``"nan"``, ``"lost_atoms"``).
        step: the time step at which it was caught, where known.
    """

    def __init__(self, message: str, run_dir: Path | None = None, lammps_error: str = "",
                 cause: str = "", step: int | None = None):
        self.cause = cause
        self.step = step
        super().__init__(message, run_dir=run_dir, lammps_error=lammps_error)


class OverlapWarning(UserWarning):
    """A run saw overlaps above ``ContactModel.overlap_warning`` (results may be too soft)."""


class QuasiStaticWarning(UserWarning):
    """A driven test was not quasi-static: inertia or drag carry a large part of its
    force (see the summary's ``quasi_static``); slow it down before using the curve."""


class RunInterrupted(FabmdError):
    """A run was stopped by SIGTERM or SIGINT after writing a checkpoint; ``--resume``
    (``resume=True``) continues it. The command line exits with :attr:`exit_code`.

    Attributes:
        run_dir: the folder whose checkpoint was written (None between stages).
        step: the time step of the checkpoint, where one was written.
    """

    exit_code = 5

    def __init__(self, message: str, run_dir: Path | None = None, step: int | None = None):
        self.run_dir = Path(run_dir) if run_dir is not None else None
        self.step = step
        super().__init__(message)
