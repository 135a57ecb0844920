"""Convergence: do the plain weave's results change when the model is refined?

Refinements of ``examples/plain_weave.toml`` (600 tex E-glass, 4 ends/cm x 4 picks/cm),
each varied alone from the example's defaults (7 fibres per yarn, s/d 0.5, its coupons):

* ``fibres`` — virtual fibres per yarn 1 / 7 / 19 (the yarn's tex, width, height and
  count unchanged: the fibres get thinner);
* ``sd`` — bead spacing over bead diameter 0.5 / 0.25 (and 0.125 when named:
  ``--levels sd=0.125``; stored, not tabled);
* ``cells`` — coupon size 3 / 4 / 6 unit cells (5 mm): tension, the coupon's length
  along the load (width fixed at the example's 2 cells); picture frame, the square's
  side. Compaction runs on the periodic cell: no coupon, so no ``cells`` levels.

Quantities (every run crimps the periodic cell once per discretisation and tiles its
coupon from it, as ``fabmd test`` does):

* tension — stiffness before and after the transition (fabmd's bilinear fit) and force
  at 1 / 2 / 3 %, all per unit width in N/mm (so coupon widths compare);
* picture frame — normalised force at 10 / 20 / 30 / 40° [N/mm] and the locking angle;
* periodic shear — the same of the crimped cell sheared by its box (no clamps: the
  frame's large-coupon limit, so no ``cells`` levels);
* compaction — thickness at 1 / 10 / 100 kPa [mm].

For each refinement the change between its two finest levels (fibres 7 → 19, s/d 0.5
→ 0.25, cells 4 → 6) is judged by issue #16's criterion: ≤ 5 % of the finer value,
locking angle ≤ 2°. Wall time, beads and steps are recorded per run. A run that did not
happen is listed as "not run (reason)", never filled in.

    python benchmarks/convergence.py --only compaction --only tension   # runs, prints
    python benchmarks/convergence.py --levels fibres=1,7 --levels sd     # some levels
    python benchmarks/convergence.py --set contact.within_family.law=glass   # another contact
    python benchmarks/convergence.py --replot --write     # section "Convergence" from the JSON

Results go to ``benchmarks/convergence.json`` (``convergence-<set>.json`` with ``--set``)
as each run finishes; a later call keeps them (``--fresh`` starts over) and runs only
what is missing. A run stopped by SIGTERM (e.g. ``timeout``) is recorded as not run,
with the time it had had.
"""

from __future__ import annotations

import argparse
import copy
import hashlib
import json
import math
import re
import sys
import tempfile
import time
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))  # _results, also when imported

from _results import machine, table, update_section  # noqa: E402

from fabmd.cli.validate import parse_settings  # noqa: E402
from fabmd.errors import FabmdError, OverlapWarning, RunInterrupted  # noqa: E402
from fabmd.examples_dir import example_scene  # noqa: E402
from fabmd.scenefile import Scene, parse_scene  # noqa: E402
from fabmd.schema import merged  # noqa: E402
from fabmd.stages import section as stage_section  # noqa: E402
from fabmd.units import quantity  # noqa: E402

HERE = Path(__file__).resolve().parent
EXAMPLE = "plain_weave.toml"
SECTION = "Convergence"
COMMAND = "python benchmarks/convergence.py --write"

TESTS = ("compaction", "tension", "picture-frame", "periodic-shear")
#: the tests whose quantities are the normalised shear force and the locking angle
SHEAR_TESTS = ("picture-frame", "periodic-shear")
#: refinement -> its levels, coarse to fine
LEVELS: dict[str, tuple] = {"fibres": (1, 7, 19), "sd": (0.5, 0.25), "cells": (3, 4, 6)}
#: finer levels run only when asked for by name (``--levels sd=0.125``): stored, not in the
#: tables or the judged pair (a 2 x 2 picture frame at s/d 0.125 is ~70 min here)
ON_REQUEST: dict[str, tuple] = {"sd": (0.125,)}
#: the criterion of issue #16 between the two finest levels of a refinement
TOLERANCE = 0.05
LOCKING_TOLERANCE_DEG = 2.0
#: longest JSON file name (most file systems: 255 bytes)
NAME_MAX = 255
#: optical gauge strains past the toe of the relieved coupon (its warp keeps the woven crimp,
#: ~3.7 % at 7 fibres; the gauge reaches ~5.8 % when the clamps reach the example's 6 %)
TENSION_STRAINS_PCT = (4.0, 4.5, 5.0)
FRAME_ANGLES_DEG = (10.0, 20.0, 30.0, 40.0)
PRESSURES_KPA = (1.0, 10.0, 100.0)
#: quantity -> (column title, unit)
QUANTITIES = {
    "tension": {"k_before": ("k before", "N/mm"), "k_after": ("k after", "N/mm"),
                **{f"F{e:g}%": (f"F {e:g} %", "N/mm") for e in TENSION_STRAINS_PCT}},
    "picture-frame": {**{f"F{a:g}°": (f"F {a:g}°", "N/mm") for a in FRAME_ANGLES_DEG},
                      "locking": ("locking", "°")},
    "compaction": {f"h{p:g}kPa": (f"h {p:g} kPa", "mm") for p in PRESSURES_KPA},
}
QUANTITIES["periodic-shear"] = dict(QUANTITIES["picture-frame"])


@dataclass(frozen=True)
class Variant:
    """One discretisation and coupon of the example for one test."""

    test: str
    n_fibres: int
    spacing_ratio: float
    cells: int | None  # tension: length along the load; picture frame: square side

    @property
    def key(self) -> str:
        text = f"{self.test} N{self.n_fibres} s/d {self.spacing_ratio:g}"
        return text + (f" {self.cells} cells" if self.cells is not None else "")

    @property
    def cost(self) -> float:
        """Relative run cost (ordering only): beads ∝ fibres/(s/d)·cells, the time step
        ∝ fibre diameter·(s/d)."""
        return self.n_fibres ** 1.5 / self.spacing_ratio ** 2 * (self.cells or 1)

    @property
    def crimp_tag(self) -> str:
        return f"n{self.n_fibres}_s{self.spacing_ratio:g}"


def read_example(name: str | None = None) -> dict:
    """The example scene file as a dict (TOML); default: the study's (``--scene``)."""
    return tomllib.loads(example_scene(name or EXAMPLE).read_text())


def base_levels(data: dict, frame_cells: int | None = None) -> dict:
    """The example's own level of each refinement: fibres per yarn, s/d, and the coupon
    cells of each test (tension: [length, width]; picture frame: side)."""
    fibres = {t.get("n_fibres") for t in data["yarns"].values()}
    if len(fibres) != 1:
        raise ValueError(f"the families' n_fibres differ ({sorted(fibres)}); give one")
    tension = data.get("tension", {}).get("coupon", {}).get("cells", [4, 2])
    frame = data.get("picture_frame", {}).get("coupon", {}).get("cells", [3, 3])
    return {"n_fibres": int(fibres.pop()),
            "spacing_ratio": float(data.get("discretisation", {}).get("spacing_ratio", 0.5)),
            "tension_cells": list(tension),
            "frame_cells": int(frame_cells if frame_cells is not None else frame[0])}


def variant(test: str, level: tuple[str, float], base: dict) -> Variant | None:
    """The run of ``test`` at refinement ``level`` = (refinement, value), the others at
    the example's level (None: the level does not apply to the test)."""
    kind, value = level
    cells = {"tension": base["tension_cells"][0], "picture-frame": base["frame_cells"],
             "compaction": None, "periodic-shear": None}[test]
    n, sd = base["n_fibres"], base["spacing_ratio"]
    if kind == "fibres":
        n = int(value)
    elif kind == "sd":
        sd = float(value)
    elif kind == "cells":
        if cells is None:  # a test on the periodic cell: no coupon
            return None
        cells = int(value)
    else:
        raise ValueError(f"refinement must be one of {', '.join(LEVELS)}, got {kind!r}")
    return Variant(test, n, sd, cells)


def scene_data(v: Variant, data: dict, base: dict) -> dict:
    """The scene-file dict of a run: ``data`` with its fibres, s/d and coupon set."""
    out = copy.deepcopy(data)
    for yarn in out["yarns"].values():
        yarn["n_fibres"] = v.n_fibres
    out.setdefault("discretisation", {})["spacing_ratio"] = v.spacing_ratio
    if v.test == "tension":
        out.setdefault("tension", {})["coupon"] = {
            "cells": [v.cells, base["tension_cells"][1]]}
    elif v.test == "picture-frame":
        out.setdefault("picture_frame", {})["coupon"] = {"cells": [v.cells, v.cells]}
    return out


def build_scene(v: Variant, data: dict, base: dict) -> Scene:
    """The validated scene of a run (through the scene-file parser, like ``fabmd test``)."""
    return parse_scene(scene_data(v, data, base), source=f"{EXAMPLE} [{v.key}]")


def planned(tests, levels: dict[str, tuple], base: dict) -> list[tuple[str, Variant]]:
    """(level label, run) of every requested level of every test, cheapest test first;
    a run shared by two levels (the example's own) appears under each."""
    out = []
    for test in TESTS:
        if test not in tests:
            continue
        for kind, values in levels.items():
            for value in values:
                v = variant(test, (kind, value), base)
                if v is not None:
                    out.append((f"{kind}={value:g}", v))
    return sorted(out, key=lambda lv: (TESTS.index(lv[1].test), lv[1].cost))


# -- running ----------------------------------------------------------------------------
def _at(x, y, point: float) -> float | None:
    """y at x = point (None outside the curve)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    slack = 1e-6 * max(abs(point), 1.0)
    if not x.size or not (x.min() - slack <= point <= x.max() + slack):
        return None
    order = np.argsort(x, kind="stable")
    return float(np.interp(point, x[order], y[order]))


def values_of(test: str, summary: dict, curve: dict) -> dict:
    """The table's quantities of a finished run (SI read, table units returned)."""
    s = summary["test_summary"]
    if test == "tension":  # against the optical gauge's strain where the run has one
        gauge = "gauge_strain_pct" in curve and "optical_gauge" in s
        x = curve["gauge_strain_pct"] if gauge else curve["elongation_pct"]
        y = curve["force_per_width_n_m"]
        forces = {f"F{e:g}%": _at(x, y, e) for e in TENSION_STRAINS_PCT}
        fit = s["optical_gauge"] if gauge else s
        return {"k_before": fit["initial_stiffness_n_m_per_width"] / 1e3,
                "k_after": fit["final_stiffness_n_m_per_width"] / 1e3,
                **{k: None if v is None else v / 1e3 for k, v in forces.items()}}
    if test in SHEAR_TESTS:
        x, y = curve["shear_angle_deg"], curve["normalised_force_n_m"]
        forces = {f"F{a:g}°": _at(x, y, a) for a in FRAME_ANGLES_DEG}
        return {**{k: None if v is None else v / 1e3 for k, v in forces.items()},
                "locking": s.get("locking_angle_deg")}
    h = s["thickness_at_pressure_m"]
    pressures = PRESSURES_KPA + datasheet_kpa(s.get("datasheet_pressure_pa"))
    return {f"h{p:g}kPa": None if h.get(f"{1e3 * p:g}") is None else 1e3 * h[f"{1e3 * p:g}"]
            for p in pressures}


def datasheet_kpa(pressure_pa) -> tuple[float, ...]:
    """The datasheet pressure [kPa] as one more compaction level (none: ())."""
    return () if pressure_pa is None else (float(pressure_pa) / 1e3,)


def add_datasheet_column(pressure_pa) -> None:
    """Show the thickness at the scene's ``[compaction] datasheet_pressure_pa`` too (a
    column after the fixed pressures; the convergence criterion judges it like them)."""
    if pressure_pa is not None:
        pressure_pa = quantity(pressure_pa, "pressure", "compaction.datasheet_pressure_pa")
    for p in datasheet_kpa(pressure_pa):
        QUANTITIES["compaction"].setdefault(f"h{p:g}kPa", (f"h {p:g} kPa (datasheet)", "mm"))


LOOP = re.compile(r"^Loop time of \S+ on \d+ procs for (\d+) steps", re.M)


def _steps(summary: dict) -> int | None:
    """Time steps the test ran: the sum of LAMMPS's loop lines (a compaction stops at its
    pressure long before its planned steps), else the summary's planned steps."""
    log = Path(summary["results"]) / "log.lammps"
    if log.exists():
        loops = [int(n) for n in LOOP.findall(log.read_text(errors="replace"))]
        if loops:
            return sum(loops)
    steps = summary["test_summary"].get("steps")
    return int(steps) if steps is not None else None


def folder_name(v: Variant) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", v.key)


def run_variant(v: Variant, data: dict, base: dict, root: Path, crimps: dict,
                engine) -> dict:
    """Crimp (once per discretisation) and run one test; its record."""
    from fabmd.pipeline import run_crimp, run_test
    from fabmd.results.folder import read_csv

    scene = build_scene(v, data, base)
    record: dict = {"key": v.key, "test": v.test, "n_fibres": v.n_fibres,
                    "spacing_ratio": v.spacing_ratio, "cells": v.cells}
    crimp_dir = root / f"crimp_{v.crimp_tag}"
    if v.crimp_tag not in crimps:
        if (crimp_dir / "summary.json").exists():
            crimps[v.crimp_tag] = {"wall_s": None, "reused": True}
        else:
            t0 = time.perf_counter()
            run_crimp(scene, crimp_dir, engine=engine, form="cell", overwrite=True)
            crimps[v.crimp_tag] = {"wall_s": time.perf_counter() - t0}
    record["crimp_wall_s"] = crimps[v.crimp_tag]["wall_s"]
    t0 = time.perf_counter()
    out = root / folder_name(v)
    summary = run_test(scene, v.test, out, engine=engine, crimped=crimp_dir, overwrite=True)
    record["wall_s"] = time.perf_counter() - t0
    s = summary["test_summary"]
    curve = read_csv(Path(summary["results"]) / "curve.csv")
    record.update(beads=summary["coupon_beads"], steps=_steps(summary),
                  values=values_of(v.test, summary, curve), **verdict_of(s), folder=str(out))
    if "thickness_monotone" in s:  # compaction: does the loading branch only get thinner?
        record["thickness_monotone"] = s["thickness_monotone"]
    if "optical_gauge" in s:  # tension: the same forces against the optical gauge's strain
        record["optical_gauge"] = s["optical_gauge"]
    return record


def verdict_of(test_summary: dict) -> dict:
    """The quasi-static verdict of a test: ok, the problems, and the trusted ranges of
    the curve where it is judged per interval."""
    verdict = test_summary.get("quasi_static")
    if not isinstance(verdict, dict):
        return {"quasi_static": None, "problems": [], "trusted": None}
    return {"quasi_static": verdict.get("ok"), "problems": verdict.get("problems", []),
            "trusted": verdict.get("trusted")}


def _verdict_text(r: dict, test: str) -> str:
    qs = r.get("quasi_static")
    if qs is None:
        return "–"
    if qs:
        return "yes"
    unit = " %" if test == "tension" else "°" if test in SHEAR_TESTS else ""
    trusted = r.get("trusted")
    if trusted:
        ranges = ", ".join(f"{a:g}–{b:g}" for a, b in trusted)
        return f"no; trusted {ranges}{unit}"
    if trusted == []:
        return "no; nowhere trusted"
    return "no"


def planned_size(v: Variant, data: dict, base: dict) -> tuple[int, int]:
    """(beads, steps) of a run's test, from its input rendered on the loose periodic
    cell without LAMMPS (the crimped cell has the same beads; steps are an upper bound
    for tests that stop early, e.g. compaction)."""
    from fabmd.engine.script import logical_lines, total_run_steps
    from fabmd.stages import coupon_stage, periodic_cell, protocol_stage

    scene = build_scene(v, data, base)
    model = periodic_cell(scene)
    protocol = protocol_stage(scene, v.test)
    if v.cells is not None:
        coupon, _ = coupon_stage(scene, v.test)
        model = coupon.geometry(model)
    if hasattr(protocol, "prepare"):
        model = protocol.prepare(model)
    return model.n_beads, total_run_steps(logical_lines(protocol.input_text(model)))


def estimate(plan: list[tuple[str, Variant]], data: dict, base: dict, store: dict) -> None:
    """Print beads × steps and a time for each planned run, at the cost per bead-step the
    study's finished runs of the same test measured (the engine's rough figure where
    none has run)."""
    from fabmd.engine.estimate import SECONDS_PER_BEAD_STEP

    runs = store.get("runs", {})
    seen = set()
    for _label, v in plan:
        if v.key in seen:
            continue
        seen.add(v.key)
        done = [r for r in runs.values() if r.get("test") == v.test and "values" in r
                and r.get("steps") and r.get("wall_s")]
        rate = (sum(r["wall_s"] for r in done) / sum(r["beads"] * r["steps"] for r in done)
                if done else SECONDS_PER_BEAD_STEP)
        beads, steps = planned_size(v, data, base)
        state = "done" if "values" in runs.get(v.key, {}) else "to run"
        print(f"{v.key:36s} {beads:7d} beads {steps:10d} steps  ~{rate * beads * steps / 60:6.1f}"
              f" min at {rate:.2g} s/bead-step ({state})", flush=True)


def salvage(v: Variant, data: dict, base: dict, out: Path) -> dict:
    """The record of a picture frame stopped before its end, reduced from its partial
    outputs with the protocol's own reduce (values past the angle it reached are None;
    the locking method reads the curve only to a little past locking). Raises what the
    reduce raises."""
    from fabmd.protocols.coupon import load_coupon
    from fabmd.stages import protocol_stage

    if v.test != "picture-frame":
        raise ValueError("only picture frames are salvaged (their curve is read by angle)")
    scene = build_scene(v, data, base)
    protocol = protocol_stage(scene, v.test)
    test_dir = out / stage_section(v.test)
    model = protocol.prepare(load_coupon(out / "coupon"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = protocol.reduce(test_dir, model, protocol.make_monitor())
    summary = {"test_summary": result.summary, "results": str(test_dir)}
    reached = float(np.max(result.curve["shear_angle_deg"]))
    return {"key": v.key, "test": v.test, "n_fibres": v.n_fibres,
            "spacing_ratio": v.spacing_ratio, "cells": v.cells, "wall_s": None,
            "beads": model.n_beads, "steps": _steps(summary),
            "values": values_of(v.test, summary, result.curve),
            "quasi_static": None, "problems": [], "trusted": None, "folder": str(out),
            "partial": f"stopped by the time limit at {reached:.1f}° of "
                       f"{protocol.max_shear_angle_deg:g}°; reduced from the partial "
                       f"outputs, no quasi-static verdict"}


def run_study(plan: list[tuple[str, Variant]], data: dict, base: dict, store: dict,
              data_path: Path, root: Path) -> bool:
    """Run every planned variant ``store`` lacks; False when a stop signal ended it."""
    from fabmd.engine import Engine

    engine = Engine(progress=False)
    crimps: dict = {}
    runs = store.setdefault("runs", {})
    for _label, v in plan:
        if v.key in runs and "values" in runs[v.key]:
            continue
        print(f"{time.strftime('%H:%M:%S')} {v.key} ...", flush=True)
        t0 = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", OverlapWarning)
                record = run_variant(v, data, base, root, crimps, engine)
        except RunInterrupted:
            runs[v.key] = {"key": v.key, "not_run": f"stopped by the time limit after "
                           f"{(time.perf_counter() - t0) / 60:.0f} min"}
            _save(store, data_path)
            print(f"  {runs[v.key]['not_run']}", flush=True)
            return False
        except FabmdError as exc:
            first = str(exc).splitlines()[0] if str(exc) else ""
            runs[v.key] = {"key": v.key, "not_run": f"failed: {type(exc).__name__}: "
                           f"{first[:160]}"}
        else:
            runs[v.key] = record
            print(f"  {record['wall_s']:.0f} s, {record['beads']} beads, "
                  f"{record['steps']} steps: {record['values']}", flush=True)
        _save(store, data_path)
    return True


def _save(store: dict, path: Path) -> None:
    store["machine"] = machine()
    path.write_text(json.dumps(store, indent=1))


# -- the table ----------------------------------------------------------------------------
def change(test: str, quantity: str, coarse, fine) -> dict:
    """The change from the coarser to the finer level and whether it meets the criterion:
    relative to the finer value (locking: in degrees)."""
    if coarse is None or fine is None:
        return {"change": None, "ok": None}
    if quantity == "locking":
        d = fine - coarse
        return {"change": d, "ok": abs(d) <= LOCKING_TOLERANCE_DEG}
    if fine == 0:
        return {"change": None, "ok": None}
    d = (fine - coarse) / abs(fine)
    return {"change": d, "ok": abs(d) <= TOLERANCE}


def finest_pair(kind: str) -> tuple:
    """The two finest levels of a refinement (coarser first)."""
    return LEVELS[kind][-2], LEVELS[kind][-1]


def _fmt(v, quantity: str = "") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    if quantity == "locking":
        return f"{v:.1f}"
    return f"{v:.4g}"


def _change_text(c: dict, quantity: str) -> str:
    if c["change"] is None:
        return "–"
    mark = "pass" if c["ok"] else "**fail**"
    if quantity == "locking":
        return f"{c['change']:+.1f}° {mark}"
    return f"{100 * c['change']:+.1f} % {mark}"


def shown_levels(test: str, kind: str, base: dict, levels: dict) -> tuple:
    """The levels of a refinement a table shows: ``levels[kind]``, and for ``cells`` the
    test's own base coupon when it is not one of them (picture frame ``--frame-cells 2``)."""
    values = tuple(levels[kind])
    if kind == "cells" and test == "picture-frame" and base["frame_cells"] not in values:
        values = tuple(sorted(values + (base["frame_cells"],)))
    return values


def runs_table(test: str, runs: dict, base: dict, levels: dict) -> str:
    """One row per level of ``test``: run, size, cost, values."""
    names = QUANTITIES[test]
    header = (["level", "run", "beads", "steps", "wall s", "quasi-static"]
              + [f"{title} [{unit}]" for title, unit in names.values()])
    rows = []
    for kind in levels:
        for value in shown_levels(test, kind, base, levels):
            v = variant(test, (kind, value), base)
            if v is None:
                continue
            r = runs.get(v.key)
            label = f"{kind} {value:g}"
            if v == variant(test, ("sd", base["spacing_ratio"]), base):
                label += " (base)"
            if r is None or "values" not in r:
                reason = r["not_run"] if r else "not requested in this pass"
                rows.append([label, v.key, "–", "–", "–", "–",
                             f"not run ({reason})", *["" for _ in range(len(names) - 1)]])
                continue
            qs = _verdict_text(r, test)
            if r.get("partial"):
                qs = f"partial: {r['partial']}"
            if r.get("thickness_monotone") is False:
                qs += "; thickness not monotone"
            rows.append([label, v.key, r["beads"], r["steps"] if r["steps"] else "–",
                         "–" if r.get("wall_s") is None else f"{r['wall_s']:.0f}", qs,
                         *(_fmt(r["values"].get(q), q) for q in names)])
    return table(header, rows)


def pair_row(test: str, kind: str, coarse, fine, runs: dict, base: dict,
             criterion: bool) -> list | None:
    """The change of every quantity from level ``coarse`` to ``fine`` (None: a level that
    does not apply to the test)."""
    vc, vf = variant(test, (kind, coarse), base), variant(test, (kind, fine), base)
    if vc is None:
        return None
    label = f"{kind} {coarse:g} → {fine:g}" + ("" if criterion else " (coarser pair)")
    rc, rf = runs.get(vc.key, {}), runs.get(vf.key, {})
    missing = [f"{kind} {lv:g}" for lv, r in ((coarse, rc), (fine, rf)) if "values" not in r]
    if missing:
        return [label, f"not run ({', '.join(missing)} not run)",
                *["" for _ in range(len(QUANTITIES[test]) - 1)], "–"]
    cs = {q: change(test, q, rc["values"].get(q), rf["values"].get(q))
          for q in QUANTITIES[test]}
    judged = [c["ok"] for c in cs.values() if c["ok"] is not None]
    verdict = "–" if not judged else ("pass" if all(judged) else "**fail**")
    if not criterion:
        verdict = f"({verdict})" if judged else "–"
    return [label, *(_change_text(cs[q], q) for q in QUANTITIES[test]), verdict]


def convergence_rows(test: str, runs: dict, base: dict) -> list[list]:
    """The change between the two finest levels of each refinement (the criterion), then
    between coarser neighbouring levels where both ran (for information)."""
    rows, extra = [], []
    for kind in LEVELS:
        row = pair_row(test, kind, *finest_pair(kind), runs, base, criterion=True)
        if row is None:
            continue
        rows.append(row)
        values = shown_levels(test, kind, base, LEVELS)
        for coarse, fine in zip(values[:-1], values[1:], strict=True):
            if (coarse, fine) == finest_pair(kind):
                continue
            row = pair_row(test, kind, coarse, fine, runs, base, criterion=False)
            if "not run" not in row[1]:
                extra.append(row)
    return rows + extra


def convergence_table(test: str, runs: dict, base: dict) -> str:
    header = (["refinement"] + [f"Δ {title}" for title, _ in QUANTITIES[test].values()]
              + ["all ≤ criterion"])  # coarser pairs: the verdict in brackets, information
    return table(header, convergence_rows(test, runs, base))


TEST_NOTES = {
    "compaction": "crimped periodic cell between rigid platens (the example's "
                  "[compaction]: to {max_pressure}{back}); thickness on the loading "
                  "branch; – where the curve starts above that pressure (the platen's first "
                  "contact already presses harder)",
    "tension": "coupon tiled from the crimped cell, {tension_len} cells long (the level) × "
               "{tension_width} wide, its fibres set at rest as cut (the tension coupon's "
               "relieve_tension) and relaxed free, clamps of one cell, to the example's "
               "6 % clamp strain; strain = the optical gauge's (two cross-sections a quarter "
               "of the free length in from each clamp: 4.9 / 10.0 mm at 4 / 6 cells, 2.5 mm "
               "at 3); forces per unit width "
               "[N/mm], stiffness = force per unit width per unit strain [N/mm] (bilinear "
               "fit)",
    "picture-frame": "square coupon tiled from the crimped cell, clamped as cut, "
                     "{frame_cells} × {frame_cells} cells for the fibres and s/d levels; "
                     "the example's speed and angle range",
    "periodic-shear": "the crimped periodic cell sheared by its box (trellis shear, both "
                      "families keep their length; no clamps: the picture frame's limit "
                      "for a large coupon); F_norm = the box's work per initial area per "
                      "Δ sin γ, locking by the frame's method; the scene's [periodic_shear]",
}


def section(store: dict, base: dict, levels: dict, tests, settings_text: str) -> str:
    """The RESULTS.md section (or its print-out)."""
    runs = store.get("runs", {})
    done = [r for r in runs.values() if "values" in r]
    total = sum((r.get("wall_s") or 0) + (r.get("crimp_wall_s") or 0) for r in done)
    changed = " ".join(f"--set {s}" for s in store.get("settings", []))
    own = "the example's own settings (its contact included)"
    if EXAMPLE != "plain_weave.toml":
        contact = f"{own}, changed with `{changed}`" if changed else own
    else:
        contact = (f"the example's settings changed with `{changed}`" if changed else
                   "the example's contact (default stiffness, μ = 0.3)")
    example_frame = base_levels(read_example())["frame_cells"]
    frame_note = "" if base["frame_cells"] == example_frame else \
        f" (the example's is {example_frame} × {example_frame}: smaller to afford the levels)"
    lines = [
        f"`examples/{EXAMPLE}` refined one parameter at a time from its defaults "
        f"({base['n_fibres']} fibres per yarn, s/d {base['spacing_ratio']:g}, tension "
        f"coupon {base['tension_cells'][0]} × {base['tension_cells'][1]} cells, picture "
        f"frame {base['frame_cells']} × {base['frame_cells']} cells{frame_note}; "
        f"{'1 cell = 5 mm; ' if EXAMPLE == 'plain_weave.toml' else ''}"
        f"\"(base)\" marks these in the tables), "
        f"{contact}. One process, in-process LAMMPS on one core, one run after the other "
        f"under `nice`, on the 2-core machine with other jobs beside it: wall times are "
        f"noisy. Runs in the table: {len(done)}, "
        f"{total / 60:.0f} min of runs and crimps.",
        "",
        f"Criterion (issue #16): between the two finest levels of each refinement "
        f"(fibres {finest_pair('fibres')[0]} → {finest_pair('fibres')[1]}, s/d "
        f"{finest_pair('sd')[0]:g} → {finest_pair('sd')[1]:g}, cells "
        f"{finest_pair('cells')[0]} → {finest_pair('cells')[1]}) every quantity changes by "
        f"≤ {100 * TOLERANCE:g} % of the finer value, the locking angle by ≤ "
        f"{LOCKING_TOLERANCE_DEG:g}°. Δ = (finer − coarser) / |finer|.",
        "",
    ]
    for test in TESTS:
        if test not in tests:
            continue
        note = TEST_NOTES[test].format(
            max_pressure=store.get("max_pressure") or "its default pressure",
            back="" if store.get("unload") is False else " and back",
            tension_len="3 / 4 / 6", tension_width=base["tension_cells"][1],
            frame_cells=base["frame_cells"])
        lines += [f"### {test}", "", f"{note}.", "", runs_table(test, runs, base, levels), "",
                  convergence_table(test, runs, base), ""]
    lines += ["What it shows:", "", *findings(store, base, tests)]
    if store.get("note"):
        lines += ["", store["note"]]
    return "\n".join(lines)


def findings(store: dict, base: dict, tests) -> list[str]:
    """Counted from the tables: per test and refinement, how many quantities meet the
    criterion and the largest change."""
    runs = store.get("runs", {})
    out = []
    for test in TESTS:
        if test not in tests:
            continue
        for kind in LEVELS:
            coarse, fine = finest_pair(kind)
            vc, vf = variant(test, (kind, coarse), base), variant(test, (kind, fine), base)
            if vc is None:
                continue
            rc, rf = runs.get(vc.key, {}), runs.get(vf.key, {})
            if "values" not in rc or "values" not in rf:
                out.append(f"* {test}, {kind} {coarse:g} → {fine:g}: not judged (not run)")
                continue
            cs = {q: change(test, q, rc["values"].get(q), rf["values"].get(q))
                  for q in QUANTITIES[test]}
            judged = {q: c for q, c in cs.items() if c["ok"] is not None}
            if not judged:
                out.append(f"* {test}, {kind} {coarse:g} → {fine:g}: no quantity measured "
                           f"at both levels")
                continue
            worst = max(judged, key=lambda q: abs(judged[q]["change"])
                        / (LOCKING_TOLERANCE_DEG if q == "locking" else TOLERANCE))
            w = judged[worst]["change"]
            shown = f"{w:+.1f}°" if worst == "locking" else f"{100 * w:+.1f} %"
            passed = sum(c["ok"] for c in judged.values())
            out.append(f"* {test}, {kind} {coarse:g} → {fine:g}: {passed} of {len(judged)} "
                       f"quantities within the criterion; largest change "
                       f"{QUANTITIES[test][worst][0]} {shown}")
    return out


def interval_table(runs: dict, test: str = "picture-frame") -> str:
    """Per-interval quasi-static verdict of every finished ``test`` run whose folder is
    kept: one row per interval (e.g. 5° of shear) with the drag (damping) share, inertia
    share and KE/U of that interval, and whether it passes."""
    rows = []
    for key, r in sorted(runs.items(), key=lambda kv: (kv[1].get("cells") or 0, kv[0])):
        if r.get("test") != test or "values" not in r or not r.get("folder"):
            continue
        path = Path(r["folder"]) / stage_section(test) / "summary.json"
        if not path.exists():
            continue
        ts = json.loads(path.read_text())
        ts = ts.get("test_summary", ts)
        for i in (ts.get("quasi_static_intervals") or {}).get("intervals", []):
            def share(name, i=i):
                return "–" if i.get(name) is None else f"{i[name]:.3f}"
            rows.append([key, f"{i['from']:g}–{i['to']:g}", share("damping_share"),
                         share("inertia_share"), share("kinetic_to_strain_energy"),
                         "yes" if i.get("ok") else "no"])
    return table(["run", "interval", "drag share", "inertia share", "KE/U", "ok"], rows)


def pressure_text(value) -> str:
    """A ``[compaction]`` pressure as the table says it ("120 kPa"; "" when not set)."""
    if value is None or value == "":
        return ""
    return f"{quantity(value, 'pressure', 'compaction.max_pressure_pa') / 1e3:g} kPa"


def scene_settings(pairs: list[str]) -> dict:
    """``--set`` pairs as a scene-file dict: ``parse_settings``'s numbers and text, and
    ``true`` / ``false`` as TOML booleans (e.g. ``compaction.unload=false``)."""
    def booleans(table: dict) -> dict:
        return {k: booleans(v) if isinstance(v, dict) else
                {"true": True, "false": False}.get(v, v) if isinstance(v, str) else v
                for k, v in table.items()}
    return booleans(parse_settings(pairs))


def data_path_for(settings_text: str) -> Path:
    """The JSON of a study: one per ``--set`` (the default contact's has no tag)."""
    tag = re.sub(r"[^A-Za-z0-9_.-]+", "_", settings_text).strip("_")
    name = f"convergence-{tag}.json" if tag else "convergence.json"
    if len(name) > NAME_MAX:  # many --set: a file name the file system takes, still one per study
        digest = hashlib.sha1(settings_text.encode()).hexdigest()[:12]
        name = f"{name[:NAME_MAX - 18]}-{digest}.json"
    return HERE / name


def parse_levels(items: list[str] | None) -> dict[str, tuple]:
    """``["fibres=1,7", "sd"]`` -> ``{"fibres": (1, 7), "sd": (0.5, 0.25)}`` (all levels
    of every refinement when ``items`` is empty)."""
    if not items:
        return dict(LEVELS)
    out: dict[str, tuple] = {}
    for item in items:
        kind, _, values = item.partition("=")
        kind = kind.strip()
        if kind not in LEVELS:
            raise SystemExit(f"--levels: refinement must be one of {', '.join(LEVELS)}, "
                             f"got {kind!r}")
        if not values:
            out[kind] = LEVELS[kind]
            continue
        chosen, known = [], LEVELS[kind] + ON_REQUEST.get(kind, ())
        for text in values.split(","):
            try:
                value = float(text)
            except ValueError:
                raise SystemExit(f"--levels {kind}: {text!r} is not a number") from None
            if value not in known:
                raise SystemExit(f"--levels {kind}: levels are "
                                 f"{', '.join(f'{x:g}' for x in known)}, got {text}")
            chosen.append(known[known.index(value)])
        out[kind] = tuple(sorted(set(out.get(kind, ())) | set(chosen), key=known.index))
    return out


def parse_not_run(item: str, base: dict) -> tuple[Variant, str]:
    """``"picture-frame/cells=6:estimated 100 min"`` -> (its run, the reason)."""
    where, _, reason = item.partition(":")
    test, _, level = where.partition("/")
    kind, _, value = level.partition("=")
    if test not in TESTS or kind not in LEVELS or not reason.strip():
        raise SystemExit(f"--not-run expects TEST/KIND=VALUE:REASON, got {item!r}")
    v = variant(test, (kind, float(value)), base)
    if v is None:
        raise SystemExit(f"--not-run: {test} has no {kind} levels")
    return v, reason.strip()


def main(argv: list[str] | None = None) -> int:
    global EXAMPLE  # the example every helper reads (one study per process)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true",
                        help="update section 'Convergence' of benchmarks/RESULTS.md")
    parser.add_argument("--only", action="append", choices=TESTS, default=None,
                        help="run only this test (repeatable)")
    parser.add_argument("--levels", action="append", default=None, metavar="KIND[=V,...]",
                        help="refinement levels to run (repeatable): fibres=1,7,19, "
                             "sd=0.5,0.25, cells=3,4,6; a kind alone: all its levels")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change the scene (table.key=value, repeatable), e.g. "
                             "--set contact.within_family.law=glass")
    parser.add_argument("--frame-cells", type=int, default=None,
                        help="picture-frame square (cells) of the fibres and s/d levels "
                             "(default: the example's)")
    parser.add_argument("--note", default=None,
                        help="a reading of the table, kept in the JSON and printed under it")
    parser.add_argument("--not-run", action="append", default=[],
                        metavar="TEST/KIND=VALUE:REASON",
                        help="say why a level was not run (kept in the JSON), e.g. "
                             "'picture-frame/cells=6:estimated 100 min'")
    parser.add_argument("--salvage", action="store_true",
                        help="reduce picture frames stopped by the time limit from their "
                             "partial outputs (marked partial in the table)")
    parser.add_argument("--estimate", action="store_true",
                        help="no runs: beads, steps and time of each planned run")
    parser.add_argument("--replot", action="store_true", help="no runs: table from the JSON")
    parser.add_argument("--intervals", action="store_true",
                        help="no runs: print the per-interval quasi-static table of the "
                             "picture frames whose folders are kept")
    parser.add_argument("--fresh", action="store_true", help="forget the JSON's runs")
    parser.add_argument("--root", type=Path, default=None, help="folder for the runs")
    parser.add_argument("--scene", default=EXAMPLE,
                        help=f"shipped example to refine (default {EXAMPLE}); another one "
                             "has its own JSON and section")
    args = parser.parse_args(argv)

    EXAMPLE = args.scene
    settings_text = " ".join(args.set)
    if EXAMPLE != "plain_weave.toml":
        settings_text = " ".join([Path(EXAMPLE).stem, *args.set])
    data = merged(read_example(), scene_settings(args.set))
    data_path = data_path_for(settings_text)
    store = {} if args.fresh or not data_path.exists() else json.loads(data_path.read_text())
    frame_cells = args.frame_cells
    if frame_cells is None:  # a study keeps the square it started with
        frame_cells = store.get("base", {}).get("frame_cells")
    base = base_levels(data, frame_cells)
    add_datasheet_column(data.get("compaction", {}).get("datasheet_pressure_pa"))
    levels = parse_levels(args.levels)
    tests = tuple(args.only) if args.only else TESTS
    if args.note is not None:
        store["note"] = args.note
    for item in args.not_run:
        v, reason = parse_not_run(item, base)
        if "values" not in store.setdefault("runs", {}).get(v.key, {}):
            store["runs"][v.key] = {"key": v.key, "not_run": reason}
    store.update(settings=args.set, base=base,
                 max_pressure=pressure_text(data.get("compaction", {}).get("max_pressure_pa")),
                 unload=data.get("compaction", {}).get("unload", True))
    finished = True
    if args.salvage:
        if args.root is None:
            raise SystemExit("--salvage needs --root (where the runs are)")
        root = args.root
        for key, r in store.get("runs", {}).items():
            if "values" in r or not r.get("not_run", "").startswith("stopped"):
                continue
            v = next((v for _, v in planned(TESTS, LEVELS, base) if v.key == key), None)
            if v is None or v.test != "picture-frame":
                continue
            try:
                store["runs"][key] = salvage(v, data, base, root / folder_name(v))
                print(f"salvaged {key}: {store['runs'][key]['partial']}")
            except Exception as exc:  # noqa: BLE001 - reported, the record stays "not run"
                print(f"could not salvage {key}: {type(exc).__name__}: {exc}")
        _save(store, data_path)
    if args.estimate:
        estimate(planned(tests, levels, base), data, base, store)
        return 0
    if args.intervals:
        print(interval_table(store.get("runs", {})))
        return 0
    if not args.replot:
        root = args.root or Path(tempfile.mkdtemp(prefix="fabmd-convergence-"))
        root.mkdir(parents=True, exist_ok=True)
        finished = run_study(planned(tests, levels, base), data, base, store, data_path, root)
    for r in store.get("runs", {}).values():  # steps from the logs where the runs are kept
        if r.get("folder") and "values" in r:
            steps = _steps({"results": str(Path(r["folder"]) / stage_section(r["test"])),
                            "test_summary": {"steps": r.get("steps")}})
            r["steps"] = steps
            test_summary = Path(r["folder"]) / stage_section(r["test"]) / "summary.json"
            if test_summary.exists():
                ts = json.loads(test_summary.read_text())
                r.update(verdict_of(ts))
                if r["test"] == "compaction":  # its values come from the summary alone
                    r["values"] = values_of("compaction", {"test_summary": ts}, {})
                    r["thickness_monotone"] = ts.get("thickness_monotone")
    # a study's tables: the tests it asked for now and those it has runs of
    ran = {r.get("test") for r in store.get("runs", {}).values()}
    shown = tuple(t for t in TESTS if t in tests or t in ran)
    body = section(store, base, dict(LEVELS), shown, settings_text)
    print(body)
    if args.write or args.note is not None or args.not_run:
        _save(store, data_path)
    if args.write:
        name = SECTION if not settings_text else f"{SECTION} ({settings_text})"
        command = COMMAND + "".join(f" --set {s}" for s in args.set)
        if EXAMPLE != "plain_weave.toml":
            command += f" --scene {EXAMPLE}"
        command += "".join(f" --only {t}" for t in args.only or ())
        if base["frame_cells"] != base_levels(read_example())["frame_cells"]:
            command += f" --frame-cells {base['frame_cells']}"
        update_section(name, body, command)
    return 0 if finished else 5


if __name__ == "__main__":
    sys.exit(main())
