"""Picture-frame force against coupon size, and the large-coupon limit.

    python benchmarks/coupon_size.py SCENE --crimped CRIMP --cells 2 3 4 --root DIR [--ranks N]
    python benchmarks/coupon_size.py SCENE --root DIR --cells 2 3 4 --replot [--write]

Every run starts from one crimp folder (``fabmd crimp SCENE --form cell``), so the sizes
test the same fabric: the scene's picture frame on square coupons of ``cells`` × ``cells``
unit cells (its clamps, speed and angle) and its periodic shear (the cell sheared by its
box: no clamps, no edges — the limit of a large coupon). Runs already in ``DIR`` are read,
not run again. Prints, per 5° of shear, each run's mean F_norm, a least-squares fit
F = a + b/n over the coupons (n: free yarn spacings across the clamped square, the
free side over the yarn spacing), the fit's a beside the periodic cell, and each coupon's
distance from the next larger one (issue #16's criterion: within 5 %). ``--write``: section
"Picture frame against coupon size" of RESULTS.md.
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from _results import table, update_section  # noqa: E402
from interval_compare import interval_table, read_curve  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.pipeline import run_test  # noqa: E402
from fabmd.scenefile import load_scene  # noqa: E402

WIDTH_DEG = 5.0


def interval_means(curve: dict, top_deg: float) -> np.ndarray:
    """Mean F_norm [N/m] over each 5° of shear up to ``top_deg``."""
    rows = interval_table([("", curve)], WIDTH_DEG, top_deg)
    return np.array([1e3 * row["runs"][0]["force_n_mm"] for row in rows])


def run_or_read(scene, test: str, folder: Path, crimped: Path | None, engine: Engine,
                replot: bool) -> Path:
    """The test folder (``folder/<protocol>``), run unless it holds a summary."""
    inner = folder / test.replace("-", "_")
    if (inner / "summary.json").exists():
        return inner
    if replot or crimped is None:
        raise SystemExit(f"{inner}: no finished run (give --crimped CRIMP to run it)")
    run_test(scene, test, folder, engine=engine, crimped=crimped)
    return inner


def sized(scene, cells: int):
    """``scene`` with a picture-frame coupon of ``cells`` × ``cells`` unit cells."""
    protocols = copy.deepcopy(scene.protocols)
    frame = protocols.setdefault("picture_frame", {})
    frame["coupon"] = {**frame.get("coupon", {}), "cells": [cells, cells]}
    return dataclasses.replace(scene, protocols=protocols)


def fit(ns: np.ndarray, values: np.ndarray) -> tuple[float, float]:
    """Least-squares a, b of F = a + b/n."""
    design = np.vstack([np.ones_like(ns), 1.0 / ns]).T
    (a, b), *_ = np.linalg.lstsq(design, values, rcond=None)
    return float(a), float(b)


def report(rows: list[dict], periodic: dict | None, top_deg: float) -> str:
    """The tables: per interval, each coupon's F_norm, the fit and the periodic cell."""
    ns = np.array([r["n"] for r in rows], float)
    header = ["shear [°]"] + [f"{r['cells']} × {r['cells']} (n = {r['n']:g}) [N/m]"
                               for r in rows]
    header += ["fit a [N/m]", "fit b [N/m]"]
    if periodic is not None:
        header += ["periodic cell [N/m]", "a / periodic"]
    header += [f"{a['cells']}×{a['cells']} over {b['cells']}×{b['cells']}"
               for a, b in zip(rows[:-1], rows[1:], strict=True)]
    lines = []
    for k, lo in enumerate(np.arange(0.0, top_deg, WIDTH_DEG)):
        values = np.array([r["means"][k] for r in rows])
        a, b = (fit(ns, values) if len(rows) > 1 and np.all(np.isfinite(values))
                else (np.nan, np.nan))
        line = [f"{lo:g}–{lo + WIDTH_DEG:g}"] + [f"{v:.4g}" for v in values]
        line += [f"{a:.4g}", f"{b:.4g}"]
        if periodic is not None:
            p = periodic["means"][k]
            line += [f"{p:.4g}", f"{a / p:.3f}" if p else "–"]
        pairs = zip(values[:-1], values[1:], strict=True)
        line += [f"{100 * (x / y - 1):+.1f} %" for x, y in pairs]
        lines.append(line)
    locking = ", ".join(f"{r['cells']} × {r['cells']}: {r['locking']:.1f}°" for r in rows)
    if periodic is not None:
        locking += f"; periodic cell {periodic['locking']:.1f}°"
    beads = ", ".join(f"{r['cells']} × {r['cells']}: {r['beads']:,} beads, {r['steps']:,} "
                      f"steps, {r['wall_s']:.0f} s on {r['ranks']} rank(s)" for r in rows)
    return (table(header, lines) + f"\n\nLocking angle: {locking}.\nRuns: {beads}.\n")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", type=Path)
    parser.add_argument("--crimped", type=Path, default=None,
                        help="finished crimp folder of the scene's cell (fabmd crimp --form cell)")
    parser.add_argument("--cells", type=int, nargs="+", default=[2, 3, 4])
    parser.add_argument("--root", type=Path, required=True, help="folder for the runs")
    parser.add_argument("--ranks", type=int, default=1, help="MPI ranks (standalone back end)")
    parser.add_argument("--no-periodic", action="store_true", help="skip the periodic cell")
    parser.add_argument("--top", type=float, default=45.0, help="last angle tabulated [°]")
    parser.add_argument("--replot", action="store_true", help="no runs: read DIR")
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    args = parser.parse_args(argv)
    scene = load_scene(args.scene)
    engine = Engine(backend="standalone" if args.ranks > 1 else "inprocess",
                    ranks=args.ranks, progress=False)
    rows = []
    for cells in sorted(args.cells):
        folder = run_or_read(sized(scene, cells), "picture-frame", args.root / f"cells{cells}",
                             args.crimped, engine, args.replot)
        s = json.loads((folder / "summary.json").read_text())
        rows.append({"cells": cells, "n": round(s["free_side_m"] / _spacing(scene)),
                     "means": interval_means(read_curve(folder / "curve.csv"), args.top),
                     "locking": s["locking_angle_deg"], "beads": s["n_beads"],
                     "steps": s["steps"], "wall_s": s["wall_s"], "ranks": s.get("ranks", 1)})
    periodic = None
    if not args.no_periodic:
        folder = run_or_read(scene, "periodic-shear", args.root / "periodic", args.crimped,
                             engine, args.replot)
        s = json.loads((folder / "summary.json").read_text())
        periodic = {"means": interval_means(read_curve(folder / "curve.csv"), args.top),
                    "locking": s["locking_angle_deg"]}
    text = report(rows, periodic, args.top)
    print(text)
    if args.write:
        update_section("Picture frame against coupon size", text,
                       f"python benchmarks/coupon_size.py {args.scene} --crimped CRIMP "
                       f"--cells {' '.join(map(str, args.cells))} --root DIR")
    return 0


def _spacing(scene) -> float:
    """The yarn spacing across the clamps [m]: the smallest of the families' spacings (a
    2D weave's warp and weft; the frame's square holds whole spacings of both)."""
    spacings = [spec.spacing_m for spec in scene.fabric.specs().values() if spec.spacing_m]
    return float(min(spacings))


if __name__ == "__main__":
    raise SystemExit(main())
