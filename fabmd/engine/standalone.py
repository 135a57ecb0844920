"""Standalone back end: ``mpirun -np N lmp -in in.<protocol>`` in the run folder.

This is exactly what a user runs on a cluster after copying the folder; fabmd
writes ``run.sh`` with the command beside the input.
"""

from __future__ import annotations

import subprocess
from collections.abc import Callable
from pathlib import Path

from .diagnosis import to_exception
from .library import engine_environment, lmp_executable, mpirun_executable
from .log_progress import LogSteps, planned_runs
from .script import logical_lines

#: seconds between two looks at the output of a running ``lmp`` (progress)
POLL_S = 0.5


def command_line(input_name: str, ranks: int = 1, threads: int = 1,
                 lmp: str | Path | None = None, mpirun: str | Path | None = None) -> list[str]:
    """The command that runs ``input_name`` in its folder."""
    cmd = [str(mpirun or mpirun_executable()), "-np", str(ranks)] if ranks > 1 else []
    cmd += [str(lmp or lmp_executable()), "-in", input_name, "-log", "log.lammps", "-nocite"]
    if threads > 1:
        cmd += ["-sf", "omp", "-pk", "omp", str(threads)]
    return cmd


def run_standalone(run_dir: Path, input_name: str, *, ranks: int = 1, threads: int = 1,
                   progress: Callable[[int, int], None] | None = None) -> None:
    """Run the input with the ``lmp`` executable of this install.

    Screen output goes to ``run_dir/screen.log``. ``progress(step, total)`` (e.g. a
    :class:`fabmd.progress.Progress`) is called every :data:`POLL_S` seconds with the
    steps LAMMPS has written there (``lmp -nb`` leaves the screen output unbuffered; the
    log file stays buffered) and once at the end.

    Raises:
        SimulationFailed / UnstableRun: ``lmp`` exited with an error.
    """
    run_dir = Path(run_dir)
    env = engine_environment()
    env["OMP_NUM_THREADS"] = str(threads)
    screen = run_dir / "screen.log"
    cmd = command_line(input_name, ranks, threads)
    with open(screen, "w") as out:
        if progress is None:
            returncode = subprocess.run(cmd, cwd=run_dir, env=env, stdout=out,
                                        stderr=subprocess.STDOUT, check=False).returncode
        else:
            planned = planned_runs(logical_lines((run_dir / input_name).read_text()))
            proc = subprocess.Popen(cmd + ["-nb"], cwd=run_dir, env=env, stdout=out,
                                    stderr=subprocess.STDOUT)
            returncode = follow(proc, LogSteps(screen), planned, progress)
    text = screen.read_text(errors="replace")
    if returncode != 0 or "ERROR" in text:
        raise to_exception(text, run_dir)


def follow(proc, log: LogSteps, planned: list[int], progress: Callable[[int, int], None],
           poll_s: float = POLL_S) -> int:
    """Wait for ``proc``, calling ``progress(steps done, steps in all)`` from its output
    meanwhile (``planned``: the steps of the input's runs; :meth:`LogSteps.total`), at a
    clean end once more with the steps it ran. Returns the exit status; stops ``proc``
    when this Python is interrupted."""
    shown = 0
    try:
        while True:
            try:
                returncode = proc.wait(timeout=poll_s)
                break
            except subprocess.TimeoutExpired:
                done = log.read()
                if done > shown:  # from the first logged steps on: the speed leaves set-up out
                    progress(done, max(done, log.total(planned)))
                    shown = done
    except BaseException:
        proc.terminate()
        proc.wait()
        raise
    if returncode == 0:
        done = log.read()
        progress(done, done)
    return returncode
