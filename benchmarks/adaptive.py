"""Adaptive loading benchmark: steps, wall time and curve difference against the fixed speed.

For each test, crimps the periodic cell of ``examples/plain_weave.toml`` once, cuts and
relaxes the test's coupon once, then runs the test at the fixed base speed (the scene's
``speed_fraction``) and with adaptive loading (``loading_speed = { adaptive = true, ... }``,
:mod:`fabmd.scene.adaptive`) for each variant ``max_speed_factor:target``, all in this
process, one after another. Prints per run: loading steps, wall time (the test stage only),
their ratios to the fixed run's, the largest relative difference of the report values
(tension: force at 1/2/3 % elongation; picture frame: normalised force at 10/20/30/40°)
against the fixed run's, the largest difference over the whole curve (above a fifth of
its range, relative to the fixed curve's largest value) and the quasi-static verdict.

    python benchmarks/adaptive.py [--tests tension picture-frame] [--variants 8:0.25 4:0.25]
                                  [--fast] [--write] [--out DIR]
``--fast``: the picture frame's coupon with 1 fibre per yarn (7 are too slow here).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import table, update_section  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.pipeline import coupon_stage, crimp_stage, periodic_cell, protocol_stage  # noqa: E402
from fabmd.results.curves import curve_difference  # noqa: E402
from fabmd.scene.adaptive import AdaptiveLoading  # noqa: E402
from fabmd.scene.outputs import TrajectoryOutput  # noqa: E402
from fabmd.scenefile import load_scene  # noqa: E402

SCENE = Path(__file__).resolve().parents[1] / "examples" / "plain_weave.toml"
#: test -> (x column, y column, report x values, what they are)
REPORT = {"tension": ("elongation_pct", "force_n", (1.0, 2.0, 3.0), "force at 1/2/3 %"),
          "picture-frame": ("shear_angle_deg", "normalised_force_n_m", (10.0, 20.0, 30.0, 40.0),
                            "F_norm at 10/20/30/40°")}


def fast_scene(scene):
    """The scene with one fibre per yarn (``--fast``; s/d stays the scene's)."""
    specs = {fam: dataclasses.replace(spec, n_fibres=1,
                                      spacing_m=None if spec.count_per_m else spec.spacing_m)
             for fam, spec in scene.fabric.specs().items()}
    return dataclasses.replace(scene, fabric=dataclasses.replace(scene.fabric, **specs))


def prepared_coupon(scene, test: str, root: Path, engine: Engine):
    """The test's coupon of the example, cut from the crimped periodic cell and relaxed."""
    crimped = crimp_stage(scene).run(periodic_cell(scene), root / "crimp", engine=engine,
                                     overwrite=True).model
    coupon, _ = coupon_stage(scene, test)
    if test == "picture-frame":  # the 2 x 2-cell coupon
        cell = scene.fabric.unit_cell_m
        coupon = dataclasses.replace(coupon, length_m=2 * cell[0], width_m=2 * cell[1])
    return coupon.run(crimped, root / f"coupon-{test}", engine=engine, overwrite=True).model


def report_values(curve: dict, test: str) -> list[float | None]:
    """The report values, read off the curve (a point a hair past the curve's end, as the
    fixed run's last sample can be, is read at the end)."""
    xc, yc, xs, _ = REPORT[test]
    x, y = np.asarray(curve[xc], float), np.asarray(curve[yc], float)
    top = float(x.max())
    return [float(np.interp(min(v, top), x, y)) if v <= top * 1.005 else None for v in xs]


def run_one(test_obj, coupon, out: Path, engine: Engine, test: str) -> dict:
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the verdict is reported in the table
        result = test_obj.run(coupon, out, engine=engine, overwrite=True)
    wall = time.perf_counter() - t0
    s = result.summary
    adaptive = s.get("adaptive_loading")
    return {"steps": adaptive["steps"] if adaptive else s["steps"], "wall_s": wall,
            "curve": result.curve, "values": report_values(result.curve, test),
            "mean_factor": adaptive["mean_speed_factor_after_start"] if adaptive else 1.0,
            "ok": s["quasi_static"]["ok"], "beads": s["n_beads"]}


def compare(test: str, scene, coupon, variants: list[tuple[float, float]], root: Path,
            engine: Engine) -> list[list]:
    base = protocol_stage(scene, test)
    base = dataclasses.replace(base, trajectory=TrajectoryOutput(frames=0))
    fixed = run_one(base, coupon, root / f"{test}-fixed", engine, test)
    xc, yc, _, _ = REPORT[test]
    rows = [[test, "fixed", fixed["beads"], fixed["steps"], 1.0, fixed["wall_s"], 1.0,
             1.0, " / ".join(f"{v:.4g}" for v in fixed["values"] if v is not None), "-", "-",
             "yes" if fixed["ok"] else "no"]]
    print(rows[-1], flush=True)
    for k, target in variants:
        test_obj = dataclasses.replace(base, loading_speed=AdaptiveLoading(
            adaptive=True, max_speed_factor=k, target=target))
        run = run_one(test_obj, coupon, root / f"{test}-adaptive-{k:g}-{target:g}", engine,
                      test)
        diffs = [abs(a / f - 1) for a, f in zip(run["values"], fixed["values"], strict=True)
                 if a is not None and f]
        whole = curve_difference(fixed["curve"][xc], fixed["curve"][yc], run["curve"][xc],
                                 run["curve"][yc])
        rows.append([test, f"adaptive {k:g}x, target {target:g}", run["beads"], run["steps"],
                     fixed["steps"] / run["steps"], run["wall_s"],
                     fixed["wall_s"] / run["wall_s"], run["mean_factor"],
                     " / ".join(f"{v:.4g}" for v in run["values"] if v is not None),
                     f"{100 * max(diffs):.2f} %" if diffs else "-", f"{100 * whole:.2f} %",
                     "yes" if run["ok"] else "no"])
        print(rows[-1], flush=True)
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tests", nargs="+", default=["tension", "picture-frame"],
                   choices=sorted(REPORT))
    p.add_argument("--variants", nargs="+", default=["8:0.25", "4:0.25"],
                   help="max_speed_factor:target of each adaptive run")
    p.add_argument("--fast", action="store_true",
                   help="the picture frame with 1 fibre per yarn")
    p.add_argument("--out", type=Path, default=None, help="keep the run folders here")
    p.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    p.add_argument("--section", default="Adaptive loading")
    args = p.parse_args(argv)
    variants = [tuple(float(v) for v in text.split(":")) for text in args.variants]
    root = args.out or Path(tempfile.mkdtemp(prefix="adaptive-bench-"))
    engine = Engine(progress=False)
    rows = []
    for test in args.tests:
        scene = load_scene(SCENE)
        if args.fast and test == "picture-frame":
            scene = fast_scene(scene)
        coupon = prepared_coupon(scene, test, root / test, engine)
        rows += compare(test, scene, coupon, variants, root, engine)
    header = ["test", "loading", "beads", "steps", "fewer steps", "wall [s]", "faster",
              "mean speed factor", "report values", "largest report diff",
              "whole-curve diff", "quasi-static"]
    body = table(header, rows)
    print(body)
    if args.write:
        notes = "\n".join(f"- {t}: {REPORT[t][3]}" for t in args.tests)
        command = "python benchmarks/adaptive.py " + " ".join(argv or sys.argv[1:])
        update_section(args.section, body + "\n\nReport values:\n" + notes, command)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
