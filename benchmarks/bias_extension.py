"""Bias-extension benchmark: yarn cohesion and clamp speed on the example coupon.

Crimps the periodic cell of ``examples/plain_weave.toml`` once, cuts its 30 × 10 mm bias
coupon at 45° and relaxes it free once, then runs the bias-extension test on it for each
variant ``factor:speed`` (the yarn-cohesion factor linked into the relaxed coupon, 0 for
none; the clamp speed as a fraction of the fibre wave speed). Prints, per variant: beads,
steps, run time and its ratio to the first variant's (measured in this process), the
centre's fibre shear angle at the end against the closed-form (three-zone) angle, the
forces at 10/20/30° of closed-form shear and their change from the first variant, the
quasi-static measures (largest kinetic energy over work and over strain energy after
start-up, damping share of the work, energy-balance error) and the verdict.

    python benchmarks/bias_extension.py [--variants 0.01:1e-4 0.01:2e-4 0:2e-4 0.001:1e-4]
                                        [--write] [--section NAME]   # ~50 min, one core
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import table, update_section  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.model.cohesion import add_cohesion  # noqa: E402
from fabmd.pipeline import coupon_stage, crimp_stage, periodic_cell, protocol_stage  # noqa: E402
from fabmd.scenefile import load_scene  # noqa: E402

SCENE = Path(__file__).resolve().parents[1] / "examples" / "plain_weave.toml"


def relaxed_coupon(scene, root: Path, engine: Engine):
    """The example's bias coupon, cut from the crimped cell and relaxed free, unlinked."""
    crimped = crimp_stage(scene).run(periodic_cell(scene), root / "crimp", engine=engine,
                                     overwrite=True).model
    coupon, _ = coupon_stage(scene, "bias-extension")
    coupon = dataclasses.replace(coupon, cohesion_factor=0.0)
    return coupon.run(crimped, root / "coupon", engine=engine, overwrite=True).model


def run_variant(scene, coupon, factor: float, speed: float, root: Path,
                engine: Engine) -> dict:
    specimen = add_cohesion(coupon, factor) if factor > 0 else coupon
    test = dataclasses.replace(protocol_stage(scene, "bias-extension"), speed_fraction=speed)
    t0 = time.perf_counter()
    result = test.run(specimen, root / f"bias-{factor:g}-{speed:g}", engine=engine,
                      overwrite=True)
    wall = time.perf_counter() - t0
    s = result.summary
    qs = s["quasi_static"]["values"]
    return {"variant": f"cohesion {factor:g}, speed {speed:g}", "beads": s["n_beads"],
            "steps": s["steps"], "wall_s": wall,
            "centre_deg": s["fibre_shear_angle"]["fibres_deg"][-1],
            "kinematic_deg": s["fibre_shear_angle"]["kinematic_deg"][-1],
            "forces": [s["force_at_angle_n"].get(k) for k in ("10", "20", "30")],
            "ke_work": qs["max_kinetic_to_external_work"],
            "ke_strain": qs["max_kinetic_to_strain_energy"],
            "damping": qs["damping_share"], "balance": qs["energy_balance_error"],
            "ok": s["quasi_static"]["ok"]}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--variants", nargs="+",
                   default=["0.01:1e-4", "0.01:2e-4", "0:2e-4", "0.001:1e-4"],
                   help="cohesion factor:speed fraction; the first is the reference")
    p.add_argument("--out", type=Path, default=None, help="keep the run folders here")
    p.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    p.add_argument("--section", default="Bias extension")
    args = p.parse_args(argv)
    root = args.out or Path(tempfile.mkdtemp(prefix="bias-bench-"))
    engine = Engine(progress=False)
    scene = load_scene(SCENE)
    coupon = relaxed_coupon(scene, root, engine)
    rows = []
    for v in args.variants:
        factor, speed = (float(x) for x in v.split(":"))
        rows.append(run_variant(scene, coupon, factor, speed, root, engine))
        print(rows[-1], flush=True)
    ref = rows[0]

    def change(a, b):
        return (a - b) / abs(b) if a is not None and b else float("nan")

    header = ["variant", "beads", "steps", "wall [s]", "time / first", "centre shear [°]",
              "closed form [°]", "F at 10/20/30° [N]", "ΔF vs first (10/20/30°)",
              "KE/work", "KE/strain", "damping share", "balance error", "quasi-static"]
    body = [[r["variant"], r["beads"], r["steps"], r["wall_s"], r["wall_s"] / ref["wall_s"],
             r["centre_deg"], r["kinematic_deg"],
             " / ".join(f"{f:.3g}" for f in r["forces"] if f is not None),
             " / ".join(f"{change(f, g):+.0%}" for f, g in zip(r["forces"], ref["forces"],
                                                              strict=True)),
             r["ke_work"], r["ke_strain"], r["damping"], r["balance"],
             "yes" if r["ok"] else "no"] for r in rows]
    text = table(header, body)
    print(text)
    if args.write:
        given = [a for a in (argv or sys.argv[1:])]
        if "--out" in given:
            i = given.index("--out")
            del given[i:i + 2]
        note = ("The example's 30 × 10 mm bias coupon (11,078 beads, 7 fibres per yarn), one "
                "crimp and one free relaxation shared by all rows; the links go into the "
                "relaxed coupon. Changes are relative to the first row.\n\n")
        update_section(args.section, note + text,
                       ("python benchmarks/bias_extension.py " + " ".join(given)).strip())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
