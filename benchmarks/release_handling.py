"""What the handling tension of the release does to the tests (``[crimp] release_tension``).

Takes one finished crimp folder (its woven cell, ``crimped.data``: the state under the
weaving tension), releases that cell at each handling tension given into a copy of the
folder, and runs the scene's picture frame (and with ``--periodic`` its periodic shear) on
each; prints one table row per tension: the release (cell strain, membrane force left, crimp,
thickness, yarn width) and the tests' F_norm at their report angles and locking angle. The
woven cell is the same for every row, so what changes is the release alone.

    python benchmarks/release_handling.py SCENE CRIMP_DIR --out DIR \\
        --tensions "0.02 cN/tex" "0.05 cN/tex" "0.1 cN/tex" [--periodic] [--np N]
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
from pathlib import Path

from fabmd.engine import Engine
from fabmd.model.bead_model import BeadModel
from fabmd.pipeline import run_test, scene_of_crimp
from fabmd.protocols.crimp import RELEASE_DIR
from fabmd.scenefile import load_scene
from fabmd.stages import crimp_stage


def woven_cell(crimp_dir: Path) -> BeadModel:
    """The cell under the weaving tension that a crimp folder holds (``crimped.data``)."""
    return BeadModel.load(crimp_dir / "crimped.data", crimp_dir / "crimped.json")


def released_folder(scene, crimp_dir: Path, out: Path, tension: str, engine: Engine) -> dict:
    """A copy of ``crimp_dir`` (without its release) in ``out`` released at ``tension``;
    returns the release's summary."""
    if out.exists():
        shutil.rmtree(out)
    shutil.copytree(crimp_dir, out, ignore=shutil.ignore_patterns(RELEASE_DIR))
    release = crimp_stage(scene_of_crimp(scene, crimp_dir)).release_stage()
    release = dataclasses.replace(release, handling_tension=tension)
    return release.run(woven_cell(crimp_dir), out / RELEASE_DIR, engine=engine).summary


def test_cells(summary: dict) -> str:
    """F_norm at the report angles, locking angle and flagged intervals of one test."""
    forces = " / ".join("–" if v is None else f"{float(v):.3g}"
                        for v in summary["normalised_force_at_angle_n_m"].values())
    lock = summary.get("locking_angle_deg")
    flagged = summary["quasi_static_intervals"]["flagged"]
    return (f"{forces} | {'–' if lock is None else f'{lock:.1f}'} | "
            f"{', '.join(f'{a:g}–{b:g}°' for a, b in flagged) or 'none'}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene")
    p.add_argument("crimp_dir", type=Path)
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--tensions", nargs="+", required=True)
    p.add_argument("--periodic", action="store_true", help="run the periodic shear too")
    p.add_argument("--np", type=int, default=1, help="MPI ranks of each run")
    args = p.parse_args()
    scene = load_scene(args.scene)
    # several ranks: each run as 'mpirun -np N lmp' (this script itself runs on one)
    engine = Engine(progress=False) if args.np == 1 else \
        Engine(backend="standalone", ranks=args.np, progress=False)
    tests = ["picture-frame"] + (["periodic-shear"] if args.periodic else [])
    rows = []
    for tension in args.tensions:
        folder = args.out / tension.replace(" ", "_").replace("/", "_per_")
        rel = released_folder(scene, args.crimp_dir.resolve(), folder / "crimp", tension,
                              engine)
        cells = []
        for test in tests:
            summary = run_test(scene, test, folder / test, engine=engine, overwrite=True,
                               crimped=folder / "crimp")
            cells.append(test_cells(summary["test_summary"]))
        r = rel["released"]
        width = " / ".join(f"{1e3 * v['width_m']:.2f}" for v in r["yarn_sections"].values())
        rows.append(f"| {tension} | {rel['strain_pct'][0]:+.3f} | "
                    f"{rel['membrane_force_left_n_m'][0]:.3g} | "
                    + " / ".join(f"{v:.2f}" for v in r["crimp_pct"].values())
                    + f" | {1e3 * r['thickness_m']:.3f} | {width} | " + " | ".join(cells) + " |")
    head = ("| handling tension | cell strain x [%] | N_xx left [N/m] | crimp [%] | "
            "thickness [mm] | yarn width [mm] | "
            + " | ".join(f"{t} F_norm [N/m] | locking [°] | flagged" for t in tests) + " |")
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for row in rows:
        print(row)

if __name__ == "__main__":
    main()
