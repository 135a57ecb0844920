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
* :class:`NotQuasiStatic` — under ``--strict``, a test whose curve is not quasi-static.
* :class:`CalibrationNotReached` — a calibration ran but missed a target (exit 3).
* :class:`RunInterrupted` — a run stopped by a signal after writing its checkpoint.

Each class carries the exit status of the ``fabmd`` command as ``exit_code``
(:data:`EXIT_CODES`): 0 ok, 1 unexpected internal error (a bug), 2 input or usage
error, 3 simulation failed or unstable, 4 not quasi-static under ``--strict``,
5 interrupted (checkpoint written).

Warnings (Python ``warnings``, not errors): :class:`OverlapWarning` — beads of
different fibres (or a bead and a tool) overlapped more than the contact model's
stated limit; the results may be soft.
"""

from __future__ import annotations

from pathlib import Path

#: exit status of the ``fabmd`` command -> what it means (README, ``fabmd --help``)
EXIT_CODES = {
    0: "ok",
    1: "unexpected internal error (a bug: please report it with --traceback)",
    2: "input or usage error (nothing was run)",
    3: "simulation failed or went unstable, or a calibration did not reach its targets",
    4: "not quasi-static, under --strict",
    5: "interrupted (a checkpoint was written; continue with --resume)",
}


class FabmdError(Exception):
    """Base class of every error fabmd raises on purpose."""

    exit_code = 2


class InputError(FabmdError, ValueError):
    """A parameter or description is not valid (raised before LAMMPS starts)."""

    exit_code = 2


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

    exit_code = 3

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


class NotQuasiStatic(FabmdError):
    """Under ``--strict``: the test ran, but its curve is not quasi-static (the summary's
    ``quasi_static`` names the measures that failed)."""

    exit_code = 4


class CalibrationNotReached(FabmdError):
    """``fabmd calibrate`` ran, but a target was not reached (the message says which, the
    range tried, the best value and why; ``calibration.json`` records every run); or a
    crimp's ``target_tension`` cannot be reached by its family's expansion (the crimp
    folder's ``summary.json`` → ``tension_search`` records every run).

    Attributes:
        run_dir: the calibration folder.
    """

    exit_code = 3

    def __init__(self, message: str, run_dir: Path | None = None):
        self.run_dir = Path(run_dir) if run_dir is not None else None
        super().__init__(message)


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
