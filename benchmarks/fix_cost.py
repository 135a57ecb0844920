"""Per-step cost of fabmd's own fixes and variables (issue 20): seconds per fix, before
and after the cheap forms.

Inputs, each run by ``lmp -in`` on one rank with its loading cut to a fixed number of
steps (no free relaxation: ``run 0``; the same cut as ``cluster_projection.py``):

* ``3d-tension``: ``examples/through_thickness_3d.toml`` at one fibre per yarn, its
  periodic cell crimped as the scene says and tiled 5 × 2 (the piece of the cluster
  projection), fabmd's tension input for it (a quarter of ``--steps``: 6× the beads);
* ``demo-tension``, ``demo-frame``: the demo's scene (``examples/plain_weave.toml``),
  its crimped cell cut to the demo's tension and picture-frame coupons (the coupons'
  own relaxation left out), fabmd's inputs for them.

For each input: the input as fabmd writes it now ("after"), the input fabmd wrote
before (``--before DIR``: a source tree of the older fabmd, rendered in a subprocess
with that tree first on the path), and the "after" input with one group of its fixes
removed: the drag (``damping``, ``damping_affine``), the interval means (``means``: the
clamp forces and the power sums), the stability guards (``guard_*``), the boundary
motion (``pull_*`` / ``frame``; the beads then stay put: a cost, not a physics, check),
and all of them ("bare"). All back to back, the set repeated; the machine's 1-minute
load before each run is kept. Costs are CPU seconds of the ``lmp`` process (user +
system; other jobs' share of the cores left out), the median over the repeats; a fix's
cost is the full input's minus the input without it.

Also: the error of the interval means sampled every
:data:`fabmd.protocols.driven.MEAN_SAMPLE_EVERY` steps against every step, on the same
trajectory (an every-step copy of ``fix means`` added to the "after" input): the largest
difference per interval relative to the column's peak, and of the summed work.

    python benchmarks/fix_cost.py [--steps 2000] [--repeat 2] [--before OLD_TREE] [--write]
    # whole runs before/after (each under its own tree), then their curves in the table:
    (cd OLD_TREE && PYTHONPATH=$PWD python NEW_TREE/benchmarks/fix_cost.py --whole /tmp/old)
    PYTHONPATH=$PWD python benchmarks/fix_cost.py --whole /tmp/new
    python benchmarks/fix_cost.py --report-only --curves /tmp/old /tmp/new --write
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

if "--render" not in sys.argv and "--whole" not in sys.argv:  # the fabmd on PYTHONPATH
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _results import table, update_section  # noqa: E402
from cluster_projection import fixed_steps, with_fibres  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
JSON = Path(__file__).with_name("fix_cost.json")
INPUTS = {"3d-tension": ("examples/through_thickness_3d.toml", "tension", 1),
          "demo-tension": ("examples/plain_weave.toml", "tension", None),
          "demo-frame": ("examples/plain_weave.toml", "picture-frame", None)}
#: groups of fixes removed, by fix id
GROUPS = {"drag": ("damping", "damping_affine"), "means": ("means",),
          "guards": ("guard_speed", "guard_nan", "guard_bond_stretch"),
          "motion": ("pull_left", "pull_right", "frame")}
PIECE_CELLS = (5, 2)


# ---- inputs ------------------------------------------------------------------------------
def build_models(root: Path) -> dict:
    """The models of :data:`INPUTS` (crimped cells, coupons cut from them), pickled in
    ``root`` so that an older fabmd renders its inputs for the very same beads."""
    from fabmd.engine import Engine
    from fabmd.model.transform import tile
    from fabmd.scenefile import load_scene
    from fabmd.stages import coupon_stage, crimp_stage, periodic_cell, protocol_stage

    models, cells = {}, {}
    for name, (scene_path, test, fibres) in INPUTS.items():
        scene = load_scene(ROOT / scene_path)
        scene = with_fibres(scene, fibres) if fibres else scene
        if scene_path not in cells:
            cells[scene_path] = crimp_stage(scene).run(
                periodic_cell(scene), root / f"crimp-{Path(scene_path).stem}",
                engine=Engine(progress=False), overwrite=True).model
        cell = cells[scene_path]
        if test == "tension" and fibres:
            model = tile(cell, *PIECE_CELLS, periodic=False)
        else:
            coupon, _ = coupon_stage(scene, test)
            model = coupon.geometry(cell)
            proto = protocol_stage(scene, test)
            model = proto.prepare(model) if hasattr(proto, "prepare") else model
        models[name] = model
    (root / "models.pkl").write_bytes(pickle.dumps(models))
    return models


def render_inputs(root: Path, steps: int, suffix: str) -> dict[str, Path]:
    """Run folders ``<name><suffix>`` with the inputs this fabmd writes for the pickled
    models (this function runs under the older fabmd too: ``--render``)."""
    from fabmd.protocols.common import write_run_folder
    from fabmd.scenefile import load_scene
    from fabmd.stages import protocol_stage

    models = pickle.loads((root / "models.pkl").read_bytes())
    folders = {}
    for name, (scene_path, test, fibres) in INPUTS.items():
        scene = load_scene(ROOT / scene_path)
        scene = with_fibres(scene, fibres) if fibres else scene
        text = fixed_steps(protocol_stage(scene, test).input_text(models[name]),
                           steps // 4 if fibres else steps)  # the 3D piece: 6x the beads
        protocol = test.replace("-", "_")
        folders[name] = write_run_folder(root / f"{name}{suffix}", protocol, models[name],
                                         text, {}, overwrite=True)
    return folders


def logical_lines(text: str) -> list[str]:
    """Input lines with their ``&`` continuations joined (each keeps its newlines)."""
    out, cur = [], ""
    for line in text.splitlines(keepends=True):
        cur += line
        if not line.rstrip().endswith("&"):
            out.append(cur)
            cur = ""
    return out + ([cur] if cur else [])


def without(text: str, fix_ids) -> str:
    """``text`` without the fixes ``fix_ids``."""
    return "".join(line for line in logical_lines(text)
                   if not (line.split()[:1] == ["fix"] and len(line.split()) > 1
                           and line.split()[1] in fix_ids))


def with_exact_means(text: str) -> str:
    """``text`` with an every-step copy of ``fix means`` written to ``exact.dat``."""
    m = re.search(r"^fix\s+means all ave/time (\d+) (\d+) (\d+) (.*?)&\n\s+format", text, re.M)
    every, values = m.group(3), m.group(4).strip()
    extra = (f"fix             exact_means all ave/time 1 {every} {every} {values} "
             f"format \" %.12g\" file exact.dat\n")
    i = text.index("\n", m.end()) + 1
    return text[:i] + extra + text[i:]


def variant(folder: Path, name: str, text: str) -> Path:
    """A copy of run folder ``folder`` with input ``text``."""
    out = folder.with_name(f"{folder.name}-{name}")
    out.mkdir(exist_ok=True)
    for f in ("model.data", "model.json"):
        (out / f).write_bytes((folder / f).read_bytes())
    (out / input_file(folder)).write_text(text)
    return out


def input_file(folder: Path) -> str:
    return next(p.name for p in folder.glob("in.*"))


# ---- runs --------------------------------------------------------------------------------
def timed_run(folder: Path) -> dict:
    """``lmp -in`` on one rank: wall, CPU seconds, load before, LAMMPS's breakdown."""
    from cluster_projection import timing_breakdown

    from fabmd.engine.standalone import run_standalone

    load = os.getloadavg()[0]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    run_standalone(folder, input_file(folder), ranks=1)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
    b = timing_breakdown((folder / "log.lammps").read_text())
    return {"wall_s": wall, "cpu_s": cpu, "load": load, "loop_s": b["loop_s"],
            "modify_pct": b["sections"]["Modify"]["pct"], "atoms": b["atoms"],
            "steps": b["steps"]}


def sampling_error(folder: Path) -> dict:
    """Sampled means (means.dat) against every-step ones (exact.dat): per column, the
    largest per-interval difference and the difference of the summed work, both
    relative to the peak of the every-step column (respectively of its running sum)."""
    import numpy as np

    s = np.loadtxt(folder / "means.dat", ndmin=2)
    e = np.loadtxt(folder / "exact.dat", ndmin=2)
    n = min(len(s), len(e))
    if not n:
        return {}
    s, e = s[:n, 1:], e[:n, 1:]
    names = (folder / "means.dat").read_text().splitlines()[1].split()[2:]
    out = {}
    for k, col in enumerate(names):
        peak = float(np.max(np.abs(e[:, k])))
        total = float(np.max(np.abs(np.cumsum(e[:, k]))))
        out[col] = {"interval": float(np.max(np.abs(s[:, k] - e[:, k]))) / peak,
                    "sum": abs(float(np.sum(s[:, k] - e[:, k]))) / total, "intervals": n}
    return out


def measure(root: Path, steps: int, repeat: int, before: Path | None,
            sampling_steps: int) -> dict:
    print("models (crimp, coupons) ...", flush=True)
    build_models(root)
    after = render_inputs(root, steps, "")
    if before is not None:
        env = dict(os.environ, PYTHONPATH=str(before))
        subprocess.run([sys.executable, __file__, "--render", str(root), "--steps", str(steps)],
                       env=env, check=True, cwd=before)
    runs: dict[str, dict[str, Path]] = {}
    for name, folder in after.items():
        text = (folder / input_file(folder)).read_text()
        runs[name] = {"after": folder}
        if before is not None:
            runs[name]["before"] = root / f"{name}-before"
        for group, ids in GROUPS.items():
            runs[name][f"-{group}"] = variant(folder, f"no-{group}", without(text, ids))
        runs[name]["bare"] = variant(folder, "bare",
                                     without(text, [i for ids in GROUPS.values() for i in ids]))
    data = {"steps": steps, "repeat": repeat, "runs": {}, "sampling": {}}
    for r in range(repeat):
        for name, variants in runs.items():
            for key, folder in variants.items():
                rec = timed_run(folder)
                data["runs"].setdefault(name, {}).setdefault(key, []).append(rec)
                print(f"  {r} {name:13s} {key:8s} cpu {rec['cpu_s']:6.2f} s wall "
                      f"{rec['wall_s']:6.1f} s Modify {rec['modify_pct']:4.1f} % load "
                      f"{rec['load']:.2f}", flush=True)
    data["sampling"] = sampling(root, sampling_steps)
    data["sampling_steps"] = sampling_steps
    return data


def sampling(root: Path, steps: int) -> dict:
    """The sampled means against every-step ones on the "after" inputs cut to ``steps``
    (more output intervals than the timing runs)."""
    out = {}
    for name, folder in render_inputs(root, steps, "-long").items():
        exact = variant(folder, "exact", with_exact_means((folder / input_file(folder))
                                                          .read_text()))
        timed_run(exact)
        out[name] = sampling_error(exact)
    return out


# ---- report ------------------------------------------------------------------------------
def med(recs: list[dict], key: str) -> float:
    return statistics.median(r[key] for r in recs)


HEADER = ["input", "beads", "steps", "run", "CPU [s]", "wall [s]", "per bead-step [ns]",
          "Modify [%]", "load"]


def rows(data: dict) -> list[list]:
    out = []
    for name, variants in data["runs"].items():
        for key, recs in variants.items():
            beads, steps = recs[0]["atoms"], recs[0]["steps"]
            cpu = med(recs, "cpu_s")
            out.append([name, f"{beads:,}", f"{steps:,}", key, f"{cpu:.2f}",
                        f"{med(recs, 'wall_s'):.1f}", f"{1e9 * cpu / beads / max(steps, 1):.0f}",
                        f"{med(recs, 'modify_pct'):.0f}",
                        " / ".join(f"{r['load']:.1f}" for r in recs)])
    return out


def fix_rows(data: dict) -> list[list]:
    """Seconds per fix group: the full input's CPU minus the input's without it."""
    out = []
    for name, variants in data["runs"].items():
        full = med(variants["after"], "cpu_s")
        line = [name]
        if "before" in variants:
            b = med(variants["before"], "cpu_s")
            line += [f"{b:.2f}", f"{full:.2f}", f"{b / full:.2f}x"]
        else:
            line += ["-", f"{full:.2f}", "-"]
        for group in GROUPS:
            line.append(f"{full - med(variants[f'-{group}'], 'cpu_s'):.2f}")
        line.append(f"{med(variants['bare'], 'cpu_s'):.2f}")
        out.append(line)
    return out


FIX_HEADER = ["input", "before [s]", "after [s]", "speed-up", "drag [s]", "means [s]",
              "guards [s]", "motion [s]", "bare (none of them) [s]"]
SAMPLING_HEADER = ["input", "column", "intervals", "max per-interval difference / peak",
                   "summed work difference / its peak"]


def sampling_rows(data: dict) -> list[list]:
    return [[name, col, v["intervals"], f"{v['interval']:.1e}", f"{v['sum']:.1e}"]
            for name, cols in data["sampling"].items() for col, v in cols.items()]


INTRO = """\
What changed (issue 20; LAMMPS evaluates an atom-style formula node by node for every bead
on every step, about 50-70 instructions a node under callgrind, which made fabmd's per-bead
formulas most of a step):

* drag -γ·(v − v_affine): `fix viscous` (no formula) plus an `addforce` of γ·L·(r − r0)
  whose coefficients are equal-style (one multiply-add per non-zero gradient entry per
  bead), instead of three per-bead formulas (`lammps_templates/affine_drag.lmp`);
* damping power γ·(Σ|v|² − Σ v_affine·v) from `reduce sumsq vx vy vz` and the sums of
  vx, vy and one product r_j·v_i per gradient entry, instead of a 25-node formula per bead
  (`damping_power.lmp`); identical to round-off (tests/test_fix_cost.py: 3e-15);
* tension clamp power −(F_left·v_left + F_right·v_right) from the clamp forces and
  `vcm()` (the clamps move as rigid bodies along x), instead of −f·v per clamped bead
  (`clamp_power_rigid.lmp`); identical to round-off;
* interval means (clamp forces, powers) sampled every 10 steps where the output interval
  is >= 200 steps (the plan rounds the interval to a multiple of 10): a Riemann sum on a
  10-step grid instead of every step (`driven_outputs.lmp`); its error: the last two
  tables.

"""


FINDINGS = """\
Where the time goes (callgrind, instructions per step of the 3D piece's tension input after
the drag and sum changes but before the 10-step sampling, 40 steps, 47,120 beads): 41 M a
step, of which the interval means 12 M (the per-bead sums), the drag's addforce 9 M (its
one formula per bead), bonds 7 M, neighbour lists 5 M, clamp motion 3 M, guards 3 M,
contact 2 M. The 10-step sampling evaluates the means on one step in ten. What remains of fabmd's
own: the affine part of the drag (one formula per free bead per step; LAMMPS has no
built-in force linear in position with a time-dependent coefficient), the clamps' `fix
move` and the guards. A "fix group" cost below is the difference of two runs on a shared
machine: about ±0.5 s of noise (the negative ones are noise).

"""


def report(data: dict) -> str:
    speedups = [f"{name} {med(v['before'], 'cpu_s') / med(v['after'], 'cpu_s'):.2f}× "
                f"(Modify {med(v['before'], 'modify_pct'):.0f} % → "
                f"{med(v['after'], 'modify_pct'):.0f} % of the loop; the bare input "
                f"{med(v['bare'], 'modify_pct'):.0f} %)"
                for name, v in data["runs"].items() if "before" in v]
    return (INTRO + ("Before/after (CPU time): " + ", ".join(speedups) + ".\n\n"
                     if speedups else "") + FINDINGS
            + "The machine (2 cores) was loaded by the other developers' jobs (the 1-minute "
              "load before each run is in the last column): CPU time of the `lmp` process, "
              "not wall time; read ratios, not absolute costs (an idle core is faster).\n\n"
            + f"CPU seconds of `lmp -in` on one rank, median of {data['repeat']} back-to-back "
            f"repeats, loading cut to {data['steps']:,} steps (the 3D piece: a quarter; no "
            "relaxation).\n\n"
            "### Seconds per fix group (after: the full input minus the input without it)\n\n"
            + table(FIX_HEADER, fix_rows(data))
            + "\n\n### Every run\n\n" + table(HEADER, rows(data))
            + "\n\n### Interval means sampled every 10 steps against every step "
              f"(same trajectory; loading cut to {data.get('sampling_steps', 0):,} steps, "
              "the 3D piece a quarter)\n\n" + table(SAMPLING_HEADER, sampling_rows(data))
            + "\n" + curves_text(data))


def curves_text(data: dict) -> str:
    """Whole runs before/after (``data["curves"]``, from ``--curves OLD NEW``)."""
    if not data.get("curves"):
        return ""
    rows = [[c["test"], c["column"], f"{c['difference']:.1e}"] for c in data["curves"]]
    return ("\n### Whole runs, before against after (curve.csv, interpolated at the same "
            "elongation / angle)\n\n" + data.get("curves_note", "") + "\n\n"
            + table(["test", "column", "max abs(after - before) / peak"], rows) + "\n")


def whole_runs(out: Path) -> None:
    """A small crimped plain weave (tests/fabrics.py) pulled to 3 % and sheared to 30° in a
    picture frame with 25 output intervals (long enough to sample the means), run folders
    ``out/t`` and ``out/pf``; under whichever fabmd is first on the path (``--whole``)."""
    sys.path.insert(0, str(Path.cwd()))  # that fabmd's tests/fabrics.py
    from fabmd.engine import Engine
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.crimp import Crimp
    from fabmd.protocols.picture_frame import PictureFrame
    from fabmd.protocols.tension import Tension
    from tests.fabrics import plain_weave_cell

    e = Engine(progress=False)
    crimped = Crimp(expansion={"warp": -0.02, "weft": -0.02}).run(
        plain_weave_cell(spacing_m=1e-3, gap=1.0), out / "crimp", engine=e,
        overwrite=True).model
    coupon = Coupon(length_m=12e-3, width_m=6e-3, relax=None).run(
        crimped, out / "ct", engine=e, overwrite=True).model
    Tension(max_elongation_pct=3.0, samples=25).run(coupon, out / "t", engine=e,
                                                     overwrite=True)
    square = Coupon(length_m=8e-3, width_m=8e-3, relax=None).run(
        crimped, out / "cf", engine=e, overwrite=True).model
    PictureFrame(max_shear_angle_deg=30, samples=25).run(square, out / "pf", engine=e,
                                                         overwrite=True)


def compare_curves(old: Path, new: Path) -> list[dict]:
    """Each column of ``curve.csv`` of the run folders ``old/<test>`` and ``new/<test>``
    (tension ``t``, picture frame ``pf``): the largest difference relative to the peak."""
    import csv

    import numpy as np

    out = []
    for test, x in (("t", "elongation_pct"), ("pf", "shear_angle_deg")):
        cols = {}
        for key, root in (("old", old), ("new", new)):
            rows = list(csv.reader(open(root / test / "curve.csv")))
            cols[key] = {h: np.array([float(r[i]) for r in rows[1:]])
                         for i, h in enumerate(rows[0])}
        o, n = cols["old"], cols["new"]
        for c in o:
            if c in (x, "step", "time_s", "displacement_m", "frame_angle_deg") or c not in n \
                    or c.startswith("interval_") or not np.nanmax(np.abs(o[c])):
                continue
            y = np.interp(o[x], n[x], n[c])
            out.append({"test": {"t": "tension", "pf": "picture frame"}[test], "column": c,
                        "difference": float(np.nanmax(np.abs(y - o[c])) / np.nanmax(np.abs(o[c])))})
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=2000)
    p.add_argument("--repeat", type=int, default=2)
    p.add_argument("--sampling-steps", type=int, default=6000,
                   help="steps of the runs that check the sampled means")
    p.add_argument("--sampling-only", action="store_true",
                   help="rerun only the sampled-means check (timings from the saved JSON)")
    p.add_argument("--before", type=Path, default=None,
                   help="source tree of the fabmd to compare with (its inputs are rendered "
                        "with it first on the path)")
    p.add_argument("--render", type=Path, default=None, help=argparse.SUPPRESS)
    p.add_argument("--whole", type=Path, default=None,
                   help="run the small whole tension and picture frame into this folder "
                        "(run it with PYTHONPATH and cwd the fabmd tree to use)")
    p.add_argument("--curves", type=Path, nargs=2, default=None, metavar=("OLD", "NEW"),
                   help="folders with run folders t/ and pf/ of the same tests by the old "
                        "and the new fabmd: their curve.csv compared (kept in the JSON)")
    p.add_argument("--curves-note", default="", help="how the --curves runs were made")
    p.add_argument("--json", type=Path, default=JSON)
    p.add_argument("--write", action="store_true", help="RESULTS.md section")
    p.add_argument("--report-only", action="store_true", help="from the saved JSON")
    args = p.parse_args(argv)
    if args.whole is not None:  # under whichever fabmd is on the path (cwd: its tree)
        whole_runs(args.whole)
        return 0
    if args.render is not None:  # under the older fabmd: its inputs for the same models
        render_inputs(args.render, args.steps, "-before")
        return 0
    if args.report_only or args.sampling_only:
        data = json.loads(args.json.read_text())
        if args.sampling_only:
            root = Path(tempfile.mkdtemp(prefix="fabmd-fix-cost-"))
            build_models(root)
            data["sampling"] = sampling(root, args.sampling_steps)
            data["sampling_steps"] = args.sampling_steps
            args.json.write_text(json.dumps(data, indent=1) + "\n")
    else:
        root = Path(tempfile.mkdtemp(prefix="fabmd-fix-cost-"))
        data = measure(root, args.steps, args.repeat, args.before, args.sampling_steps)
        data["machine_load_after"] = os.getloadavg()[0]
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    if args.curves:
        data["curves"] = compare_curves(*args.curves)
        data["curves_note"] = args.curves_note
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    body = report(data)
    print(body)
    if args.write:
        update_section("Per-step cost of fabmd's fixes", body,
                       "python benchmarks/fix_cost.py --before <old fabmd tree> --write")
    return 0


if __name__ == "__main__":
    sys.exit(main())
