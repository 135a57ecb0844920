"""Progress of long runs: step, % done and time left, on a terminal only."""

from __future__ import annotations

import sys
import time
from typing import TextIO


def _clock(seconds: float) -> str:
    seconds = int(max(0, seconds))
    h, rest = divmod(seconds, 3600)
    m, s = divmod(rest, 60)
    return f"{h:d}:{m:02d}:{s:02d}"


class Progress:
    """Callable ``(step, total)`` that redraws one status line on a terminal.

    Args:
        label: what is running (e.g. ``"tension"``).
        stream: where to write (default stderr).
        enabled: force on/off; default on only when ``stream`` is a terminal.
        min_interval_s: minimum time between redraws.
    """

    def __init__(self, label: str, stream: TextIO | None = None, enabled: bool | None = None,
                 min_interval_s: float = 0.5):
        self.label = label
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.min_interval_s = min_interval_s
        self._t0 = time.perf_counter()
        self._last = 0.0
        self._drawn = False

    def __call__(self, step: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if step < total and now - self._last < self.min_interval_s:
            return
        self._last = now
        frac = step / total if total else 1.0
        elapsed = now - self._t0
        left = elapsed * (1 - frac) / frac if frac > 0 else 0.0
        self.stream.write(f"\r{self.label}: step {step}/{total}  {100 * frac:5.1f} %  "
                          f"elapsed {_clock(elapsed)}  left {_clock(left)}   ")
        self._drawn = True
        if step >= total:
            self.stream.write("\n")
            self._drawn = False
        self.stream.flush()
