"""Template rendering is strict, and every shipped template is found (no LAMMPS)."""

import ast
import re
from pathlib import Path

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


# -- one input writer: no LAMMPS command text in the protocols --------------------------
#: LAMMPS input commands: a string literal in a protocol whose line starts with one of them
#: (followed by an argument) is LAMMPS text, which belongs in lammps_templates/
LAMMPS_COMMANDS = frozenset("""
    angle_coeff angle_style atom_modify atom_style balance bond_coeff bond_style boundary
    change_box comm_modify comm_style compute compute_modify create_atoms create_box
    delete_atoms delete_bonds dimension displace_atoms dump dump_modify fix fix_modify group
    include jump kspace_style label lattice log mass min_modify min_style minimize molecule
    neigh_modify neighbor newton next pair_coeff pair_modify pair_style print processors
    read_data read_dump read_restart region replicate reset_timestep restart run set
    special_bonds thermo thermo_modify thermo_style timestep uncompute undump unfix units
    variable velocity write_data write_dump write_restart""".split())
_COMMAND_LINE = re.compile(r"\s*([a-z_]+)\s+\S")
#: modules not yet converted, by exact path (none left)
PENDING: set[str] = set()


def _docstrings(tree: ast.AST) -> set[int]:
    nodes = (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)
    return {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, nodes) and n.body and isinstance(n.body[0], ast.Expr)
            and isinstance(n.body[0].value, ast.Constant)}


def lammps_command_lines(source: str) -> list[tuple[int, str]]:
    """(line number, text) of every string literal line (docstrings aside) that starts
    with a LAMMPS command; an f-string's fields count as arguments."""
    tree = ast.parse(source)
    skip = _docstrings(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.JoinedStr):
            skip.update(id(v) for v in node.values)
            text = "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) \
                and id(node) not in skip:
            text = node.value
        else:
            continue
        for line in text.splitlines():
            m = _COMMAND_LINE.match(line)
            if m and m.group(1) in LAMMPS_COMMANDS:
                found.append((node.lineno, line.strip()))
    return found


def test_scan_finds_command_text():
    source = ('"""fix the docstring aside."""\nA = "fix             a all nve"\n'
              'B = f"variable        r0_{i} equal {r}"\nC = "run the crimp first"\n'
              'D = "#  run 100"\n')
    assert [n for n, _ in lammps_command_lines(source)] == [2, 3, 4]


def test_no_lammps_text_in_protocols():
    """The protocols and the input blocks take their LAMMPS text from lammps_templates/."""
    root = Path(__file__).resolve().parents[1]
    files = [*sorted((root / "fabmd" / "protocols").rglob("*.py")),
             root / "fabmd" / "scene" / "blocks.py"]
    found = [f"{p.relative_to(root)}:{n}: {line}" for p in files
             if p.relative_to(root).as_posix() not in PENDING
             for n, line in lammps_command_lines(p.read_text())]
    assert not found, "LAMMPS text outside lammps_templates/:\n" + "\n".join(found)


# -- input blocks that replace text edits after rendering ---------------------------------
def test_bond_ramp_and_its_end():
    from fabmd.scene import blocks

    from .fabrics import plain_weave_cell

    model = plain_weave_cell(spacing_m=1e-3)
    r0 = [bt.rest_length_m for bt in model.bond_type_table]
    start = blocks.bond_ramp(model, "crimp", {1: -0.02, 2: 0.0})
    assert start.splitlines() == [
        f'variable        r0_1 equal "{r0[0]:.10g}*(1+-0.02*ramp(0,1))"',
        "fix             crimp all adapt 1 bond harmonic r0 1 v_r0_1 reset no"]
    shrink = blocks.bond_ramp(model, "pre", {2: 0.01}, shrink=True)
    assert f'r0_2 equal "{r0[1]:.10g}*(1-0.01*ramp(0,1))"' in shrink
    nothing = blocks.bond_ramp(model, "crimp", {1: 0.0})
    assert f"variable        r0_1 equal {r0[0]:.10g}\n" in nothing
    end = blocks.bond_ramp_end(model, "pre", {2: 0.99}, [2], note=", preloaded")
    assert end.splitlines()[0] == "unfix           pre"
    assert end.splitlines()[1].startswith("bond_coeff      2 ")
    assert end.endswith(f"{r0[1] * 0.99:.10g}   # weft, preloaded")
    # all types by default, as bonds() writes them
    coeffs = [line for line in blocks.bonds(model).splitlines() if line.startswith("bond_c")]
    assert blocks.bond_coeffs(model).splitlines() == coeffs == \
        blocks.bond_ramp_end(model, "x", {}).splitlines()[1:]


def test_groups_and_lost_check():
    from fabmd.scene import blocks

    from .fabrics import plain_weave_cell

    assert blocks.group_ids("held", []) == "group           held empty"
    text = blocks.group_ids("held", range(1, 21))
    assert text.startswith("group           held id 1 2 ") and text.count(" &\n    ") == 1
    model = plain_weave_cell(spacing_m=1e-3)
    guarded = blocks.guards(model, 1e-7)
    assert blocks.lost_check() + "\n" in guarded
    assert blocks.guards(model, 1e-7, check_lost=False) == \
        guarded.replace(blocks.lost_check(), "")
