"""Progress of long runs: step, % done, ranks, steps per second and time left, on a
terminal only."""

from __future__ import annotations

import os
import sys
import time
from typing import TextIO


def _clock(seconds: float) -> str:
    seconds = int(max(0, seconds))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h:d}:{m:02d}:{s:02d}"


class Progress:
    """Callable ``(step, total)`` that redraws one status line on a terminal::

        tension: step 24000/120000  20.0 %  2 ranks  1,850 steps/s  elapsed 0:00:13  left 0:00:52

    The speed is measured from the first call on (so a resumed run, which starts at its
    checkpoint's step, shows its own speed; none is shown before the second call, except
    on the last line of a stage that ended before a speed was measured: the steps over
    the time since the line was made); the time left is the steps left at that speed. The last
    line is drawn once, however often the end is reported.

    Args:
        label: what is running (e.g. ``"tension"``).
        stream: where to write (default stderr).
        enabled: force on/off; default on only when ``stream`` is a terminal (or
            ``FABMD_TTY=1``: a command re-launched under ``mpirun``, whose rank 0
            writes to a pipe that ``mpirun`` copies to the terminal).
        min_interval_s: minimum time between redraws.
        ranks: MPI ranks the run uses (shown).
    """

    def __init__(self, label: str, stream: TextIO | None = None, enabled: bool | None = None,
                 min_interval_s: float = 0.5, ranks: int = 1):
        self.label = label
        self.stream = stream or sys.stderr
        if enabled is None:
            enabled = self.stream.isatty() or os.environ.get("FABMD_TTY") == "1"
        self.enabled = enabled
        self.min_interval_s = min_interval_s
        self.ranks = ranks
        self._t0 = time.perf_counter()
        self._first: tuple[float, int] | None = None  # (time, step) of the first call
        self._last = 0.0
        self._drawn = False
        self._ended: tuple[int, int] | None = None  # (step, total) of the last line drawn

    def rate(self, step: int, now: float) -> float:
        """Steps per second since the first call (0 before any step was timed)."""
        if self._first is None or now <= self._first[0] or step <= self._first[1]:
            return 0.0
        return (step - self._first[1]) / (now - self._first[0])

    def __call__(self, step: int, total: int) -> None:
        if not self.enabled or self._ended == (step, total):
            return
        now = time.perf_counter()
        rate = self.rate(step, now)
        if self._first is None:
            self._first = (now, step)
        if rate == 0 and step >= total and now > self._t0:  # ended before a speed: the mean
            rate = step / (now - self._t0)
        if step < total and now - self._last < self.min_interval_s:
            return
        self._last = now
        frac = step / total if total else 1.0
        elapsed = now - self._t0
        left = _clock((total - step) / rate) if rate > 0 else "-:--:--"
        ranks = f"{self.ranks} rank{'s' if self.ranks > 1 else ''}"
        self.stream.write(f"\r{self.label}: step {step}/{total}  {100 * frac:5.1f} %  {ranks}"
                          f"  {rate:,.0f} steps/s  elapsed {_clock(elapsed)}  "
                          f"left {left}   ")
        self._drawn = True
        if step >= total:
            self.stream.write("\n")
            self._drawn = False
            self._ended = (step, total)
        self.stream.flush()
