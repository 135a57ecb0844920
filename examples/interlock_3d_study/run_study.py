"""The 3D study at its scale: the method paper's through-thickness angle interlock, from
the as-woven periodic cell to the 120 × 50 mm tension coupon and a picture frame.

Stages (each a fabmd run folder under ``--out``; every one runs again with plain
``mpirun -np N lmp -in in.<protocol>`` from its folder, see ``run.sh``):

* ``cell``    the periodic unit cell crimped as woven (thickness, crimp per family, yarn
              tension, cost);
* ``piece``   6 × 6 cells of the crimped cell, tiled, cut free and relaxed (thickness and
              crimp of its interior and of the whole piece against the cell);
* ``loose``   (not in the default list) the 6 × 6-cell piece crimped from loose as a
              finite piece (the issue's wording; about 4× the beads of the tension coupon);
* ``tension`` the 120 × 50 mm warp-direction coupon to 3 % (fabmd's pipeline: coupon cut
              from the crimped cell, its crimp tension relieved, relaxed, pulled);
* ``frame``   a 40 × 40 mm picture frame to 60° on the same crimped cell; the midplane of
              the sheared fabric against its thickness (wrinkling);
* ``frame-check`` (not in the default list) a 20 × 20 mm frame at 0.3 × the loading
              speed: quasi-static where the 40 mm frame at the default speed is not;
* ``stuffer`` (not in the default list) why the tension has no toe: a 48 × 20 mm coupon
              of the cell as crimped and of the cell crimped with its stuffers 1.5 %
              longer (wavy), both at s/d 0.9;
* ``mpirun``  (``--quick`` only by default) the quick tension coupon again as a run folder run
              by ``mpirun -np 2 lmp -in`` (the standalone back end): its curve against the
              in-process one.

``--quick`` runs the same stages on a tiny setting (2 × 2-cell piece, 48 × 20 mm coupon,
20 mm frame to 30°, loading 10 × faster) in about a minute; the test uses it. The results
go to ``<out>/study.json`` (the table of the README) and ``<out>/*.png``.

    python examples/interlock_3d_study/run_study.py --out runs/study3d [--np 1]
    python examples/interlock_3d_study/run_study.py --out /tmp/q --quick
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import json
import re
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SCENE = HERE / "interlock_3d_study.toml"
STAGES = ("cell", "piece", "tension", "frame")
ALL_STAGES = (*STAGES, "frame-check", "loose", "stuffer", "mpirun")

#: the tiny setting of ``--quick`` (scene tables replaced; the fabric is the same)
QUICK = {
    "piece_cells": 2,
    "tension": {"max_elongation_pct": 3.0, "speed_fraction": 1e-3,
                "coupon": {"length_m": "48 mm", "width_m": "20 mm"}},
    "picture_frame": {"max_shear_angle_deg": 30, "speed_fraction": 1e-2,
                      "coupon": {"length_m": "20 mm", "width_m": "20 mm"}},
}
PIECE_CELLS = 6
#: the interior of a piece: beads at least this fraction of its shorter side inside its
#: edges (24 mm on the 6 x 6-cell piece)
PIECE_EDGE_FRACTION = 0.2
#: elongation ranges [%] of the tangent stiffness before and after the warp straightens
SOFT_RANGE_PCT, STIFF_RANGE_PCT = (0.2, 1.0), (1.5, 3.0)
#: the stuffer experiment: the stuffers' extra rest-length strain and the coupon
STUFFER_EXPANSION = 0.015
STUFFER_COUPON = {"length_m": "48 mm", "width_m": "20 mm"}
STUFFER_SPACING_RATIO = 0.9
#: the picture frame's quasi-static check: a 20 mm frame at 0.3 × the default speed
FRAME_CHECK = {"speed_fraction": 3e-4, "coupon": {"length_m": "20 mm", "width_m": "20 mm"}}
#: in-plane bin of the midplane measure [m] (about a cell's weft columns)
MIDPLANE_BIN_M = 0.004

_LOOP = re.compile(r"^Loop time of (\S+) on (\d+) procs for (\d+) steps", re.M)


# ---- the scene ---------------------------------------------------------------------------
def study_scene(quick: bool = False, scene_path: Path = SCENE):
    """The study's scene (``--quick``: the tiny setting's tension and frame tables)."""
    from fabmd.scenefile import load_scene

    scene = load_scene(scene_path)
    if not quick:
        return scene
    protocols = copy.deepcopy(scene.protocols)
    for table in ("tension", "picture_frame"):
        protocols[table] = {**protocols.get(table, {}), **QUICK[table]}
    return dataclasses.replace(scene, protocols=protocols)


def engine_for(ranks: int):
    """One rank: in-process LAMMPS; more: the run folder under ``mpirun -np ranks lmp``."""
    from fabmd.engine import Engine

    if ranks > 1:
        return Engine(backend="standalone", ranks=ranks, progress=False)
    return Engine(progress=False, ranks=1)


def lammps_cost(folder: Path) -> dict:
    """Steps, ranks and LAMMPS loop time summed over every ``log.lammps`` under ``folder``."""
    steps = loop = 0.0
    ranks = set()
    for log in sorted(Path(folder).rglob("log.lammps")):
        for m in _LOOP.finditer(log.read_text(errors="replace")):
            loop += float(m.group(1))
            ranks.add(int(m.group(2)))
            steps += int(m.group(3))
    return {"steps": int(steps), "loop_s": loop, "ranks": sorted(ranks)}


def _families(values: dict, key: str | None = None) -> dict:
    return {f: (v[key] if key else v) for f, v in values.items()}


# ---- stages -------------------------------------------------------------------------------
def stage_cell(scene, out: Path, engine) -> dict:
    """(a) The periodic cell crimped as woven."""
    from fabmd.pipeline import run_crimp

    if engine is not None:
        run_crimp(scene, out / "cell", engine=engine, overwrite=True, form="cell")
    s = json.loads((out / "cell" / "summary.json").read_text())
    return {"folder": str(out / "cell"), "beads": s["crimped"]["n_beads"],
            "wall_s": s.get("wall_s"), "backend": s.get("backend"),
            **lammps_cost(out / "cell"), "stop": s["stop"],
            "thickness_m": {"loose": s["loose"]["thickness_m"],
                            "crimped": s["crimped"]["thickness_m"]},
            "crimp_pct": s["crimped"]["crimp_pct"],
            "yarn_tension_cn_per_tex": _families(s["yarn_tension"], "cn_per_tex"),
            "pass_through": s["pass_through"]}


def piece_measures(model, cell: dict) -> dict:
    """Thickness [m] and crimp [%] of a piece, whole and interior, against the cell's."""
    from fabmd.results.measure import fabric_measures
    from fabmd.results.yarn_tension import yarn_tension

    whole = fabric_measures(model)
    edge = PIECE_EDGE_FRACTION * float(np.ptp(model.unwrapped_positions[:, :2], axis=0).min())
    inner = fabric_measures(model, edge_m=edge)
    ref_t = cell["thickness_m"]["crimped"]
    return {"beads": model.n_beads,
            "thickness_m": {"whole": whole["thickness_m"], "interior": inner["thickness_m"],
                            "cell": ref_t},
            "thickness_vs_cell_pct": {"whole": 100 * (whole["thickness_m"] / ref_t - 1),
                                      "interior": 100 * (inner["thickness_m"] / ref_t - 1)},
            "crimp_pct": {"whole": whole["crimp_pct"], "interior": inner["crimp_pct"],
                          "cell": cell["crimp_pct"]},
            "interior_edge_m": edge,
            "yarn_tension_cn_per_tex": _families(yarn_tension(model), "cn_per_tex")}


def stage_piece(scene, out: Path, engine, cell: dict, cells: int) -> dict:
    """(b) ``cells`` × ``cells`` crimped cells tiled, cut free and relaxed (the crimp's
    tension kept: the yarns let go only where they are cut)."""
    from fabmd.protocols.coupon import Coupon, load_coupon
    from fabmd.protocols.crimp import load_crimped
    from fabmd.settings import build

    size = scene.fabric.unit_cell_m
    coupon = build(Coupon, {"length_m": cells * size[0], "width_m": cells * size[1]},
                   "piece.coupon", contact=scene.contact)
    wall = None
    if engine is not None:
        t0 = time.perf_counter()
        coupon.run(load_crimped(out / "cell"), out / "piece", engine=engine, overwrite=True)
        wall = time.perf_counter() - t0
    summary = json.loads((out / "piece" / "summary.json").read_text())
    return {"folder": str(out / "piece"), "cells": [cells, cells], "method": "tiled",
            "wall_s": wall, **lammps_cost(out / "piece"), "stop": summary.get("stop"),
            **piece_measures(load_coupon(out / "piece"), cell)}


def stage_loose(scene, out: Path, engine, cell: dict, cells: int) -> dict:
    """(b') The ``cells`` × ``cells`` piece crimped from loose as a finite piece."""
    from fabmd.model.fabric_model import render_fabric
    from fabmd.protocols.crimp import load_crimped
    from fabmd.stages import crimp_stage

    if engine is not None:
        fabric = dataclasses.replace(scene.fabric, periodic=False, tiling=(cells, cells))
        loose = render_fabric(fabric, scene.discretisation)
        crimp_stage(scene).run(loose, out / "loose", engine=engine, overwrite=True)
    s = json.loads((out / "loose" / "summary.json").read_text())
    return {"folder": str(out / "loose"), "cells": [cells, cells], "method": "from loose",
            "wall_s": s.get("wall_s"), **lammps_cost(out / "loose"), "stop": s["stop"],
            "pass_through": s["pass_through"],
            **piece_measures(load_crimped(out / "loose"), cell)}


def stage_wall(folder: Path, test_summary: dict) -> dict:
    """Wall time [s] of a test stage as its summaries recorded it: the test's engine wall
    time plus the coupon's LAMMPS loop time (the coupon summary keeps no wall time)."""
    coupon = lammps_cost(folder / "coupon")["loop_s"]
    test = test_summary.get("wall_s")
    return {"wall_s": None if test is None else test + coupon, "test_wall_s": test,
            "coupon_loop_s": coupon, "backend": test_summary.get("backend")}


def _curve(folder: Path) -> dict:
    data = np.genfromtxt(folder / "curve.csv", delimiter=",", names=True)
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


def tangent_stiffness(x, y, lo: float, hi: float) -> float | None:
    """Slope of the least-squares line of ``y`` over ``lo <= x <= hi`` (None: < 3 points)."""
    sel = (x >= lo) & (x <= hi)
    if sel.sum() < 3:
        return None
    return float(np.polyfit(x[sel], y[sel], 1)[0])


def _verdict(test_summary: dict) -> dict:
    """The quasi-static verdict: whole run and per interval (failed intervals listed)."""
    qs = test_summary.get("quasi_static") or {}
    intervals = test_summary.get("quasi_static_intervals") or {}
    failed = [{k: i.get(k) for k in ("start", "end", "problems") if k in i}
              for i in intervals.get("intervals", []) if i.get("problems")]
    return {"ok": qs.get("ok"), "problems": qs.get("problems", []),
            "intervals": len(intervals.get("intervals", [])), "failed_intervals": failed}


def stage_tension(scene, out: Path, engine) -> dict:
    """(c) The warp-direction tension coupon on the crimped cell."""
    from fabmd.pipeline import run_test

    if engine is not None:
        run_test(scene, "tension", out / "tension", engine=engine, overwrite=True,
                 crimped=out / "cell")
    summary = json.loads((out / "tension" / "summary.json").read_text())
    s = summary["test_summary"]
    folder = Path(summary["results"])
    c = _curve(folder)
    x, f = c["elongation_pct"], c["force_per_width_n_m"]
    # N/m per unit strain (fabmd's stiffness unit): the slope per % times 100
    soft, stiff = (None if k is None else 100 * k for k in
                   (tangent_stiffness(x, f, *SOFT_RANGE_PCT),
                    tangent_stiffness(x, f, *STIFF_RANGE_PCT)))
    coupon = scene.protocols["tension"]["coupon"]
    return {"folder": str(out / "tension"), "coupon": coupon, "beads": s["n_beads"],
            **stage_wall(out / "tension", s), **lammps_cost(out / "tension"),
            "coupon_stop": summary.get("coupon_stop"),
            "force_at_elongation_n": s["force_at_elongation_n"],
            "max_force_n": s["max_force_n"],
            "bilinear": {k: s.get(k) for k in ("initial_stiffness_n_m_per_width",
                                                "final_stiffness_n_m_per_width",
                                                "transition_elongation_pct")},
            "tangent_stiffness_n_m_per_width": {f"{SOFT_RANGE_PCT}": soft,
                                                f"{STIFF_RANGE_PCT}": stiff},
            "stiffening_ratio": stiff / soft if soft and stiff and soft > 0 else None,
            "rises": bool(f[-1] > f[0] and f.max() > 0),
            "midplane": midplane(folder / "trajectory.h5"),
            "quasi_static": _verdict(s)}


def stage_frame(scene, out: Path, engine, name: str = "frame") -> dict:
    """(d) The picture frame on the crimped cell (``name``: its folder)."""
    from fabmd.pipeline import run_test

    if engine is not None:
        run_test(scene, "picture-frame", out / name, engine=engine, overwrite=True,
                 crimped=out / "cell")
    summary = json.loads((out / name / "summary.json").read_text())
    s = summary["test_summary"]
    folder = Path(summary["results"])
    c = _curve(folder)
    angle, force = c["shear_angle_deg"], c["normalised_force_n_m"]
    reports = {f"{a:g}": float(np.interp(a, angle, force))
               for a in (10, 20, 30, 40, 50, 60) if a <= angle.max() + 1e-9}
    table = scene.protocols["picture_frame"]
    return {"folder": str(out / name), "coupon": table["coupon"],
            "speed_fraction": table.get("speed_fraction", 1e-3),
            "beads": summary["coupon_beads"], **stage_wall(out / name, s),
            **lammps_cost(out / name),
            "max_shear_angle_deg": float(angle.max()),
            "normalised_force_n_m": reports,
            "locking_angle_deg": s.get("locking_angle_deg"),
            "energy_balance": s.get("energy_balance"),
            "midplane": midplane(folder / "trajectory.h5", central=0.3),
            "quasi_static": _verdict(s)}


def frame_check_scene(scene):
    """The picture frame slower on a smaller frame (:data:`FRAME_CHECK`): the kinetic
    energy of the fabric moving with the frame takes a share of the frame's work ∝
    side × speed², here about 1/20 of the study frame's."""
    protocols = copy.deepcopy(scene.protocols)
    protocols["picture_frame"] = {**protocols.get("picture_frame", {}), **FRAME_CHECK}
    return dataclasses.replace(scene, protocols=protocols)


def midplane_of(positions: np.ndarray, diameter_m: float) -> dict:
    """Out-of-plane deviation of a sheet's midplane [m] (bead centres ``positions`` [m]).

    The beads are binned in-plane (:data:`MIDPLANE_BIN_M`); a bin's midplane is the mean of
    its highest and lowest bead centre, its thickness their distance plus a bead diameter;
    bins with few beads (a ragged edge) are left out. ``max_deviation_m`` = max |midplane −
    mean midplane| over the bins. Wrinkling shows as a deviation that grows to a fair part
    of the thickness.
    """
    xy, z = positions[:, :2], positions[:, 2]
    ij = np.floor((xy - xy.min(axis=0)) / MIDPLANE_BIN_M).astype(int)
    key = ij[:, 0] * (ij[:, 1].max() + 1) + ij[:, 1]
    order = np.argsort(key, kind="stable")
    _, start = np.unique(key[order], return_index=True)
    hi = np.maximum.reduceat(z[order], start)
    lo = np.minimum.reduceat(z[order], start)
    count = np.diff(np.append(start, len(order)))
    full = count >= max(3, 0.25 * np.median(count))
    mid, thick = 0.5 * (hi + lo)[full], (hi - lo)[full] + diameter_m
    dev = np.abs(mid - mid.mean())
    return {"bins": int(full.sum()), "max_deviation_m": float(dev.max()),
            "rms_deviation_m": float(np.sqrt(np.mean(dev**2))),
            "mean_thickness_m": float(thick.mean()),
            "max_deviation_over_thickness": float(dev.max() / thick.mean())}


def midplane(trajectory: Path, central: float | None = None) -> dict | None:
    """:func:`midplane_of` on the first and the last frame of a trajectory; ``central``:
    only beads within that fraction of the sheet's side from its centroid (a picture
    frame's free fabric, away from the clamps)."""
    from fabmd.analysis.trajectory_file import frame_count, read_model

    if not Path(trajectory).exists():
        return None
    out = {"bin_m": MIDPLANE_BIN_M, "central_fraction": central}
    for key, k in (("first", 0), ("last", frame_count(trajectory) - 1)):
        model = read_model(trajectory, k)
        p = model.unwrapped_positions
        if central is not None:
            xy = p[:, :2]
            side = float(np.ptp(xy, axis=0).max())
            p = p[np.linalg.norm(xy - xy.mean(axis=0), axis=1) <= central * side]
        out[key] = {"frame": k, **midplane_of(p, float(model.diameters.max()))}
    return out


def stage_mpirun(scene, out: Path, ranks: int = 2) -> dict:
    """The quick tension coupon's test again as a run folder run by ``mpirun -np ranks
    lmp -in in.tension``; its curve against the in-process run's (same coupon)."""
    from fabmd.engine import Engine
    from fabmd.protocols.coupon import load_coupon
    from fabmd.stages import protocol_stage

    first = out / "tension" / "tension"
    protocol = protocol_stage(scene, "tension")
    t0 = time.perf_counter()
    again = protocol.run(load_coupon(out / "tension" / "coupon"), out / "mpirun",
                         engine=Engine(backend="standalone", ranks=ranks, progress=False),
                         overwrite=True)
    wall = time.perf_counter() - t0
    a, b = _curve(first), again.curve
    f_a = a["force_n"]
    f_b = np.interp(a["elongation_pct"], b["elongation_pct"], b["force_n"])
    cmd = (out / "mpirun" / "run.sh").read_text() if (out / "mpirun" / "run.sh").exists() \
        else ""
    return {"folder": str(out / "mpirun"), "ranks": ranks, "wall_s": wall,
            **{k: v for k, v in lammps_cost(out / "mpirun").items() if k != "ranks"},
            "lammps_ranks": lammps_cost(out / "mpirun")["ranks"],
            "max_force_difference_over_peak": float(np.abs(f_b - f_a).max()
                                                    / np.abs(f_a).max()),
            "run_sh": bool(cmd)}


def stage_stuffer(scene, out: Path, engine, expansion: float = STUFFER_EXPANSION) -> dict:
    """Why the warp tension has no toe: the stuffers come out of the crimp straight. The
    tension test on a short coupon (:data:`STUFFER_COUPON`, the study's loading speed) of
    the cell as crimped, and of the cell crimped with the stuffers' rest length also
    lengthened by ``expansion`` (they buckle between the binders: crimp, slack); both at
    s/d :data:`STUFFER_SPACING_RATIO`."""
    from fabmd.pipeline import run_crimp, run_test

    out = out / "stuffer"
    results = {}
    for name, extra in (("straight", 0.0), ("wavy", expansion)):
        protocols = copy.deepcopy(scene.protocols)
        crimp = protocols.setdefault("crimp", {})
        crimp["expansion"] = {**crimp.get("expansion", {}), **({"warp": extra} if extra else {})}
        protocols["tension"] = {**protocols.get("tension", {}), "coupon": STUFFER_COUPON}
        # s/d below 1: the coupon's tension relief sets the longer stuffers' rest length to
        # their length, which at s/d 1 would exceed the bead diameter (refused)
        variant = dataclasses.replace(scene, protocols=protocols, discretisation=dataclasses.
                                      replace(scene.discretisation,
                                              spacing_ratio=STUFFER_SPACING_RATIO))
        if engine is not None:
            run_crimp(variant, out / name / "cell", engine=engine, overwrite=True, form="cell")
            run_test(variant, "tension", out / name / "tension", engine=engine, overwrite=True,
                     crimped=out / name / "cell")
        cell = json.loads((out / name / "cell" / "summary.json").read_text())
        test = json.loads((out / name / "tension" / "summary.json").read_text())
        t = test["test_summary"]
        c = _curve(out / name / "tension" / "tension")
        x, f = c["elongation_pct"], c["force_per_width_n_m"]
        results[name] = {
            "warp_expansion": extra, "spacing_ratio": STUFFER_SPACING_RATIO,
            "cell_crimp_pct": cell["crimped"]["crimp_pct"],
            "beads": t["n_beads"], **lammps_cost(out / name),
            "force_at_elongation_n": t["force_at_elongation_n"],
            "tangent_stiffness_n_m_per_width": {
                f"{lo}-{hi}": 100 * tangent_stiffness(x, f, lo, hi)
                for lo, hi in ((0.2, 0.6), (0.6, 1.0), (1.0, 1.5), (1.5, 2.0), (2.0, 3.0))},
            "bilinear": {k: t.get(k) for k in ("initial_stiffness_n_m_per_width",
                                                "final_stiffness_n_m_per_width",
                                                "transition_elongation_pct")},
            "quasi_static": _verdict(t), "folder": str(out / name)}
    results["wall_s"] = None
    return results


# ---- plots ---------------------------------------------------------------------------------
def plots(results: dict, out: Path) -> list[str]:
    """The study's figures into ``out``: tension curve, picture-frame curve."""
    from fabmd.results.plots import plot_curves

    made = []
    if "tension" in results:
        r = results["tension"]
        c = _curve(Path(r["folder"]) / "tension")
        path = plot_curves(out / "study_tension.png", [
            {"x": c["elongation_pct"], "y": c["force_per_width_n_m"], "label": "3D fabric"}],
            "elongation [%]", "force per width [N/m]",
            title=f"Warp tension, {r['coupon']['length_m']} x {r['coupon']['width_m']}",
            notes=f"{r['beads']:,} beads, {r['steps']:,} steps")
        made.append(str(path))
    series = []
    for key in ("frame", "frame-check"):
        if key in results:
            r = results[key]
            c = _curve(Path(r["folder"]) / "picture_frame")
            series.append({"x": c["shear_angle_deg"], "y": c["normalised_force_n_m"],
                           "label": f"{r['coupon']['length_m']} frame, speed "
                                    f"{r['speed_fraction']:g} ({r['beads']:,} beads, "
                                    f"{r['steps']:,} steps)"})
    if series:
        path = plot_curves(out / "study_frame.png", series, "shear angle [deg]",
                           "normalised force [N/m]", title="Picture frame, 3D fabric")
        made.append(str(path))
    if "frame" in results:  # the sheared fabric: top view and two cuts
        from fabmd.analysis.trajectory_file import read_model
        from fabmd.results.preview import preview_png

        r = results["frame"]
        traj = Path(r["folder"]) / "picture_frame" / "trajectory.h5"
        if traj.exists():
            path = preview_png(read_model(traj, -1), out / "study_frame_sheared.png",
                               title=f"Picture frame {r['coupon']['length_m']} at "
                                     f"{r['max_shear_angle_deg']:.0f} deg")
            made.append(str(path))
    if "stuffer" in results:
        r = results["stuffer"]
        series = []
        for name in ("straight", "wavy"):
            c = _curve(Path(r[name]["folder"]) / "tension" / "tension")
            crimp = r[name]["cell_crimp_pct"]["warp"]
            series.append({"x": c["elongation_pct"], "y": c["force_per_width_n_m"],
                           "label": f"stuffers {name} (crimp {crimp:.2f} %)"})
        path = plot_curves(out / "study_stuffer.png", series, "elongation [%]",
                           "force per width [N/m]",
                           title=f"Warp tension, {STUFFER_COUPON['length_m']} x "
                                 f"{STUFFER_COUPON['width_m']}: straight or wavy stuffers")
        made.append(str(path))
    return made


def small_png(src: Path, dst: Path, max_bytes: int = 200_000) -> Path | None:
    """``src`` as a palette PNG at ``dst``, halved until it is under ``max_bytes`` (the
    repository takes no large pictures); None when it cannot be made that small."""
    from PIL import Image

    image = Image.open(src).convert("RGB")
    for _ in range(4):
        image.quantize(colors=64).save(dst, optimize=True)
        if dst.stat().st_size < max_bytes:
            return dst
        image = image.resize((image.width * 3 // 4, image.height * 3 // 4), Image.LANCZOS)
    dst.unlink()
    return None


# ---- the table of the README ---------------------------------------------------------------
def _mm(m) -> str:
    return "–" if m is None else f"{1e3 * m:.2f}"


def _pct(values: dict) -> str:
    return ", ".join(f"{f} {v:.2f}" for f, v in values.items())


def _time(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def _cost(r: dict) -> str:
    wall = r.get("wall_s")
    ranks = "/".join(str(n) for n in r["ranks"])
    return (f"{r['beads']:,} beads, {r['steps']:,} steps, {ranks} rank(s), "
            f"LAMMPS loop {_time(r['loop_s'])}" + (f", wall {_time(wall)}" if wall else ""))


def table(results: dict) -> str:
    """The results as a markdown table (one row per stage that ran)."""
    rows = []
    if "cell" in results:
        r = results["cell"]
        rows.append(["(a) periodic cell, crimped", _cost(r),
                     f"thickness {_mm(r['thickness_m']['loose'])} → "
                     f"{_mm(r['thickness_m']['crimped'])} mm; crimp % {_pct(r['crimp_pct'])}; "
                     f"tension cN/tex {_pct(r['yarn_tension_cn_per_tex'])}; "
                     f"{r['pass_through']['flipped_pairs']} flipped pairs; {r['stop']}"])
    for key in ("piece", "loose"):
        if key in results:
            r = results[key]
            t, c = r["thickness_m"], r["crimp_pct"]
            rows.append([f"(b) {r['cells'][0]} × {r['cells'][1]}-cell piece, {r['method']}",
                         _cost(r),
                         f"thickness interior {_mm(t['interior'])} mm "
                         f"({r['thickness_vs_cell_pct']['interior']:+.1f} % against the cell), "
                         f"whole {_mm(t['whole'])} mm "
                         f"({r['thickness_vs_cell_pct']['whole']:+.1f} %); crimp % interior "
                         f"{_pct(c['interior'])}, whole {_pct(c['whole'])}; {r['stop']}"])
    if "tension" in results:
        r = results["tension"]
        k = r["tangent_stiffness_n_m_per_width"]
        soft, stiff = k[str(SOFT_RANGE_PCT)], k[str(STIFF_RANGE_PCT)]
        f = r["force_at_elongation_n"]
        m = r["midplane"]["last"] if r.get("midplane") else None
        rows.append([f"(c) tension {r['coupon']['length_m']} × {r['coupon']['width_m']}",
                     _cost(r),
                     f"F at 0.5/1/2 % {f['0.5']:.1f} / {f['1']:.1f} / {f['2']:.1f} N; "
                     f"tangent stiffness {SOFT_RANGE_PCT[0]}–{SOFT_RANGE_PCT[1]} % "
                     f"{soft:.3g}, {STIFF_RANGE_PCT[0]}–{STIFF_RANGE_PCT[1]} % "
                     f"{stiff:.3g} N/m per unit strain (× {r['stiffening_ratio']:.2f}); "
                     f"bilinear break "
                     f"{r['bilinear']['transition_elongation_pct']:.2f} %"
                     + (f"; midplane max abs(z − mean) {_mm(m['max_deviation_m'])} mm of "
                        f"{_mm(m['mean_thickness_m'])} mm" if m else "")
                     + f"; quasi-static: {_qs(r['quasi_static'])}"])
    for key in ("frame", "frame-check"):
        if key not in results:
            continue
        r = results[key]
        m = r["midplane"]
        f = r["normalised_force_n_m"]
        e = r.get("energy_balance") or {}
        kinetic = (e["kinetic_energy_change_j"] / e["external_work_j"]
                   if e.get("external_work_j") else None)
        rows.append([f"(d) picture frame {r['coupon']['length_m']} square, speed "
                     f"{r['speed_fraction']:g}", _cost(r),
                     "F_norm " + ", ".join(f"{a}° {v:.3g}" for a, v in f.items()) + " N/m; "
                     f"locking angle {r['locking_angle_deg']:.1f}°"
                     + (f"; midplane max abs(z − mean) {_mm(m['first']['max_deviation_m'])} → "
                        f"{_mm(m['last']['max_deviation_m'])} mm, thickness "
                        f"{_mm(m['first']['mean_thickness_m'])} → "
                        f"{_mm(m['last']['mean_thickness_m'])} mm" if m else "")
                     + (f"; kinetic energy {100 * kinetic:.0f} % of the frame's work"
                        if kinetic is not None else "")
                     + f"; quasi-static: {_qs(r['quasi_static'])}"])
    if "stuffer" in results:
        for name in ("straight", "wavy"):
            r = results["stuffer"][name]
            k = r["tangent_stiffness_n_m_per_width"]
            rows.append([f"stuffers {name} (expansion {r['warp_expansion']:+.3f}), tension "
                         f"{STUFFER_COUPON['length_m']} × {STUFFER_COUPON['width_m']}",
                         _cost(r), f"cell crimp % {_pct(r['cell_crimp_pct'])}; tangent "
                         "stiffness N/m per unit strain " + ", ".join(
                             f"{band} % {v:.3g}" for band, v in k.items())
                         + f"; quasi-static: {_qs(r['quasi_static'])}"])
    if "mpirun" in results:
        r = results["mpirun"]
        rows.append([f"mpirun -np {r['ranks']} lmp -in (quick tension)",
                     f"{r['steps']:,} steps, LAMMPS ranks {r['lammps_ranks']}",
                     f"force against the in-process curve: max difference "
                     f"{100 * r['max_force_difference_over_peak']:.2g} % of the peak"])
    lines = ["| stage | cost | result |", "|---|---|---|"]
    lines += [f"| {' | '.join(row)} |" for row in rows]
    return "\n".join(lines)


def _qs(verdict: dict) -> str:
    if verdict["ok"]:
        return f"ok ({verdict['intervals']} intervals)"
    failed = verdict["failed_intervals"]
    return (f"{len(failed)} of {verdict['intervals']} intervals flagged"
            if failed else "; ".join(verdict["problems"][:2]))


# ---- main ----------------------------------------------------------------------------------
def run(out: Path, stages=STAGES, ranks: int = 1, quick: bool = False,
        scene_path: Path = SCENE, summarise: bool = False) -> dict:
    """Run ``stages`` into ``out`` (``cell`` first where a later stage needs it; a stage
    finds an earlier one's folder from a previous call); returns and writes study.json.
    ``summarise``: run nothing, read the stages' finished folders back."""
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    scene = study_scene(quick, scene_path)
    engine = None if summarise else engine_for(ranks)
    cells = QUICK["piece_cells"] if quick else PIECE_CELLS
    path = out / "study.json"
    results = json.loads(path.read_text()) if path.exists() else {}
    results.update({"scene": str(scene_path), "quick": quick, "ranks": ranks})
    for stage in stages:
        print(f"study: {stage} ...", flush=True)
        if stage == "cell":
            results["cell"] = stage_cell(scene, out, engine)
        elif stage in ("piece", "loose"):
            fn = stage_piece if stage == "piece" else stage_loose
            results[stage] = fn(scene, out, engine, results["cell"], cells)
        elif stage == "tension":
            results["tension"] = stage_tension(scene, out, engine)
        elif stage == "frame":
            results["frame"] = stage_frame(scene, out, engine)
        elif stage == "frame-check":
            results[stage] = stage_frame(frame_check_scene(scene), out, engine, stage)
        elif stage == "stuffer":
            results["stuffer"] = stage_stuffer(scene, out, engine)
        elif stage == "mpirun":
            if not summarise:  # its result is only what the run measured
                results["mpirun"] = stage_mpirun(scene, out)
        else:
            raise SystemExit(f"unknown stage {stage!r}; one of {', '.join(ALL_STAGES)}")
        wall = results.get(stage, {}).get("wall_s")
        print(f"study: {stage} done" + (f" ({wall:.0f} s wall)" if wall else ""), flush=True)
        path.write_text(json.dumps(results, indent=1, default=float) + "\n")
    results["figures"] = plots(results, out)
    path.write_text(json.dumps(results, indent=1, default=float) + "\n")
    print(table(results), flush=True)
    return results


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=Path, required=True, help="results folder")
    p.add_argument("--np", type=int, default=1, dest="ranks",
                   help="MPI ranks (1: in-process; more: mpirun -np N lmp -in per stage)")
    p.add_argument("--quick", action="store_true", help="the tiny setting (about a minute)")
    p.add_argument("--stages", default=None,
                   help=f"comma-separated, in order (default {','.join(STAGES)}; "
                        f"--quick adds mpirun; also: loose)")
    p.add_argument("--pictures", type=Path, default=None,
                   help="copy the study's figures, each under 200 kB, into this folder")
    p.add_argument("--summarise", action="store_true",
                   help="run nothing: read the stages' finished folders in --out back")
    args = p.parse_args(argv)
    stages = args.stages.split(",") if args.stages else \
        [*STAGES, "mpirun"] if args.quick else list(STAGES)
    results = run(args.out, stages, args.ranks, args.quick, summarise=args.summarise)
    if args.pictures:
        args.pictures.mkdir(parents=True, exist_ok=True)
        for figure in results["figures"]:
            made = small_png(Path(figure), args.pictures / Path(figure).name)
            print(f"{figure} -> {made or 'over 200 kB: not copied'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
