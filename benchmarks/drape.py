"""Drape benchmark: quarter against full model, 1 against 7 virtual fibres per yarn.

Runs the hemispherical-punch drape of the example fabric (``examples/drape.toml``: the
yarns of the 3D example in a loose plain weave, 4 mm spacing) on a reduced case (smaller
punch and blank, so that every variant runs in minutes) and prints, per variant, the
beads, steps, run time, punch force (largest, and the mean over the last 5 % of the
depth), the largest shear angle, the draw-in along the warp, the mean inertial force over
the mean punch force and the holder-force error, with the relative differences to the
first variant. A variant ``quarter:1:0.5`` runs at half the punch speed (rate check),
``quarter:1:1:all`` gives punch and die contact to every bead instead of only to those that
can reach the tools (the skip's cost ratio; the results must not change).

    python benchmarks/drape.py [--radius-mm 15] [--depth-mm 9] [--blank-mm 80]
                               [--variants quarter:1 full:1 quarter:1:0.5 full:1:0.5
                                quarter:1:0.25 quarter:1:1:all quarter:7] [--write]
                               [--section NAME]   # ~14 min with the default variants
"""

from __future__ import annotations

import argparse
import copy
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import table, update_section  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.pipeline import crimp_stage, periodic_cell, protocol_stage  # noqa: E402
from fabmd.protocols.coupon import Coupon  # noqa: E402
from fabmd.scene.outputs import TrajectoryOutput  # noqa: E402
from fabmd.scenefile import load_scene  # noqa: E402

SCENE = Path(__file__).resolve().parents[1] / "examples" / "drape.toml"


def scene_with(fibres: int):
    """The example scene with ``fibres`` virtual fibres per yarn."""
    scene = load_scene(SCENE)
    if fibres != 1:
        import dataclasses

        fabric = scene.fabric
        scene.fabric = dataclasses.replace(
            fabric, warp=dataclasses.replace(fabric.warp, n_fibres=fibres),
            weft=dataclasses.replace(fabric.weft, n_fibres=fibres))
    return scene


def run_variant(symmetry: str, fibres: int, speed: float, args, root: Path,
                zones: bool = True) -> dict:
    scene = scene_with(fibres)
    engine = Engine(progress=False)
    crimped = crimp_stage(scene).run(periodic_cell(scene), root / f"crimp{fibres}",
                                     engine=engine, overwrite=True).model
    blank = Coupon(length_m=args.blank_mm * 1e-3, width_m=args.blank_mm * 1e-3,
                   relax=None).geometry(crimped)
    table_ = copy.deepcopy(scene.protocols.get("drape", {}))
    table_.pop("coupon", None)
    table_.update(punch_radius_m=args.radius_mm * 1e-3, depth_m=args.depth_mm * 1e-3,
                  die_clearance_m=args.clearance_mm * 1e-3, holder_force_n=args.holder_n,
                  symmetry=symmetry)
    scene.protocols["drape"] = table_
    drape = protocol_stage(scene, "drape")
    import dataclasses

    drape = dataclasses.replace(drape, trajectory=TrajectoryOutput(frames=0),
                                speed_fraction=drape.speed_fraction * speed, tool_zones=zones)
    t0 = time.perf_counter()
    result = drape.run(blank, root / f"{symmetry}{fibres}-{speed:g}{'' if zones else '-all'}",
                       engine=engine,
                       overwrite=True)
    wall = time.perf_counter() - t0
    s = result.summary
    label = f"{symmetry}, {fibres} fibre{'s' if fibres > 1 else ''}/yarn"
    if speed != 1.0:
        label += f", {speed:g} x speed"
    if not zones:
        label += ", tool contact for every bead"
    return {"variant": label,
            "beads": s["n_beads"], "steps": s["steps"] + (s["clamp_steps"] or 0),
            "wall_s": wall, "max_force_n": s["max_punch_force_n"],
            "final_force_n": s["final_punch_force_n"], "max_shear_deg": s["max_shear_angle_deg"],
            "draw_in_warp_mm": 1e3 * (s["draw_in"]["warp_m"] or 0.0),
            "ke_ratio": s["max_kinetic_to_external_work"],
            "holder_error": s["holder_force"]["max_relative_error"],
            "inertia": s["inertia"]["mean_inertial_force_n"] / s["inertia"]["mean_punch_force_n"],
            "max_overlap": s.get("max_overlap_ratio")}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--radius-mm", type=float, default=15.0)
    p.add_argument("--depth-mm", type=float, default=9.0)
    p.add_argument("--clearance-mm", type=float, default=3.0)
    p.add_argument("--blank-mm", type=float, default=80.0)
    p.add_argument("--holder-n", type=float, default=40.0)
    p.add_argument("--variants", nargs="+",
                   default=["quarter:1", "full:1", "quarter:1:0.5", "full:1:0.5",
                            "quarter:1:0.25", "quarter:1:1:all", "quarter:7"],
                   help="symmetry:fibres per yarn[:speed factor[:all]] (all: tool contact "
                        "for every bead, not only near the tools)")
    p.add_argument("--out", type=Path, default=None, help="keep the run folders here")
    p.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    p.add_argument("--section", default="Drape",
                   help="RESULTS.md section to write (one per case)")
    args = p.parse_args(argv)
    root = args.out or Path(tempfile.mkdtemp(prefix="drape-bench-"))
    rows = []
    for v in args.variants:
        parts = v.split(":")
        speed = float(parts[2]) if len(parts) > 2 else 1.0
        zones = not (len(parts) > 3 and parts[3] == "all")
        rows.append(run_variant(parts[0], int(parts[1]), speed, args, root, zones))
        print(rows[-1], flush=True)
    ref = rows[0]

    def rel(a, b):
        return abs(a - b) / abs(b) if b else float("nan")

    header = ["variant", "beads", "steps", "wall [s]", "max force [N]", "final force [N]",
              "max shear [°]", "draw-in warp [mm]", "inertia/punch", "holder error",
              "Δ final force", "Δ max shear"]
    body = [[r["variant"], r["beads"], r["steps"], r["wall_s"], r["max_force_n"],
             r["final_force_n"], r["max_shear_deg"], r["draw_in_warp_mm"], r["inertia"],
             r["holder_error"], rel(r["final_force_n"], ref["final_force_n"]),
             rel(r["max_shear_deg"], ref["max_shear_deg"])] for r in rows]
    text = table(header, body)
    print(text)
    if args.write:
        given = list(argv or sys.argv[1:])
        if "--out" in given:  # where the run folders went is not part of the recipe
            i = given.index("--out")
            del given[i:i + 2]
        command = "python benchmarks/drape.py " + " ".join(given)
        note = (f"Punch R = {args.radius_mm:g} mm, depth {args.depth_mm:g} mm, clearance "
                f"{args.clearance_mm:g} mm, blank {args.blank_mm:g} mm square, holder "
                f"{args.holder_n:g} N; the example's yarns, contact, modulus scale and punch "
                f"speed. Differences are relative to the first row.\n\n")
        update_section(args.section, note + text, command.strip())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
