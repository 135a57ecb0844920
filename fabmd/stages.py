"""The stages a scene file builds, before anything runs: which tests exist, the loose
periodic cell, and the crimp, coupon and protocol objects of a scene's tables (validated).

Below both :mod:`fabmd.preflight` (which checks the objects) and :mod:`fabmd.pipeline`
(which runs them), so neither imports the other.
"""

from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass

from .errors import InputError
from .model.bead_model import BeadModel
from .protocols.coupon import Coupon
from .protocols.crimp import Crimp
from .scenefile import Scene
from .settings import build


@dataclass(frozen=True)
class TestKind:
    """A virtual test the pipeline can run."""

    module: str
    cls: str
    coupon: dict | None  # default coupon (None: the test takes the periodic cell itself)


#: test name (CLI spelling) -> where its protocol lives and its default coupon
TESTS: dict[str, TestKind] = {
    # the crimp's locked-in yarn tension relieved evenly before the free relaxation: let go
    # through the cut edges it leaves a crimp that varies with the coupon's length
    "tension": TestKind("fabmd.protocols.tension", "Tension",
                        {"length_m": 0.120, "width_m": 0.050, "relieve_tension": True}),
    # clamped as cut: a relaxed square of slack yarns crumples in the frame
    "picture-frame": TestKind("fabmd.protocols.picture_frame", "PictureFrame",
                              {"length_m": 0.100, "width_m": 0.100, "relax": None}),
    # yarn cohesion: cut free at 45°, yarns of loose fibres fray instead of trellising
    "bias-extension": TestKind("fabmd.protocols.bias_extension", "BiasExtension",
                               {"length_m": 0.150, "width_m": 0.050, "angle_deg": 45.0,
                                "cohesion_factor": 0.01}),
    # a square blank cut as tiled (no free relaxation: the drape's clamping phase relaxes it
    # under the blank holder); the quarter model keeps its x > 0, y > 0 part
    "drape": TestKind("fabmd.protocols.drape", "Drape",
                      {"length_m": 0.200, "width_m": 0.200, "relax": None}),
    "periodic-tension": TestKind("fabmd.protocols.periodic", "PeriodicTension", None),
    "periodic-shear": TestKind("fabmd.protocols.periodic", "PeriodicShear", None),
    # the as-woven periodic cell between two rigid platens
    "compaction": TestKind("fabmd.protocols.compaction", "Compaction", None),
}


def section(name: str) -> str:
    """Scene-file table of a test: ``picture-frame`` -> ``picture_frame``."""
    return name.replace("-", "_")


def periodic_cell(scene: Scene) -> BeadModel:
    """The scene's fabric as one periodic unit cell (loose)."""
    fabric = dataclasses.replace(scene.fabric, periodic=True, tiling=(1, 1))
    from .model.fabric_model import render_fabric

    return render_fabric(fabric, scene.discretisation)


def crimp_stage(scene: Scene) -> Crimp:
    """The crimp settings of ``[crimp]`` (contact from ``[contact]`` unless overridden)."""
    return build(Crimp, scene.protocols.get("crimp"), "crimp", contact=scene.contact)


def coupon_stage(scene: Scene, test: str) -> tuple[Coupon, str]:
    """The coupon of a test from ``[<test>.coupon]`` and its source (``cell``/``fabric``)."""
    kind = TESTS[test]
    table = scene.protocols.get(section(test), {}).get("coupon", {})
    if not isinstance(table, dict):
        raise InputError(f"[{section(test)}] coupon must be a table, e.g. coupon = "
                         f"{{ length_m = \"120 mm\", width_m = \"50 mm\" }} or coupon = "
                         f"{{ cells = [4, 2] }}, got {table!r}")
    table = dict(table)
    source = table.pop("source", "cell")
    if source not in ("cell", "fabric"):
        raise InputError(f"[{section(test)}.coupon] source must be 'cell' or 'fabric', "
                         f"got {source!r}")
    cells = table.pop("cells", None)
    if cells is not None:
        cell = scene.fabric.unit_cell_m
        if not (isinstance(cells, list | tuple) and len(cells) == 2
                and all(isinstance(n, int) and not isinstance(n, bool) and n > 0
                        for n in cells)):
            raise InputError(f"[{section(test)}.coupon] cells must be two whole numbers > 0 "
                             f"[along x, along y], got {cells!r}")
        table.setdefault("length_m", cells[0] * cell[0])
        table.setdefault("width_m", cells[1] * cell[1])
        table["cells"] = tuple(cells)  # of the crimped cell's own size (a released one is
        # shorter than the drawn one)
    defaults = dict(kind.coupon or {})
    defaults.update(table)
    return build(Coupon, defaults, f"{section(test)}.coupon", contact=scene.contact), source


def build_protocol(test: str, settings: dict | None = None, **defaults):
    """The protocol object of test ``test`` from a settings table (validated)."""
    if test not in TESTS:
        raise InputError(f"test must be one of {', '.join(sorted(TESTS))}, got {test!r}")
    kind = TESTS[test]
    cls = getattr(importlib.import_module(kind.module), kind.cls)
    return build(cls, settings, section(test), **defaults)


def protocol_stage(scene: Scene, test: str):
    """The protocol object of a test from its scene-file table."""
    table = {k: v for k, v in scene.protocols.get(section(test), {}).items() if k != "coupon"}
    return build_protocol(test, table, contact=scene.contact)
