"""Read a LAMMPS input script into logical commands, and find its runs."""

from __future__ import annotations

import re

_RUN = re.compile(r"^run\s+(\d+)\s*$")


def _strip_comment(line: str) -> str:
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return line[:i]
    return line


def logical_lines(text: str) -> list[str]:
    """Commands of ``text``: comments stripped, ``&`` continuations joined, blanks dropped."""
    out: list[str] = []
    pending = ""
    for raw in text.splitlines():
        line = _strip_comment(raw).rstrip()
        if line.endswith("&"):
            pending += line[:-1] + " "
            continue
        line = (pending + line).strip()
        pending = ""
        if line:
            out.append(line)
    if pending.strip():
        out.append(pending.strip())
    return out


def plain_run_steps(command: str) -> int | None:
    """N for a plain ``run N`` command, else None."""
    m = _RUN.match(command)
    return int(m.group(1)) if m else None


def total_run_steps(commands: list[str]) -> int:
    """Sum of all plain ``run N`` commands."""
    return sum(plain_run_steps(c) or 0 for c in commands)
