"""Contact history across a restart: give the resumed pair style the fix ID it had.

Granular pair styles keep their contact history (tangential springs) in an
internal fix named after the pair's instance number, e.g. ``NEIGH_HISTORY_HH3``.
That number counts every pair style created in the *process* (a static counter
of LAMMPS), so a resumed run usually gets another one, and LAMMPS then ignores
the history in the restart file ("Unused restart file peratom fix info"): every
sticking contact would restart with an unloaded tangential spring.

Before ``read_restart`` the in-process engine therefore raises the counter to
the checkpoint's number by creating throw-away pair styles in a scratch LAMMPS
instance (:func:`align_pair_instances`; every run reads the counter that way first, so
no run's pair is instance 0 and a new process can always catch up). A counter
already past it (a resume in the same Python process after more runs) cannot go
back: the resume then warns that the contact history starts afresh.
"""

from __future__ import annotations

import re

from .library import new_instance

#: internal fixes that hold granular contact history, and the pair instance number
_HISTORY = re.compile(r"^NEIGH_HISTORY_([A-Z]+?)(\d+)$")
_DUMMY = re.compile(r"^NEIGH_HISTORY_HH_DUMMY(\d+)$")


def history_fixes(lmp) -> list[str]:
    """IDs of the contact-history fixes of a LAMMPS instance (after its first run)."""
    return [i for i in lmp.available_ids("fix") if _HISTORY.match(i)]


def pair_instance(fix_id: str) -> int | None:
    """The pair instance number in a contact-history fix ID (None: not one)."""
    m = _HISTORY.match(fix_id)
    return int(m.group(2)) if m else None


def align_pair_instances(target: int | None = None) -> bool:
    """Make the next pair style this process creates instance ``target``.

    The counter is read by creating a pair style, which uses one number: so every
    in-process run calls this first (``target=None``: only read it), and a run's pair
    is never instance 0 — a resume in a new process can always reach its number.
    Returns False when the counter is past ``target`` already (cannot go back).
    """
    lmp = new_instance()
    try:
        lmp.commands_string("atom_style sphere\nregion b block 0 1 0 1 0 1\ncreate_box 1 b\n"
                            "pair_style gran/hooke/history 1 1 1 1 0.3 1")
        found = [int(m.group(1)) for i in lmp.available_ids("fix") if (m := _DUMMY.match(i))]
        after = found[0] + 1  # the number the next pair style gets
        if target is None:
            return True
        if after > target:
            return False
        styles = ("zero 1.0", "gran/hooke/history 1 1 1 1 0.3 1")  # a new style, a new pair
        for k in range(target - after):
            lmp.command(f"pair_style {styles[k % 2]}")
        return True
    finally:
        lmp.close()
