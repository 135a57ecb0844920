"""Run the ``fabmd`` command again under the install's ``mpirun``, on more ranks.

The in-process engine runs on the ranks of the ``mpirun`` that started Python, so a
command started plainly (``fabmd demo``) that should use several cores starts itself
again as ``mpirun -np N python -m fabmd <same arguments>`` and waits for it. What the
user sees is the same: the ranks print on rank 0 only, the exit status is passed
through (an interrupted run: 5), and a stop signal reaches every rank once.

Signals: MPICH's ``mpiexec`` passes SIGINT and SIGUSR1 on to every rank but dies on
SIGTERM without telling them; so the child runs in its own session (a Ctrl-C at the
terminal reaches this process only, once), a SIGINT received here is sent on as
SIGINT and a SIGTERM as SIGUSR1, which the ranks take for the SIGTERM it was
(:mod:`fabmd.engine.interrupt`): each rank then writes its part of a checkpoint at the
next chunk boundary and stops with exit status 5; ``--resume`` continues as after any
interruption. A second SIGINT makes ``mpiexec`` abort at once, as a second Ctrl-C
does elsewhere.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys

from .interrupt import FORWARDED_SIGTERM, RELAUNCHED_VARIABLE
from .library import engine_environment, mpirun_executable

#: set in the ranks' environment when the progress line should be drawn although
#: ``mpiexec`` hands rank 0 a pipe instead of the terminal
TTY_VARIABLE = "FABMD_TTY"


def command_line(argv: list[str], ranks: int) -> list[str]:
    """``mpirun -np ranks python -m fabmd argv...``."""
    return [str(mpirun_executable()), "-np", str(ranks), sys.executable, "-m", "fabmd",
            *argv]


def relaunch_environment(ranks: int, threads: int = 1) -> dict[str, str]:
    """The ranks' environment: libmpi on the loader path, the ranks fixed (``FABMD_NP``),
    one OpenMP thread per rank unless asked, the terminal flag for the progress line."""
    from .ranks import ENV_VARIABLE

    env = engine_environment()
    env[ENV_VARIABLE] = str(ranks)
    env.setdefault("OMP_NUM_THREADS", str(threads))
    env[RELAUNCHED_VARIABLE] = "1"  # never again, even where the launcher sets no size
    if sys.stderr.isatty():
        env[TTY_VARIABLE] = "1"
    return env


def run_under_mpirun(argv: list[str], ranks: int, threads: int = 1) -> int:
    """Run ``fabmd argv`` on ``ranks`` ranks; return its exit status.

    Raises:
        EngineUnavailable: this install has no ``mpirun``.
    """
    cmd = command_line(argv, ranks)
    proc = subprocess.Popen(cmd, env=relaunch_environment(ranks, threads),
                            stdin=subprocess.DEVNULL, start_new_session=True)

    def forward(signum, frame) -> None:
        # mpiexec passes SIGINT and SIGUSR1 on to the ranks (SIGTERM would kill it alone)
        if proc.poll() is None:
            proc.send_signal(FORWARDED_SIGTERM if signum == signal.SIGTERM else signal.SIGINT)

    old = {sig: signal.signal(sig, forward) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        code = proc.wait()  # a signal runs forward() and the wait goes on (PEP 475)
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
    # mpiexec itself killed by a signal: the shell's convention (128 + signal number)
    return 128 - code if code < 0 else code


def under_mpirun() -> bool:
    """True when this process is already one of several MPI ranks."""
    from .mpi import launched_by_mpirun

    return launched_by_mpirun() or os.environ.get(RELAUNCHED_VARIABLE) == "1"
