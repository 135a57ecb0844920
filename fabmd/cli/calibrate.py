"""``fabmd calibrate SCENE.toml --out DIR``: the crimp expansion that gives the datasheet's
fabric (thickness, free or at a pressure; crimp; yarn tension), written back as a scene
file (:mod:`fabmd.calibration`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_stage_options, emit, stage_inputs


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", type=Path, help="scene file (TOML) with a [calibrate] table "
                                           "and/or a datasheet [fabric] thickness")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a [calibrate] key (text with a unit or SI; repeatable), "
                        "e.g. --set thickness_m='0.45 mm' --set crimp_pct.weft=1.2 "
                        "--set max_runs=12")
    add_stage_options(p)


def run(args) -> int:
    from ..calibration import run_calibration
    from ..engine import mpi
    from .validate import parse_settings

    settings = parse_settings(args.set)
    if "max_runs" in settings:  # --set reads numbers as floats
        settings["max_runs"] = _whole(settings["max_runs"])
    scene, engine = stage_inputs(args)
    table = Table()
    found = run_calibration(scene, args.out, engine=engine, overwrite=args.overwrite,
                            settings=settings, preset=args.preset,
                            on_run=None if args.json or not mpi.is_root() else table.line)
    emit(found.result.summary, args.json, result_text(found))
    return 0


def _whole(value):
    return int(value) if isinstance(value, float) and value.is_integer() else value


class Table:
    """Prints one line per calibration run as it is measured (a header first)."""

    def __init__(self):
        self.started = False

    def line(self, record: dict) -> None:
        names = list(record["achieved"])
        if not self.started:
            print("run  " + "  ".join(f"{n:>24s}" for n in ["strains"] + names)
                  + "    wall", flush=True)
            self.started = True
        strains = ", ".join(f"{v:+.4f}" for v in record["knobs"].values())
        values = [_value(n, record["achieved"][n]) for n in names]
        notes = [text for key, text in (("failed", "run failed"),
                                        ("pressure_note", "curve starts above the pressure"))
                 if record.get(key)]
        if record.get("undrawable"):
            notes = ["the loose cell cannot be drawn at these heights: half the step"]
        if record.get("compaction_quasi_static") is False:
            notes.append("compaction not quasi-static")
        print(f"{record['run']:3d}  " + "  ".join(f"{v:>24s}" for v in [strains] + values)
              + f"  {record['wall_s']:5.1f} s" + (f"  ({'; '.join(notes)})" if notes else ""),
              flush=True)


def _value(name: str, value) -> str:
    if value is None:
        return "not measured"
    if name.startswith("thickness"):
        return f"{1e3 * value:.4f} mm"
    return f"{value:.3f} %" if name.startswith("crimp") else f"{value:.3f} N"


def result_text(found) -> str:
    """The terminal summary: targets and what was reached, the expansion, the files."""
    s = found.result.summary
    lines = [f"calibrated in {len(s['runs'])} crimp runs, {s['wall_s']:.3g} s: "
             f"run {s['best_run']} is the closest"]
    lines += [f"  {note}" for note in s.get("notes", [])]
    lines.append(f"  measured: {s['measure']}")
    for knob in s["knobs"] + s["uncontrolled"]:
        got = s["achieved"][knob["name"]]
        status = "reached" if knob["verdict"] in ("reached", "met") else "NOT reached"
        control = ("" if knob in s["knobs"] else
                   " (by the crimp's tension search)" if knob.get("acts_on") == "crimp_search"
                   else " (not controlled)")
        tol = knob["tolerance"]
        lines.append(f"  {knob['name']:16s} target {_value(knob['name'], knob['target'])} "
                     f"± {_value(knob['name'], tol).replace(' %', ' pp')}, "
                     f"got {_value(knob['name'], got)}: {status}{control}")
    lines.append("  [crimp] expansion = { " + ", ".join(
        f"{f} = {v:+.5g}" for f, v in s["expansion"].items()) + " }")
    for fam, height in sorted((s.get("loose_height_m") or {}).items()):
        lines.append(f"  [yarns.{fam}] height_m = {1e3 * height:.6g} mm (loose section)")
    if found.final:
        lines.append(f"  calibrated.toml crimped again: thickness "
                     f"{1e3 * found.final['thickness_m']:.4f} mm, crimp " + ", ".join(
                         f"{f} {v:.3f} %" for f, v in found.final["crimp_pct"].items()))
    if found.calibrated:
        lines.append(f"  scene file with this expansion: {found.calibrated}")
    lines.append(f"  results in {found.out}")
    return "\n".join(lines)
