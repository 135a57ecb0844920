"""Find and fill the LAMMPS input templates.

Templates are plain LAMMPS text with ``{{ name }}`` placeholders (LAMMPS keeps
``$x`` and ``${x}`` for its own variables). Rendering is strict: a missing or an
unused value is a programming error and raises.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path

_PLACEHOLDER = re.compile(r"\{\{\s*([A-Za-z_][A-Za-z0-9_]*)\s*\}\}")


@functools.cache
def template_dir() -> Path:
    """Folder of the shipped templates (installed package data, or the source tree)."""
    package = Path(__file__).resolve().parents[1]
    for folder in (package / "lammps_templates",          # installed wheel
                   package.parent / "lammps_templates"):  # source tree / editable install
        if folder.is_dir() and any(folder.glob("*.lmp")):
            return folder
    raise FileNotFoundError("lammps_templates not found in the installed package or source tree")


def template_text(name: str) -> str:
    """Raw text of ``lammps_templates/<name>.lmp``."""
    return (template_dir() / f"{name}.lmp").read_text()


def placeholders(name: str) -> set[str]:
    """Placeholder names used by a template."""
    return set(_PLACEHOLDER.findall(template_text(name)))


def fmt(value) -> str:
    """LAMMPS text for a value: floats with 10 significant digits."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.10g}"
    return str(value)


def render(name: str, /, **values) -> str:
    """Fill template ``name`` with ``values``.

    Raises:
        KeyError: a placeholder has no value, or a value has no placeholder.
    """
    text = template_text(name)
    wanted = set(_PLACEHOLDER.findall(text))
    missing = wanted - values.keys()
    unused = values.keys() - wanted
    if missing or unused:
        raise KeyError(f"template {name}: missing {sorted(missing)}, unused {sorted(unused)}")
    return _PLACEHOLDER.sub(lambda m: fmt(values[m.group(1)]), text)


def render_inline(name: str, /, **values) -> str:
    """:func:`render` without the template's final newline: a fragment that fills a
    placeholder line of another template (or joins with others line by line)."""
    return render(name, **values).removesuffix("\n")
