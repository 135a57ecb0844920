"""Steps done by a running ``lmp``, read from its growing screen output.

The standalone back end cannot ask LAMMPS for its step, so it reads LAMMPS's output as
it is written (the screen output of ``lmp -nb``, unbuffered; the log file stays buffered
even then): a thermo header (first column ``Step``) opens a run, its rows carry the
step, and ``Loop time of ... for N steps`` closes the run. Steps done = the steps of the
closed runs + (last row − first row) of the open one; steps in all = the steps of the
closed runs + those the input plans for the runs after them (a run a ``fix halt`` ended
early counts what it ran, as in the in-process back end).
"""

from __future__ import annotations

import re
from pathlib import Path

_HEADER = re.compile(r"^\s*Step\s")
_RUN = re.compile(r"^run\s+(\d+)")
_LOOP = re.compile(r"^Loop time of \S+ on \d+ procs for (\d+) steps")


class LogSteps:
    """Follows one LAMMPS output file; :meth:`read` returns the steps done so far."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.offset = 0
        self.pending = ""  # a line LAMMPS has not finished writing
        self.closed: list[int] = []  # steps of the runs that ended
        self.first: int | None = None  # first and last step of the open run's rows
        self.last: int | None = None
        self.in_run = False

    @property
    def done(self) -> int:
        open_run = self.last - self.first if self.in_run and self.first is not None else 0
        return sum(self.closed) + open_run

    def total(self, planned: list[int]) -> int:
        """Steps in all: the closed runs' steps + ``planned`` of the runs after them."""
        return sum(self.closed) + sum(planned[len(self.closed):])

    def feed(self, text: str) -> int:
        """Take more of the log's text; return the steps done."""
        lines = (self.pending + text).split("\n")
        self.pending = lines.pop()
        for line in lines:
            self._line(line)
        return self.done

    def read(self) -> int:
        """Read what LAMMPS wrote since the last call; return the steps done."""
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                chunk = f.read()
        except OSError:  # not written yet
            return self.done
        self.offset += len(chunk)
        return self.feed(chunk.decode(errors="replace"))

    def _line(self, line: str) -> None:
        loop = _LOOP.match(line)
        if loop:
            self.closed.append(int(loop.group(1)))
            self.in_run, self.first, self.last = False, None, None
        elif _HEADER.match(line):
            self.in_run, self.first, self.last = True, None, None
        elif self.in_run:
            token = line.split(maxsplit=1)[:1]
            if token and token[0].isdigit():  # a thermo row (not a WARNING line)
                step = int(token[0])
                self.first = step if self.first is None else self.first
                self.last = step


def planned_runs(commands: list[str]) -> list[int]:
    """Steps of every ``run`` command of an input, in order (with options too: each prints
    its ``Loop time`` line)."""
    return [int(m.group(1)) for m in map(_RUN.match, commands) if m]
