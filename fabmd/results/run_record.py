"""How a run ended, read from LAMMPS's own record (``log.lammps``), not from the last
periodic history sample.

LAMMPS prints a thermo line at the last step of every run (and of every chunk the
in-process back end sends) and, when a ``fix halt ... message yes`` fires, the line
``Fix halt condition for fix-id ID met on step N with value V``. A relaxation that
stopped because it was quasi-static therefore ends at the step of its ``settled``
halt, which may lie between two history samples.
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass, field
from pathlib import Path

#: the halt fix of a relaxation that stops once quasi-static (fabmd.scene.quasi_static)
SETTLED_FIX = "settled"
#: log files of one run folder, oldest first (a resumed run writes the second)
LOG_FILES = ("log.lammps", "log.resume.lammps")

_HALT = re.compile(r"^Fix halt condition for fix-id (\S+) met on step (\d+)")


@dataclass(frozen=True)
class RunEnd:
    """How a run ended.

    Attributes:
        final_step: the time step LAMMPS stopped at (last thermo line of the log).
        stopped_by: ``"quasi-static"`` (the ``settled`` halt fired), ``"halted"``
            (another ``fix halt`` fired), ``"budget"`` (a relaxation ran out of its step
            budget without settling) or ``"completed"`` (all runs ran their steps).
        halts: ``[fix id, step]`` of every halt that fired, in order.
        final_thermo: the last thermo line, column name → value (LAMMPS's names).
    """

    final_step: int
    stopped_by: str
    halts: list = field(default_factory=list)
    final_thermo: dict = field(default_factory=dict)

    @property
    def quasi_static(self) -> bool:
        return self.stopped_by == "quasi-static"

    def as_dict(self) -> dict:
        return asdict(self)

    def sentence(self) -> str:
        """One line for the terminal, e.g. ``stopped at step 3,000: quasi-static``."""
        why = {"quasi-static": "quasi-static (criterion met)",
               "halted": f"halted by fix {self.halts[-1][0] if self.halts else '?'}",
               "budget": "step budget spent before quasi-static",
               "completed": "all steps run"}[self.stopped_by]
        return f"stopped at step {self.final_step:,}: {why}"


def _lines(run_dir: Path):
    for name in LOG_FILES:
        path = Path(run_dir) / name
        if path.is_file():
            with path.open(errors="replace") as f:
                yield from f


def read_run_end(run_dir: Path, relaxation: bool = False) -> RunEnd | None:
    """How the run in ``run_dir`` ended (None: no log with a thermo line).

    Args:
        relaxation: the last run is a relaxation that stops with the ``settled`` halt;
            ending it without that halt means its budget was spent (a relaxation's
            damped run halts first, :func:`fabmd.scene.blocks.relax`).
    """
    halts: list[list] = []
    header: list[str] | None = None
    last: dict | None = None
    for line in _lines(run_dir):
        m = _HALT.match(line)
        if m:
            halts.append([m.group(1), int(m.group(2))])
            continue
        words = line.split()
        if not words:
            continue
        if words[0] == "Step":
            header = words
            continue
        if header is None:
            continue
        if len(words) == len(header):
            try:
                values = [float(w) for w in words]
            except ValueError:
                header = None  # the thermo block ended
                continue
            last = dict(zip(header, values, strict=True))
        else:
            header = None
    if last is None:
        return None
    step = int(last["Step"])
    if halts:
        step = max(step, halts[-1][1])
    if halts and halts[-1][0] == SETTLED_FIX:
        reason = "quasi-static"
    elif relaxation:  # a halt of its own earlier run (the damped one) does not end it
        reason = "budget"
    elif halts:  # the last halt ended the run
        reason = "halted"
    else:
        reason = "completed"
    return RunEnd(step, reason, halts, last)
