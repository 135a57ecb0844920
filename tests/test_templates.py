"""Template rendering is strict, and every shipped template is found (no LAMMPS)."""

import pytest

from fabmd.scene.templates import placeholders, render, template_dir


def test_templates_ship():
    names = {p.stem for p in template_dir().glob("*.lmp")}
    assert {"setup", "bonds", "guards", "fibre_tension", "run", "finish"} <= names


def test_render_fills_every_placeholder():
    text = render("run", steps=1000)
    assert "run             1000" in text and "{{" not in text


def test_missing_or_unused_values_raise():
    with pytest.raises(KeyError, match="missing"):
        render("run")
    with pytest.raises(KeyError, match="unused"):
        render("run", steps=1, extra=2)
    assert placeholders("run") == {"steps"}


def test_pyproject_lists_every_package():
    import tomllib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    listed = set(tomllib.loads((root / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(root).parts)
             for p in (root / "fabmd").rglob("__init__.py")}
    assert found | {"fabmd.lammps_templates", "fabmd.examples"} == listed
