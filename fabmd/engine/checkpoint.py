"""Checkpoints of in-process runs, and the script that resumes from one.

Every ``every_steps`` steps, and when SIGTERM/SIGINT arrived (at a chunk boundary),
the in-process engine writes ``checkpoint.restart`` (LAMMPS ``write_restart``: atoms,
bonds, box, groups, time step and clock, and the state of fixes that keep one — clamp
origins, contact history) and ``checkpoint.json`` (which command of the input was
running, where its run started, the Python monitors' samples and the contact-history
fix IDs, see :mod:`fabmd.engine.history`). A checkpoint written after a run's last
chunk (or a run a ``fix halt`` ended) points at the command after it.

Resuming replays the input in order with these rules: commands that *define*
settings (styles, coefficients, variables, computes, fixes, regions, outputs)
are replayed; commands that *change the state* the restart file already holds
(``read_data`` → ``read_restart``, ``group``, ``velocity``, ``reset_timestep``,
finished ``run`` commands, ...) are skipped; output fixes append to their files,
which are first cut back to the checkpoint; the files of dumps still open at the
checkpoint (the trajectory) are cut back to their frames before the checkpoint
step and set aside (``<file>.before-resume``: LAMMPS cannot append to a binary
dump), the resumed run writes them afresh from the checkpoint step (the frame at
that step again if it falls on the dump's interval) and :func:`join_dump_parts`
puts the two together when it ends, so every frame is there once; the interrupted
``run`` continues with the same ``start``/``stop`` so ramps pick up exactly where
they were. A variable defined with an immediate value (``variable t equal $(time)``) is
replayed with the value it got in the interrupted run (``frozen_variables``), not what
``$(...)`` gives at the checkpoint; so is an ``internal`` variable (a ``fix controller``
integrates one step by step: the adaptive boundary's or the compaction platen's travel,
its pace), which the restart file does not hold.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass
from pathlib import Path

from .script import plain_run_steps

RESTART = "checkpoint.restart"
STATE = "checkpoint.json"

#: commands whose effect before the checkpoint the restart file already holds
STATE_COMMANDS = {
    "units", "atom_style", "boundary", "newton", "dimension", "lattice", "create_box",
    "create_atoms", "group", "velocity", "set", "displace_atoms", "reset_timestep",
    "change_box", "delete_atoms", "delete_bonds", "create_bonds", "write_data",
    "write_restart", "read_restart", "mass", "run", "minimize",
}
_FILE_KEYWORD = re.compile(r"\b(file)\s+(\S+)")
#: ``variable NAME equal ...$(...)...``: a value fixed when the command ran
_IMMEDIATE_VARIABLE = re.compile(r"^variable\s+(\S+)\s+equal\s+.*\$\(")
#: ``variable NAME internal VALUE``: a value a fix may change as the run goes
_INTERNAL_VARIABLE = re.compile(r"^variable\s+(\S+)\s+internal\s")
#: dump styles whose files :func:`fabmd.engine.lammps_dump.truncate_dump` can cut back
_CUT_DUMP_STYLES = ("custom", "atom", "local")
#: what a dump file written before the checkpoint is called while the resumed run writes
BEFORE_RESUME = ".before-resume"


@dataclass
class CheckpointState:
    """Where a run was when its checkpoint was written."""

    input_name: str
    command_index: int
    run_start: int
    run_steps: int
    step: int
    done: int
    monitor: dict | None = None
    #: IDs of the contact-history fixes (their pair instance numbers must match on resume)
    history_fixes: list[str] | None = None
    #: values of the immediate variables defined before the checkpoint (name -> value)
    frozen_variables: dict[str, float] | None = None

    def save(self, run_dir: Path) -> None:
        path = Path(run_dir) / STATE
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(self.__dict__, indent=1))
        os.replace(tmp, path)

    @classmethod
    def load(cls, run_dir: Path) -> CheckpointState:
        return cls(**json.loads((Path(run_dir) / STATE).read_text()))


def has_checkpoint(run_dir: Path) -> bool:
    """True if ``run_dir`` holds a checkpoint to resume from."""
    return (Path(run_dir) / STATE).exists() and (Path(run_dir) / RESTART).exists()


def output_files(command: str) -> list[str]:
    """Files a ``fix print`` / ``fix ave/time`` command writes to."""
    words = command.split()
    if len(words) > 3 and words[0] == "fix" and words[3] in ("print", "ave/time"):
        return [m.group(2).strip("\"'") for m in _FILE_KEYWORD.finditer(command)]
    return []


def dump_file(command: str) -> tuple[str, str] | None:
    """(dump id, file) of a ``dump ID group style N file ...`` command writing one file
    that a resumed run can append to (text or binary custom/atom/local), else None."""
    words = command.split()
    if len(words) > 5 and words[0] == "dump" and words[3] in _CUT_DUMP_STYLES:
        file = words[5].strip("\"'")
        if "*" not in file and "%" not in file and not file.endswith(".gz"):
            return words[1], file
    return None


def open_dumps(commands: list[str]) -> dict[str, str]:
    """Dumps defined by ``commands`` and not undumped again: {id: file}."""
    dumps: dict[str, str] = {}
    for command in commands:
        found = dump_file(command)
        if found is not None:
            dumps[found[0]] = found[1]
            continue
        words = command.split()
        if len(words) == 2 and words[0] == "undump":
            dumps.pop(words[1], None)
    return dumps


def immediate_variables(commands: list[str]) -> list[str]:
    """Names of the equal-style variables ``commands`` define with an immediate ``$(...)``
    value (fixed when the command ran: a replay at another time would change them), and of
    their ``internal`` variables (a fix changes them as the run goes)."""
    return [m.group(1) for c in commands
            for m in (_IMMEDIATE_VARIABLE.match(c) or _INTERNAL_VARIABLE.match(c),) if m]


def resume_commands(commands: list[str], state: CheckpointState) -> list[str]:
    """The commands that bring a fresh LAMMPS to the checkpoint's state and settings.

    The commands returned stop before the interrupted run (the caller continues it).
    """
    out = []
    frozen = state.frozen_variables or {}
    for command in commands[: state.command_index]:
        name = command.split()[0]
        immediate = _IMMEDIATE_VARIABLE.match(command)
        internal = _INTERNAL_VARIABLE.match(command)
        if immediate and immediate.group(1) in frozen:
            out.append(f"variable        {immediate.group(1)} equal "
                       f"{frozen[immediate.group(1)]!r}")
        elif internal and internal.group(1) in frozen:
            out.append(f"variable        {internal.group(1)} internal "
                       f"{frozen[internal.group(1)]!r}")
        elif name == "read_data":
            out.append(f"read_restart    {RESTART}")
        elif name in STATE_COMMANDS or plain_run_steps(command) is not None:
            continue
        elif output_files(command):
            out.append(_FILE_KEYWORD.sub(r"append \2", command))
        else:
            out.append(command)
    return out


def cut_outputs(run_dir: Path, commands: list[str], step: int) -> None:
    """Cut the output files of ``commands`` back to the lines up to ``step`` (a line the
    resumed run prints again at ``step`` is dropped by the readers), and the files of the
    dumps still open back to their frames before ``step``, set aside for
    :func:`join_dump_parts` (the resumed run writes the dump file anew)."""
    from .lammps_dump import truncate_dump

    join_dump_parts(run_dir, commands)  # of a resumed run that was stopped hard
    for name in open_dumps(commands).values():
        path = Path(run_dir) / name
        if path.exists():
            truncate_dump(path, step)
            os.replace(path, path.with_name(path.name + BEFORE_RESUME))
    for command in commands:
        for name in output_files(command):
            path = Path(run_dir) / name
            if not path.exists():
                continue
            keep = []
            for line in path.read_text().splitlines():
                words = line.split()
                if line.startswith("#") or not words:
                    keep.append(line)
                    continue
                try:
                    if float(words[0]) <= step:
                        keep.append(line)
                except ValueError:
                    keep.append(line)
            path.write_text("\n".join(keep) + "\n")


def drop_repeated_steps(run_dir: Path, commands: list[str]) -> None:
    """Keep one line per step in the output files of ``commands``: every chunk of a run is
    set up anew, and a ``fix print`` prints its step again at set-up (the last of equal
    lines is kept, as :func:`fabmd.results.folder.read_print_file` would)."""
    for command in commands:
        for name in output_files(command):
            path = Path(run_dir) / name
            if not path.exists():
                continue
            lines = path.read_text().splitlines()
            keep: list[str] = []
            last_step = None  # the step of the last data line kept
            for line in lines:
                words = line.split()
                step = words[0] if words and not line.startswith("#") else None
                if step is not None and step == last_step:
                    keep.pop(next(i for i in range(len(keep) - 1, -1, -1)
                                  if keep[i].split()[:1] == [step]))
                keep.append(line)
                if step is not None:
                    last_step = step
            if len(keep) != len(lines):
                tmp = path.with_name(path.name + ".tmp")
                tmp.write_text("\n".join(keep) + "\n")
                os.replace(tmp, path)


def join_dump_parts(run_dir: Path, commands: list[str]) -> None:
    """Put the frames written before a resume in front of the resumed run's (binary and
    text dumps alike: their frames are self-contained, so the files just concatenate)."""
    for name in open_dumps(commands).values():
        path = Path(run_dir) / name
        before = path.with_name(path.name + BEFORE_RESUME)
        if not before.exists():
            continue
        if path.exists():
            with open(before, "ab") as out, open(path, "rb") as after:
                while chunk := after.read(1 << 24):
                    out.write(chunk)
        os.replace(before, path)
