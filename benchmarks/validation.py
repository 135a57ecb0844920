"""Simulated against measured: the Twintex fabrics of the woven-fabric benchmark.

The scenes (``examples/twintex_plain.toml``, ``benchmarks/scenes/twintex_twill.toml``)
are written from the datasheet values of Cao et al. (2008), Table 1, and a friction
coefficient that is no fit (docs/validation_sources.md); nothing in them is tuned to the
shear curves they are compared with here, each against its own fabric's (``FABRICS``: the
digitised picture-frame curves, min / max / median per angle — the plain weave's seven
laboratories in ``benchmarks/data/cao2008_plain_weave.csv``, the balanced twill's four
curves in ``benchmarks/data/cao2008_balanced_twill.csv``).

Each ``--scene`` is crimped as a periodic cell (its ``[crimp]``), then sheared in the
picture frame (its ``[picture_frame]``) and, with ``--compaction``, pressed to its
datasheet pressure (thickness against the datasheet's). Results are kept by scene title
in ``benchmarks/validation.json`` so variants (contact laws) accumulate; ``--from DIR``
adds a finished ``fabmd test picture-frame`` folder without running it again (``--fabric``
says which fabric's measurements it is compared with; a ``--scene``'s weave says it).

    python benchmarks/validation.py --scene examples/twintex_plain.toml --out /tmp/val
    python benchmarks/validation.py --from /tmp/val/pf --label "stiff contact" --write
    python benchmarks/validation.py --from /tmp/twill/pf --fabric twill --label "..." --write
    python benchmarks/validation.py --write          # the section from validation.json
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from _results import table, update_section  # noqa: E402

STORE = HERE / "validation.json"
ANGLES = (10, 20, 30, 40)
#: every laboratory's picture-frame curve at 5° (the fabrics' CSVs hold min / max / median)
CURVES = HERE / "data" / "cao2008_picture_frame_curves.csv"
#: the measured curves are read by fabmd's locking method on straight lines between their
#: digitised points, sampled this finely [deg] (the method fits over 5° windows)
CURVE_STEP_DEG = 0.25


@dataclass(frozen=True)
class Measured:
    """One fabric's measurements: the CSV, who measured, the locking angle stated."""

    title: str
    data: Path
    sources: str
    #: the locking angle the paper states [deg]; None where it states none
    locking_deg: float | None
    locking_note: str


FABRICS = {
    # Cao et al. (2008) p. 1045: "approximately 45 deg where locking began"
    "plain": Measured("Twintex plain weave (TPEET22XXX)",
                      HERE / "data" / "cao2008_plain_weave.csv", "7 laboratories", 45.0, "≈ 45"),
    "twill": Measured("Twintex balanced 2/2 twill (TPEET44XXX)",
                      HERE / "data" / "cao2008_balanced_twill.csv",
                      "4 curves (UML, UT, KUL 1st / 3rd run)", None, "not stated"),
}

def _data_rows(path: Path) -> csv.DictReader:
    """The rows of one of ``benchmarks/data``'s CSV files (its ``#`` header lines left out)."""
    return csv.DictReader(line for line in path.read_text().splitlines()
                          if not line.startswith("#"))


def measured(test: str = "picture_frame", fabric: str = "plain") -> dict[int, dict[str, float]]:
    """Per angle: min, max, median F_norm [N/mm] of the laboratories (the fabric's CSV)."""
    out = {}
    for row in _data_rows(FABRICS[fabric].data):
        if row["test"] == test:
            out[int(row["angle_deg"])] = {k: float(row[k]) for k in
                                          ("min_n_mm", "max_n_mm", "median_n_mm")}
    return out


def measured_curves(fabric: str = "plain") -> dict[str, tuple[list[float], list[float]]]:
    """Each laboratory's picture-frame curve of ``fabric``: source → (angles [deg],
    F_norm [N/mm]), in the order of the CSV."""
    out: dict[str, tuple[list[float], list[float]]] = {}
    for row in _data_rows(CURVES):
        if row["fabric"] == fabric:
            angles, forces = out.setdefault(row["source"], ([], []))
            angles.append(float(row["angle_deg"]))
            forces.append(float(row["f_norm_n_mm"]))
    return out


def measured_locking(fabric: str = "plain") -> dict[str, dict]:
    """fabmd's locking method (:func:`fabmd.results.curves.locking_angle`, its defaults)
    on each laboratory's curve, read on straight lines between the digitised points every
    :data:`CURVE_STEP_DEG`: source → ``{"deg": angle or None, "ends_deg": where the curve
    ends, "reason": why none}``. The same method as the simulated rows' locking angle, so
    the two compare like with like (the paper's "≈ 45°" is where the force "begins to
    increase significantly", read by eye)."""
    import numpy as np

    from fabmd.results.curves import locking_angle

    out = {}
    for source, (angles, forces) in measured_curves(fabric).items():
        x = np.arange(angles[0], angles[-1] + 1e-9, CURVE_STEP_DEG)
        found = locking_angle(x, np.interp(x, angles, forces))
        out[source] = {"deg": found["x"] if found["found"] else None,
                       "ends_deg": angles[-1], "reason": found["reason"]}
    return out


def locking_line(fabric: str = "plain") -> str:
    """One sentence: the measured curves' locking angles by fabmd's method."""
    locks = measured_locking(fabric)
    hit = {s: r["deg"] for s, r in locks.items() if r["deg"] is not None}
    miss = [f"{s} (ends at {r['ends_deg']:g}°)" for s, r in locks.items() if r["deg"] is None]
    text = ("fabmd's locking method (`fabmd.results.curves.locking_angle`, as for the "
            "simulated rows) on each measured curve, read on straight lines between its "
            "5° points: ")
    text += ", ".join(f"{s} {d:.1f}°" for s, d in hit.items()) if hit else "none found"
    if miss:
        text += "; no departure confirmed before the curve ends: " + ", ".join(miss)
    return text + "."


def picture_frame_record(folder: Path) -> dict:
    """What the comparison needs from a finished picture-frame folder."""
    folder = Path(folder)
    path = folder / "picture_frame" / "summary.json"  # a `fabmd test` folder
    if not path.exists():
        path = folder / "summary.json"
    s = json.loads(path.read_text())
    forces = s.get("normalised_force_at_angle_n_m", {})
    intervals = s.get("quasi_static_intervals", {})
    return {
        "folder": str(path.parent),
        "f_norm_n_mm": {str(a): (forces[str(a)] / 1e3 if str(a) in forces else None)
                        for a in ANGLES},
        "locking_angle_deg": s.get("locking_angle_deg"),
        "flagged_deg": intervals.get("flagged", []),
        "n_beads": s.get("n_beads"),
        "wall_s": s.get("wall_s"),
    }


def run_scene(scene_path: Path, out: Path, compaction: bool) -> dict:
    """Crimp the cell, shear it in the picture frame, optionally compact it."""
    from fabmd.pipeline import run_crimp, run_test
    from fabmd.scenefile import load_scene

    scene = load_scene(scene_path)
    t0 = time.perf_counter()
    crimp = run_crimp(scene, out / "crimp", form="cell")
    weave = scene.fabric.architecture
    rec = {"scene": str(scene_path), "title": scene.title,
           "fabric": "twill" if getattr(weave, "name", "").startswith("twill") else "plain",
           "crimp": {k: crimp.summary.get(k) for k in ("wall_s",)},
           "crimp_tension": crimp.summary.get("tension", {}).get("per_family")}
    run_test(scene, "picture-frame", out / "pf", crimped=out / "crimp")
    rec["picture_frame"] = picture_frame_record(out / "pf")
    if compaction:
        s = run_test(scene, "compaction", out / "compaction", crimped=out / "crimp")
        comp = s.get("compaction", s)
        rec["compaction"] = {k: comp.get(k) for k in comp if "thickness" in k}
    rec["wall_s"] = time.perf_counter() - t0
    return rec


def section(store: dict) -> str:
    """The RESULTS.md section: per fabric, one row per variant, its measured ranges beside."""
    runs = {k: v for k, v in store.items() if not k.startswith("_")}
    parts = []
    for key, fabric in FABRICS.items():
        mine = {k: v for k, v in runs.items() if v.get("fabric", "plain") == key}
        reading = store.get("_reading" if key == "plain" else f"_reading_{key}")
        parts.append(f"### {fabric.title}\n\n" + _fabric_tables(key, mine, reading))
    return "\n\n".join(parts)


def _fabric_tables(key: str, runs: dict, reading: str | None) -> str:
    """One fabric's tables: measured and simulated F_norm, ratios, notes, reading."""
    fabric = FABRICS[key]
    ref = measured(fabric=key)
    header = ["model"] + [f"F_norm {a}° [N/mm]" for a in ANGLES] + [
        "locking [°]", "flagged intervals", "beads", "wall [s]"]
    rows = [[f"measured, {fabric.sources}: min – max (median)"]
            + [f"{ref[a]['min_n_mm']:.3f} – {ref[a]['max_n_mm']:.3f} "
               f"({ref[a]['median_n_mm']:.3f})" for a in ANGLES]
            + [fabric.locking_note, "—", "—", "—"]]
    ratio_rows = []
    for label, rec in runs.items():
        pf = rec["picture_frame"]
        vals = [pf["f_norm_n_mm"].get(str(a)) for a in ANGLES]
        rows.append([label] + [("—" if v is None else f"{v:.3g}") for v in vals]
                    + [f"{pf['locking_angle_deg']:.1f}" if pf.get("locking_angle_deg")
                       else "—",
                       ", ".join(f"{a:g}–{b:g}°" for a, b in pf["flagged_deg"]) or "none",
                       pf.get("n_beads") or "—",
                       f"{pf['wall_s']:.0f}" if pf.get("wall_s") else "—"])
        ratio_rows.append([label] + [
            ("—" if v is None else f"{v / ref[a]['median_n_mm']:.3g}")
            + ("" if v is None or ref[a]["min_n_mm"] <= v <= ref[a]["max_n_mm"]
               else " (outside)") for a, v in zip(ANGLES, vals, strict=True)])
    text = table(header, rows) + "\n\n" + locking_line(key)
    if ratio_rows:
        text += "\n\nSimulated over the measured median " \
            "(\"outside\": beyond the laboratories' range):\n\n"
        text += table(["model"] + [f"{a}°" for a in ANGLES], ratio_rows)
    notes = [f"- **{label}**: {rec['note']}" for label, rec in runs.items()
             if rec.get("note")]
    if notes:
        text += "\n\n" + "\n".join(notes)
    if reading:
        text += "\n\n" + reading
    return text


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", type=Path, action="append", default=[],
                   help="scene to crimp and test (repeatable)")
    p.add_argument("--out", type=Path, help="folder for the runs of --scene")
    p.add_argument("--compaction", action="store_true",
                   help="also press the crimped cell to its datasheet pressure")
    p.add_argument("--from", dest="folder", type=Path,
                   help="a finished picture-frame folder to add (with --label)")
    p.add_argument("--label", help="row label (default: the scene's title)")
    p.add_argument("--note", default="", help="one line on how the row was made")
    p.add_argument("--fabric", choices=sorted(FABRICS),
                   help="the measurements a --from folder is compared with (default plain; "
                        "a --scene's weave decides for it)")
    p.add_argument("--reading", help="the fabric's closing paragraph (kept in the store)")
    p.add_argument("--write", action="store_true", help="write the RESULTS.md section")
    args = p.parse_args(argv)

    store = json.loads(STORE.read_text()) if STORE.exists() else {}
    fabric = args.fabric or "plain"
    if args.reading:
        store["_reading" if fabric == "plain" else f"_reading_{fabric}"] = args.reading
    if args.folder:
        rec = {"picture_frame": picture_frame_record(args.folder), "note": args.note}
        if fabric != "plain":
            rec["fabric"] = fabric
        store[args.label or str(args.folder)] = rec
    for i, scene in enumerate(args.scene):
        if args.out is None:
            p.error("--scene needs --out")
        rec = run_scene(scene, args.out / f"{i}-{scene.stem}", args.compaction)
        rec["note"] = args.note
        if args.fabric:
            rec["fabric"] = args.fabric
        store[args.label or rec["title"]] = rec
    STORE.write_text(json.dumps(store, indent=1) + "\n")
    text = section(store)
    print(text)
    if args.write:
        update_section("Validation", text, "python benchmarks/validation.py --write")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
