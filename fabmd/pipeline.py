"""What a scene file runs: loose fabric → crimp → coupon → virtual test.

A results folder of ``fabmd test NAME SCENE.toml --out DIR`` holds one folder
per stage::

    DIR/crimp/    the as-woven state (crimped.data + crimped.json, sections.png, ...)
    DIR/coupon/   the coupon cut (or tiled) from it and relaxed free (coupon.data)
    DIR/NAME/     the test: curve.csv, summary.json, curve.png, the LAMMPS run
    DIR/summary.json   the stages' key results

Coupons are tiled from the crimped *periodic unit cell* of the scene's fabric by
default (cheap, no edge zone); ``[NAME.coupon] source = "fabric"`` cuts them from
the crimped fabric as described instead (its edge zone excluded).
"""

from __future__ import annotations

import dataclasses
import importlib
from dataclasses import dataclass
from pathlib import Path

from .engine import Engine, mpi
from .errors import InputError
from .model.bead_model import BeadModel
from .protocols.coupon import Coupon, CouponResult, load_coupon
from .protocols.crimp import Crimp, CrimpResult, load_crimped
from .results.folder import prepare_run_folder, write_json
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
    "tension": TestKind("fabmd.protocols.tension", "Tension",
                        {"length_m": 0.120, "width_m": 0.050}),
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


def register_test(name: str, kind: TestKind) -> None:
    """Add a test to the pipeline (protocol modules call this)."""
    TESTS[name] = kind


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


def run_crimp(scene: Scene, out: Path | None, engine: Engine | None = None,
              overwrite: bool = False, form: str = "fabric") -> CrimpResult:
    """Crimp the scene's fabric (``form="fabric"``) or its periodic unit cell (``"cell"``)."""
    if form not in ("fabric", "cell"):
        raise InputError(f"crimp form must be 'fabric' or 'cell', got {form!r}")
    loose = scene.model() if form == "fabric" else periodic_cell(scene)
    return crimp_stage(scene).run(loose, out, engine=engine, overwrite=overwrite)


def coupon_stage(scene: Scene, test: str) -> tuple[Coupon, str]:
    """The coupon of a test from ``[<test>.coupon]`` and its source (``cell``/``fabric``)."""
    kind = TESTS[test]
    table = dict(scene.protocols.get(section(test), {}).get("coupon", {}))
    source = table.pop("source", "cell")
    if source not in ("cell", "fabric"):
        raise InputError(f"[{section(test)}.coupon] source must be 'cell' or 'fabric', "
                         f"got {source!r}")
    cells = table.pop("cells", None)
    if cells is not None:
        cell = scene.fabric.unit_cell_m
        if not (isinstance(cells, list | tuple) and len(cells) == 2):
            raise InputError(f"[{section(test)}.coupon] cells must be [along x, along y], "
                             f"got {cells!r}")
        table.setdefault("length_m", cells[0] * cell[0])
        table.setdefault("width_m", cells[1] * cell[1])
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


def run_test(scene: Scene, test: str, out: Path, engine: Engine | None = None,
             overwrite: bool = False, check_rate: bool = False, resume: bool = False,
             crimped: Path | None = None) -> dict:
    """Run the whole pipeline for one test; returns the combined summary.

    Args:
        crimped: a finished crimp folder to start from (skips the crimp stage).
        resume: continue an interrupted run in ``out`` (finished stages are kept).
    """
    engine = engine or Engine()
    protocol = protocol_stage(scene, test)  # validate everything before LAMMPS starts
    coupon, source = coupon_stage(scene, test) if TESTS[test].coupon is not None else \
        (None, "cell")
    if coupon is None and scene.protocols.get(section(test), {}).get("coupon"):
        raise InputError(f"[{section(test)}] takes the crimped periodic cell itself: "
                         f"remove its coupon table")
    crimp = crimp_stage(scene)
    out = Path(out)
    if resume:
        if not out.is_dir():
            raise InputError(f"nothing to resume: {out} does not exist")
    else:
        out = prepare_run_folder(out, overwrite=overwrite, prefix=test)
    # 1. crimp
    crimp_dir = Path(crimped) if crimped is not None else out / "crimp"
    if crimped is None and not (crimp_dir / "crimped.data").exists():
        loose = periodic_cell(scene) if source == "cell" else scene.model()
        crimp_result: CrimpResult | None = crimp.run(loose, crimp_dir, engine=engine)
        crimped_model = crimp_result.model
    else:
        crimp_result = None
        crimped_model = load_crimped(crimp_dir)
    # 2. coupon
    if coupon is None:
        specimen = crimped_model
        coupon_result: CouponResult | None = None
    elif (out / "coupon" / "coupon.data").exists():
        specimen, coupon_result = load_coupon(out / "coupon"), None
    else:
        coupon_result = coupon.run(crimped_model, out / "coupon", engine=engine)
        specimen = coupon_result.model
    # 3. test
    result = protocol.run(specimen, out / section(test), engine=engine, check_rate=check_rate,
                          resume=resume and (out / section(test)).exists())
    summary = {"test": test, "scene": scene.source, "results": str(out / section(test)),
               "crimp": str(crimp_dir), "coupon_beads": specimen.n_beads,
               "test_summary": result.summary}
    if crimp_result is not None:
        summary["crimped"] = crimp_result.summary.get("crimped")
    if coupon_result is not None:
        summary["coupon"] = coupon_result.summary.get("relaxed_state")
    if mpi.is_root():
        write_json(out / "summary.json", summary)
    return summary
