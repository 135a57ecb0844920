"""How many MPI ranks a run gets: every usable core, unless the model is too small.

Splitting a model over ranks pays only when each rank keeps enough beads that its
share of the pair and bond work outweighs the exchange of ghost beads every step.
``MIN_BEADS_PER_RANK`` is set above that break-even, measured on the idle 2-core
development machine (``benchmarks/RESULTS.md`` "Ranks on an idle machine"): LAMMPS's loop
on 2 ranks ran 0.84x as fast as on one at 128 beads per rank and 1.24x at 256, and fabmd's
own runs ran 1.5-1.6x faster from 532 beads per rank (the example's periodic cell, 1,064
beads) up. More than two ranks have not been measured here.

The choice, in order of precedence: ``--np N`` (``requested``), the environment
variable ``FABMD_NP`` (CI and the test suite set ``FABMD_NP=1`` so that parallel test
workers do not oversubscribe the cores), else the usable cores of this process
(``os.sched_getaffinity``: what a batch scheduler or ``taskset`` grants, not the
machine's total) less those other jobs keep busy (:func:`free_cores`: the busy share of
the CPU time in ``/proc/stat`` over a fraction of a second, :func:`busy_cores`; the 1-minute
load average only where ``/proc/stat`` is missing, since it still counts a run that ended
a minute ago), limited by the model size. Busy cores count because MPI ranks wait for
each other by polling: on the 2-core development machine with a load of 11, 2 ranks ran
every coupon size 1.9-14x slower than one (``benchmarks/RESULTS.md`` "Ranks").
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from dataclasses import dataclass

from ..errors import InputError

#: environment variable that sets the ranks when ``--np`` is not given
ENV_VARIABLE = "FABMD_NP"
#: fewest beads per rank for which another rank pays (see the module docstring)
MIN_BEADS_PER_RANK = 500
#: how long :func:`busy_cores` watches the machine, s (long enough for 40 jiffies at
#: 100 Hz on two cores, short enough not to be noticed at start-up)
SAMPLE_WINDOW_S = 0.4
#: where the kernel counts CPU time (Linux)
PROC_STAT = "/proc/stat"


@dataclass(frozen=True)
class RankChoice:
    """A number of ranks and why (``reason``: one line for the terminal); ``measured``:
    decided from the machine and a known model size (not told, not a default)."""

    ranks: int
    reason: str
    measured: bool = False

    def line(self) -> str:
        """``fabmd: 2 MPI ranks (2 usable cores, 12,000 beads)``."""
        return f"fabmd: {self.ranks} MPI rank{'s' if self.ranks > 1 else ''} ({self.reason})"


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity; ``os.cpu_count()`` where the
    platform has no affinity)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def cpu_times(text: str) -> tuple[int, int]:
    """(busy, total) jiffies of the whole machine from the text of ``/proc/stat``.

    Its first line is ``cpu user nice system idle iowait irq softirq steal ...``; idle and
    iowait are idle, the rest (niced jobs too) busy. Guest time is already in user.
    """
    for line in text.splitlines():
        fields = line.split()
        if fields and fields[0] == "cpu":
            values = [int(v) for v in fields[1:9]]
            idle = sum(values[3:5])
            return sum(values) - idle, sum(values)
    raise ValueError("no 'cpu' line in /proc/stat")


def busy_cores(window_s: float = SAMPLE_WINDOW_S,
               read: Callable[[], str] | None = None,
               sleep: Callable[[float], None] = time.sleep) -> float | None:
    """Cores of the whole machine kept busy now, from two samples of ``/proc/stat``
    ``window_s`` seconds apart (this process sleeps meanwhile, so the busy time is other
    jobs'); None where ``/proc/stat`` cannot be read. ``read`` returns the file's text
    (tests inject samples)."""
    if read is None:
        def read() -> str:
            with open(PROC_STAT) as handle:
                return handle.read()
    try:
        busy0, total0 = cpu_times(read())
        sleep(window_s)
        busy1, total1 = cpu_times(read())
    except (OSError, ValueError):
        return None
    if total1 <= total0:
        return None
    return (busy1 - busy0) / (total1 - total0) * (os.cpu_count() or 1)


def free_cores(cores: int | None = None, load: float | None = None) -> int:
    """Usable cores that other jobs do not keep busy (at least 1).

    ``load`` (default: :func:`busy_cores`, else the 1-minute load average) counts busy
    cores on the whole machine; the part of it that cores outside this process's affinity
    could carry is not held against it. Where neither measure exists, every usable core.
    """
    cores = usable_cores() if cores is None else cores
    if load is None:
        load = busy_cores()
    if load is None:
        try:
            load = os.getloadavg()[0]
        except (AttributeError, OSError):
            return cores
    elsewhere = max(0, (os.cpu_count() or cores) - cores)
    busy = int(max(0.0, load - elsewhere) + 0.5)
    return max(1, cores - busy)


def _env_ranks() -> int | None:
    text = os.environ.get(ENV_VARIABLE, "").strip()
    if not text or text.lower() == "auto":
        return None
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise InputError(f"{ENV_VARIABLE} must be a whole number >= 1 or 'auto', got {text!r}")
    return value


def choose_ranks(beads: int | None | Callable[[], int | None], requested: int | None = None,
                 cores: int | None = None, load: float | None = None) -> RankChoice:
    """Ranks for a model of ``beads`` beads (None: size unknown before the run).

    Args:
        beads: the count, or a function that estimates it (called only when neither
            ``requested`` nor ``FABMD_NP`` decides).
        requested: ``--np`` (None: not given).
        cores: usable cores (default :func:`usable_cores`).
        load: busy cores of the machine (default: measured now; see
            :func:`free_cores`).

    Raises:
        InputError: ``requested`` or ``FABMD_NP`` is not a whole number >= 1.
    """
    if requested is not None:
        if requested < 1:
            raise InputError(f"--np must be a whole number >= 1, got {requested}")
        return RankChoice(requested, "--np")
    env = _env_ranks()
    if env is not None:
        return RankChoice(env, f"{ENV_VARIABLE}={env}")
    cores = usable_cores() if cores is None else cores
    if callable(beads):
        beads = beads()
    if beads is None:
        return RankChoice(1, "model size not known before the run; --np N to choose")
    free = free_cores(cores, load)
    by_size = max(1, beads // MIN_BEADS_PER_RANK)
    ranks = min(free, by_size)
    where = f"{cores} usable core{'s' if cores > 1 else ''}" + \
        (f", {cores - free} kept busy by other jobs" if free < cores else "") + \
        f", about {beads:,} beads"
    if by_size < free:
        return RankChoice(ranks, f"{where}: at least {MIN_BEADS_PER_RANK:,} beads per rank "
                                 f"pay for their communication", True)
    return RankChoice(ranks, where, True)
