"""SIGTERM and SIGINT stop a run cleanly: a checkpoint first, then :class:`RunInterrupted`.

Schedulers send SIGTERM before they kill a job, Ctrl-C sends SIGINT. While
:func:`catching` is active, either signal only sets a flag; the in-process engine
looks at it at every chunk boundary (:func:`stop_requested`), writes a checkpoint
there and raises :class:`fabmd.errors.RunInterrupted`; the pipeline also looks
between stages. A second SIGINT while the first waits for its chunk raises
``KeyboardInterrupt`` at once (a user who insists). Under MPI the flag is summed
over all ranks, because a launcher may signal rank 0 only: every rank then stops at
the same chunk. Outside the main thread (where Python cannot install handlers)
nothing is caught.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading

from . import mpi

#: the signals that stop a run at its next chunk boundary
SIGNALS = (signal.SIGTERM, signal.SIGINT)

#: what a re-launched command's parent sends for a SIGTERM (see the module docstring)
FORWARDED_SIGTERM = signal.SIGUSR1
#: set in the ranks' environment of a re-launched command (fabmd.engine.relaunch)
RELAUNCHED_VARIABLE = "FABMD_RELAUNCHED"

_received: list[int] = []  # signal numbers received while catching
_depth = 0  # nesting of catching() (the pipeline around the engine's runs)


def _handler(signum, frame) -> None:
    if signum == signal.SIGINT and _received:
        raise KeyboardInterrupt  # second Ctrl-C: stop now, no checkpoint
    _received.append(signal.SIGTERM if signum == FORWARDED_SIGTERM else signum)


def _signals() -> tuple:
    """The signals caught: SIGTERM and SIGINT, and in a re-launched command SIGUSR1."""
    relaunched = os.environ.get(RELAUNCHED_VARIABLE) == "1"
    return SIGNALS + ((FORWARDED_SIGTERM,) if relaunched else ())


@contextlib.contextmanager
def catching():
    """Catch SIGTERM/SIGINT as a stop request while the block runs (nestable)."""
    global _depth
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = None
    if _depth == 0:
        _received.clear()
        old = {sig: signal.signal(sig, _handler) for sig in _signals()}
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1
        if old is not None:
            for sig, handler in old.items():
                signal.signal(sig, handler)
            _received.clear()


def received() -> str | None:
    """Name of the first stop signal this rank received (None: none)."""
    return signal.Signals(_received[0]).name if _received else None


def stop_requested() -> bool:
    """True on every rank when any rank received a stop signal (collective under MPI:
    call it on all ranks at the same point)."""
    return mpi.allreduce_sum([1.0 if _received else 0.0])[0] > 0


def signal_name() -> str:
    """The signal's name as rank 0 knows it (``"a stop signal"`` on ranks that got none)."""
    return received() or "a stop signal"
