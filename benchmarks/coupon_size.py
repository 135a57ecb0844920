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
distance from the next larger one (issue #16's criterion: within 5 %); with three sizes or
more, how far the fit misses the coupon it misses most (whether the edges' share goes as
1/n). Then each coupon's thickness at 10-40° in the centre of its free square and in the
band next to its clamps (``fabmd.results.zone_thickness``; read from the trajectory of runs
older than the summary's ``zone_thickness``) beside the periodic cell's. ``--write``:
section ``--section`` of RESULTS.md (default "Picture frame against coupon size").
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

from fabmd.analysis import FabricFrame  # noqa: E402
from fabmd.engine import Engine  # noqa: E402
from fabmd.pipeline import run_test  # noqa: E402
from fabmd.results.curves import locking_angle  # noqa: E402
from fabmd.results.zone_thickness import (  # noqa: E402
    REPORT_ANGLES_DEG,
    frame_zone_thickness,
    zone_summary,
    zone_thickness_m,
)
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


def zone_block(folder: Path, summary: dict, curve: dict) -> dict | None:
    """The run's ``zone_thickness`` summary block, measured on its trajectory when the run
    predates it (the free square centred on the coupon, as the frame places it)."""
    if summary.get("zone_thickness"):
        return summary["zone_thickness"]
    if not (folder / "trajectory.h5").exists():
        return None
    xy = FabricFrame.from_trajectory(folder / "trajectory.h5", 0).positions[:, :2]
    centre = 0.5 * (xy.min(axis=0) + xy.max(axis=0))
    half = 0.5 * summary["free_side_m"]
    zones = frame_zone_thickness(folder, (centre[0] - half, centre[0] + half,
                                          centre[1] - half, centre[1] + half), centre)
    angle = np.interp(zones["step"] * summary["time_step_s"], curve["time_s"],
                      curve["shear_angle_deg"])
    return zone_summary(angle, zones["centre_m"], zones["edge_m"])


def periodic_thickness(folder: Path) -> dict[str, float]:
    """The periodic cell's thickness at the report angles [m], measured as a zone's is
    (1-99 % span of the bead centres + a bead diameter) over the whole cell."""
    curve = read_curve(folder / "curve.csv")
    angles, values = [], []
    for frame in FabricFrame.iter_trajectory(folder / "trajectory.h5"):
        d = float(np.mean(frame.diameters)) if frame.diameters is not None else 0.0
        angles.append(np.interp(frame.time_s, curve["time_s"], curve["shear_angle_deg"]))
        values.append(zone_thickness_m(frame.positions[:, 2], d))
    # a run to 40° ends a hair short of it: read its last frame there
    return {f"{a:g}": float(np.interp(a, angles, values))
            for a in (0.0, *REPORT_ANGLES_DEG) if angles and max(angles) >= a - 0.5}


def thickness_table(rows: list[dict], periodic: dict | None) -> str:
    """Centre and edge-band thickness [mm] of each coupon at the start and the report
    angles, and the periodic cell's."""
    keys = [f"{a:g}" for a in REPORT_ANGLES_DEG]
    header = ["coupon", "0°"] + [f"{k}°" for k in keys]
    lines = []
    for r in rows:
        z = r["zones"]
        if not z:
            lines.append([f"{r['cells']} × {r['cells']}"] + ["–"] * (len(keys) + 1))
            continue
        at = z["at_angle"]
        lines.append([f"{r['cells']} × {r['cells']}: centre / band [mm]",
                      f"{1e3 * z['centre_m'][0]:.3f} / {1e3 * z['edge_m'][0]:.3f}"]
                     + [f"{1e3 * at[k]['centre_m']:.3f} / {1e3 * at[k]['edge_m']:.3f}"
                        if k in at else "–" for k in keys])
    if periodic is not None and periodic.get("thickness"):
        th = periodic["thickness"]
        lines.append(["periodic cell (whole cell) [mm]"]
                     + [f"{1e3 * th[k]:.3f}" if k in th else "–" for k in ["0", *keys]])
    return table(header, lines)


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
    if len(rows) > 2:
        header.append("fit's worst miss")
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
        if len(rows) > 2:  # the fit's worst miss: is the edges' share a clean 1/n?
            miss = (a + b / ns) / values - 1
            line.append(f"{100 * miss[np.argmax(np.abs(miss))]:+.1f} %")
        lines.append(line)
    locking = ", ".join(f"{r['cells']} × {r['cells']}: {r['locking']:.1f}°" for r in rows)
    if periodic is not None:
        locking += f"; periodic cell {periodic['locking']:.1f}°"
    beads = ", ".join(f"{r['cells']} × {r['cells']}: {r['beads']:,} beads, {r['steps']:,} "
                      f"steps, {r['wall_s']:.0f} s on {r['ranks']} rank(s)" for r in rows)
    return (table(header, lines) + f"\n\nLocking angle: {locking}.\nRuns: {beads}.\n\n"
            "Thickness of the free square's centre (the square half its side wide) and of "
            "the band next to the clamps (the rest of it), 1-99 % span of the bead centres "
            "+ a bead diameter:\n\n" + thickness_table(rows, periodic) + "\n")


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
    parser.add_argument("--section", default="Picture frame against coupon size",
                        help="the RESULTS.md section --write writes into (or appends)")
    args = parser.parse_args(argv)
    scene = load_scene(args.scene)
    engine = Engine(backend="standalone" if args.ranks > 1 else "inprocess",
                    ranks=args.ranks, progress=False)
    rows = []
    for cells in sorted(args.cells):
        folder = run_or_read(sized(scene, cells), "picture-frame", args.root / f"cells{cells}",
                             args.crimped, engine, args.replot)
        s = json.loads((folder / "summary.json").read_text())
        curve = read_curve(folder / "curve.csv")
        rows.append({"cells": cells, "n": round(s["free_side_m"] / _spacing(scene)),
                     "means": interval_means(curve, args.top),
                     "zones": zone_block(folder, s, curve),
                     "locking": s["locking_angle_deg"], "beads": s["n_beads"],
                     "steps": s["steps"], "wall_s": s["wall_s"], "ranks": s.get("ranks", 1)})
    periodic = None
    if not args.no_periodic:
        folder = run_or_read(scene, "periodic-shear", args.root / "periodic", args.crimped,
                             engine, args.replot)
        s = json.loads((folder / "summary.json").read_text())
        curve = read_curve(folder / "curve.csv")
        # by the frame's method (periodic summaries before stop 37 hold a tangent's angle)
        lock = locking_angle(curve["shear_angle_deg"], curve["normalised_force_n_m"])
        periodic = {"means": interval_means(curve, args.top),
                    "locking": lock["x"] if lock["found"] else float("nan"),
                    "thickness": (periodic_thickness(folder)
                                  if (folder / "trajectory.h5").exists() else None)}
    text = report(rows, periodic, args.top)
    print(text)
    if args.write:
        update_section(args.section, text,
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
