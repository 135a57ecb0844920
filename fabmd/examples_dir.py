"""Where the shipped example scenes are (installed wheel or source tree)."""

from __future__ import annotations

from pathlib import Path

from .errors import InputError


def example_scene(name: str) -> Path:
    """Path of ``examples/<name>`` (e.g. ``plain_weave.toml``)."""
    package = Path(__file__).resolve().parent
    for folder in (package / "examples", package.parent / "examples"):
        if (folder / name).exists():
            return folder / name
    raise InputError(f"example scene {name!r} not found in the installed package or "
                     f"the source tree")
