"""Shared by the benchmark scripts: machine line and RESULTS.md sections."""

from __future__ import annotations

import datetime
import os
import platform
import re
from pathlib import Path

RESULTS = Path(__file__).with_name("RESULTS.md")


def machine() -> str:
    """One line naming the machine and date of a measurement."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{datetime.date.today().isoformat()}, {os.cpu_count()} cores, {cpu}, "
            f"Python {platform.python_version()}")


def table(header: list[str], rows: list[list]) -> str:
    """A markdown table."""
    def cell(v):
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |" for row in rows]
    return "\n".join(lines)


def update_section(name: str, body: str, command: str) -> None:
    """Write a script's measurement (machine line, command, ``body``) into the section
    ``name`` of RESULTS.md, leaving what was written there by hand.

    The measurement sits between ``<!-- name: generated -->`` and ``<!-- /name: generated
    -->`` inside the section, and a rerun replaces only that part: the reading and the
    tables of earlier invocations that a section gathers by hand stay (until stop 46 a
    ``--write`` replaced the whole section, "Ranks" with its hand-written reading among
    them). A section without those marks gets the measurement added at its end; a missing
    section is created with its heading."""
    text = RESULTS.read_text() if RESULTS.exists() else "# fabmd benchmark results\n"
    start, end = f"<!-- {name} -->", f"<!-- /{name} -->"
    gen_start, gen_end = f"<!-- {name}: generated -->", f"<!-- /{name}: generated -->"
    generated = (f"{gen_start}\nMeasured {machine()}.\nReproduce: `{command}`\n\n"
                 f"{body.strip()}\n{gen_end}")
    inner = re.compile(re.escape(gen_start) + r".*?" + re.escape(gen_end), re.S)
    section = re.compile(re.escape(start) + r".*?" + re.escape(end), re.S)
    if inner.search(text):
        text = inner.sub(lambda _m: generated, text, count=1)
    elif (found := section.search(text)) is not None:
        kept = found.group(0)[:-len(end)].rstrip()
        text = text[:found.start()] + f"{kept}\n\n{generated}\n{end}" + text[found.end():]
    else:
        text = text.rstrip() + f"\n\n{start}\n## {name}\n\n{generated}\n{end}\n"
    RESULTS.write_text(text)
