"""Steps done by a running ``lmp``, read from its growing log file.

The standalone back end cannot ask LAMMPS for its step, so it reads the log as LAMMPS
writes it (``lmp -nb``: unbuffered): a thermo header (first column ``Step``) opens a
run, its rows carry the step, and ``Loop time of ... for N steps`` closes the run.
Steps done = the steps of the closed runs + (last row − first row) of the open one.
"""

from __future__ import annotations

import re
from pathlib import Path

_HEADER = re.compile(r"^\s*Step\s")
_LOOP = re.compile(r"^Loop time of \S+ on \d+ procs for (\d+) steps")


class LogSteps:
    """Follows one log file; :meth:`read` returns the steps done so far."""

    def __init__(self, path: Path):
        self.path = Path(path)
        self.offset = 0
        self.pending = ""  # a line LAMMPS has not finished writing
        self.closed = 0  # steps of the runs that ended
        self.first: int | None = None  # first and last step of the open run's rows
        self.last: int | None = None
        self.in_run = False

    @property
    def done(self) -> int:
        open_run = self.last - self.first if self.in_run and self.first is not None else 0
        return self.closed + open_run

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
            self.closed += int(loop.group(1))
            self.in_run, self.first, self.last = False, None, None
        elif _HEADER.match(line):
            self.in_run, self.first, self.last = True, None, None
        elif self.in_run:
            token = line.split(maxsplit=1)[:1]
            if token and token[0].isdigit():  # a thermo row (not a WARNING line)
                step = int(token[0])
                self.first = step if self.first is None else self.first
                self.last = step
