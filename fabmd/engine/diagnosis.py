"""Turn a LAMMPS error into a fabmd exception that names cause and remedy.

fabmd's inputs carry stability guards (``fix guard_<cause> all halt ...``, see
``lammps_templates/guards.lmp``); LAMMPS stops with "Fix halt condition for
fix-id guard_<cause> met on step N". Other LAMMPS messages that mean a run blew
up (lost atoms, missing bond atoms, non-numeric coordinates) are recognised too.
"""

from __future__ import annotations

import re
from pathlib import Path

from ..errors import SimulationFailed, UnstableRun

#: cause -> (what happened, likely cause and remedy)
CAUSES: dict[str, tuple[str, str]] = {
    "speed": ("bead speed ran away (kinetic-energy blow-up)",
              "the time step is too large for the stiffest spring or the loading is too "
              "abrupt; lower time_step.factor (e.g. halve it), raise mass_scaling, or load "
              "more slowly"),
    "nan": ("a bead position or velocity became NaN",
            "the integration diverged; lower time_step.factor or the contact stiffness"),
    "bond_stretch": ("a bond stretched beyond the runaway limit",
                     "the loading outruns the fibres (too fast) or the time step is too large; "
                     "lower the loading speed or time_step.factor"),
    "overlap": ("two beads of different fibres overlap beyond the limit",
                "the contact stiffness is too low for the loads (raise "
                "contact.normal_stiffness_pa) or fibres are pushed through each other too fast"),
    "lost_atoms": ("atoms were lost (left the box or a bond partner went missing)",
                   "the run went unstable; lower time_step.factor or the loading speed"),
    "runaway_atom": ("a bead flew far away (the box or the neighbour lists blew up)",
                     "the run went unstable between two guard checks; lower "
                     "time_step.factor or the loading speed"),
}

#: LAMMPS messages that mean an atom ran away, whatever check caught it first
_RUNAWAY = ("too many neighbor bins", "out of range atoms", "neighbor list overflow",
            "bond/angle/dihedral extent > half of periodic box length")

_HALT = re.compile(r"fix-id guard_(\w+) met on step (\d+)")
_STEP = re.compile(r"\b(?:at|on) step (\d+)")
_ERROR = re.compile(r"ERROR(?: on proc \d+)?: (.*)")


def lammps_error_line(text: str) -> str:
    """The first ``ERROR: ...`` line in ``text`` (or its first line)."""
    for line in text.splitlines():
        m = _ERROR.search(line)
        if m:
            return "ERROR: " + m.group(1).strip()
    return text.strip().splitlines()[0] if text.strip() else "unknown LAMMPS error"


def to_exception(text: str, run_dir: Path | None) -> SimulationFailed:
    """Map a LAMMPS error message to :class:`UnstableRun` or :class:`SimulationFailed`."""
    line = lammps_error_line(text)
    m = _HALT.search(text)
    if m:
        cause, step = m.group(1), int(m.group(2))
        what, remedy = CAUSES.get(cause, (f"guard {cause} tripped", "see the log"))
        return UnstableRun(f"unstable run stopped at step {step}: {what}. Likely cause and "
                           f"fix: {remedy}", run_dir=run_dir, lammps_error=line, cause=cause,
                           step=step)
    lowered = line.lower()
    at = _STEP.search(line)
    step = int(at.group(1)) if at else None
    if "lost atoms" in lowered or "bond atoms" in lowered and "missing" in lowered:
        what, remedy = CAUSES["lost_atoms"]
        where = f" at step {step}" if step is not None else ""
        return UnstableRun(f"unstable run{where}: {what}. Likely cause and fix: {remedy}",
                           run_dir=run_dir, lammps_error=line, cause="lost_atoms", step=step)
    if any(m in lowered for m in _RUNAWAY):
        what, remedy = CAUSES["runaway_atom"]
        return UnstableRun(f"unstable run: {what}. Likely cause and fix: {remedy}",
                           run_dir=run_dir, lammps_error=line, cause="runaway_atom")
    if "non-numeric" in lowered or "nan" in lowered.split():
        what, remedy = CAUSES["nan"]
        return UnstableRun(f"unstable run: {what}. Likely cause and fix: {remedy}",
                           run_dir=run_dir, lammps_error=line, cause="nan")
    return SimulationFailed(f"LAMMPS stopped: {line}", run_dir=run_dir, lammps_error=line)
