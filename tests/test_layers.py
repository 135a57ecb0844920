"""fabmd's layers: no module imports from a layer above its own, and no import cycles.

Every ``import`` is counted, also those inside functions (they run sooner or later);
imports under ``if TYPE_CHECKING:`` are not (they never run). ``from pkg import mod``
counts as an import of ``pkg.mod`` when ``mod`` is a module.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "fabmd"

#: bottom to top; a module may import from its own layer and those below it
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "units", "inputs", "progress", "examples_dir", "version", "describe", "schema"),
    ("engine",),
    ("geometry",),
    ("model",),
    ("scene",),
    ("analysis",),
    ("results",),
    ("protocols",),
    ("verification", "export"),
    ("scenefile", "settings", "stages", "preflight", "loose_height", "pipeline", "presets",
     "calibration"),
    ("cli", "__main__", ""),  # "" is fabmd/__init__.py: the public API on top
)


def module_names() -> dict[str, Path]:
    names = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        names[".".join(parts)] = path
    return names


def _type_checking_lines(tree: ast.AST) -> set[int]:
    """Line numbers inside ``if TYPE_CHECKING:`` blocks."""
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, (child.end_lineno or child.lineno) + 1))
    return lines


def imports(name: str, path: Path, modules: dict[str, Path]) -> set[str]:
    """The fabmd modules that ``name`` imports (anywhere in its file)."""
    tree = ast.parse(path.read_text())
    skip = _type_checking_lines(tree)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if getattr(node, "lineno", None) in skip:
            continue
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            subs = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in modules]
            found.update(subs)
            if len(subs) < len(node.names):
                found.add(target)
    return {m for m in found if m in modules and m != name}


def layer(name: str) -> int:
    first = name.split(".")[1] if "." in name else ""
    for level, members in enumerate(LAYERS):
        if first in members:
            return level
    raise AssertionError(f"fabmd module {name} is in no layer of tests/test_layers.py")


def graph() -> dict[str, set[str]]:
    modules = module_names()
    return {name: imports(name, path, modules) for name, path in modules.items()}


def test_no_import_from_a_higher_layer():
    upward = sorted(f"{name} imports {target}" for name, targets in graph().items()
                    for target in targets if layer(target) > layer(name))
    assert not upward, "imports from a higher layer:\n" + "\n".join(upward)


def find_cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return cycles


def test_no_import_cycles():
    cycles = find_cycles(graph())
    assert not cycles, "import cycles:\n" + "\n".join(" ↔ ".join(c) for c in cycles)


def test_the_checker_sees_imports_inside_functions_and_cycles(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("from typing import TYPE_CHECKING\n\n"
                     "if TYPE_CHECKING:\n    from ..protocols.common import scene_dict\n\n"
                     "def f():\n    from ..results.trajectory import finalise\n")
    modules = {"fabmd.model.probe": probe, "fabmd.results.trajectory": probe,
               "fabmd.protocols.common": probe}
    assert imports("fabmd.model.probe", probe, modules) == {"fabmd.results.trajectory"}
    assert find_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert layer("fabmd.model.bead_model") < layer("fabmd.results.trajectory")
