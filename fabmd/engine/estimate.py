"""What a stage will cost, said before it starts: bead count, steps and a rough time.

The time is a rough guide, not a promise: ``SECONDS_PER_BEAD_STEP`` is the cost of
one bead for one step of a whole fabmd input (contact, bonds, drag, boundary motion,
interval means, guards) on one core of the 2-core development machine, divided by the
MPI ranks. Measured (benchmarks/RESULTS.md "Per-step cost of fabmd's fixes", CPU time
of ``lmp -in`` on one rank, machine loaded by other jobs): 3.1e-7 s for the 3D
fabric's tension, 3.3e-7 s for the demo's tension and 4.4e-7 s for its picture frame
(before the cheap drag and sums of issue 20: 4.7e-7, 5.1e-7, 7.4e-7 s; the bare
contact and bonds 1.4e-7 to 2.3e-7 s). Relaxations that stop once quasi-static usually
end well before their step budget, so the steps and time are upper bounds.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from .script import logical_lines, total_run_steps

#: seconds per bead and step on one core (see the module docstring)
SECONDS_PER_BEAD_STEP = 3.5e-7
_READ_DATA = re.compile(r"^read_data\s+(\S+)")
_ATOMS = re.compile(r"^\s*(\d+)\s+atoms\s*$")


def data_file_atoms(path: Path) -> int | None:
    """The atom count in a LAMMPS data file's header (None: not found)."""
    try:
        with open(path, errors="replace") as f:
            for k, line in enumerate(f):
                m = _ATOMS.match(line)
                if m:
                    return int(m.group(1))
                if k > 50:
                    break
    except OSError:
        return None
    return None


def _clock(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.2g} s"
    if seconds < 3600:
        return f"{seconds / 60:.2g} min"
    return f"{seconds / 3600:.2g} h"


def _beads(run_dir: Path, commands: list[str]) -> int | None:
    for c in commands:
        m = _READ_DATA.match(c)
        if m:
            return data_file_atoms(Path(run_dir) / m.group(1))
    return None


def input_beads(run_dir: Path, input_name: str) -> int | None:
    """Beads of the data file the input reads (None: it reads none, or no count)."""
    return _beads(run_dir, logical_lines((Path(run_dir) / input_name).read_text()))


def stage_header(run_dir: Path, input_name: str, label: str, ranks: int = 1) -> str:
    """``tension: 4,096 beads, up to 120,000 steps, rough cost up to 1.2 min on 1 rank``."""
    commands = logical_lines((Path(run_dir) / input_name).read_text())
    steps = total_run_steps(commands)
    beads = _beads(run_dir, commands)
    if beads is None:
        return f"{label}: up to {steps:,} steps"
    cost = SECONDS_PER_BEAD_STEP * beads * steps / max(1, ranks)
    # a halt that lets the input go on ends a run at its target (guards stop hard)
    halts = [c for c in commands if c.split()[:1] == ["fix"] and " halt " in f" {c} "
             and "error continue" in c]
    early = (" (a relaxation stops once quasi-static: usually sooner)"
             if any("quasi_static" in c for c in halts) else
             " (a run stops at its target: usually sooner)" if halts else "")
    estimate = _planned_estimate(run_dir)  # a plan's own estimate, where it has one
    if estimate and estimate < steps:
        early += (f"; estimated {estimate:,} steps, about "
                  f"{_clock(SECONDS_PER_BEAD_STEP * beads * estimate / max(1, ranks))}")
    return (f"{label}: {beads:,} beads, up to {steps:,} steps; rough cost up to "
            f"{_clock(cost)} on {ranks} rank{'s' if ranks > 1 else ''}" + early)


def _planned_estimate(run_dir: Path) -> int | None:
    """``estimated_steps`` of the run folder's ``plan.json`` (the compaction's: its
    input's runs are bounds at the step limit, halted at the target), None without."""
    path = Path(run_dir) / "plan.json"
    try:
        value = json.loads(path.read_text()).get("extra", {}).get("estimated_steps")
    except (OSError, ValueError, AttributeError):
        return None
    return int(value) if isinstance(value, (int, float)) and value > 0 else None
