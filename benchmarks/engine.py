"""Engine efficiency, each a ratio measured side by side in one process.

* overhead: fabmd's in-process run (chunks, progress, contact-power sampling)
  against the same input file run bare by ``lmp -in`` (target <= 1.05);
* cost against bead count (the growth exponent should be 0.9–1.15);
* 2 MPI ranks and 2 OpenMP threads against 1;
* each "skip" against not skipping it: no bending term, guard cadence, output
  cadence, neighbour skin, early stop once quasi-static.

    python benchmarks/engine.py [--quick] [--write]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _results import table, update_section  # noqa: E402
from fabrics import plain_weave_cell  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.engine.standalone import run_standalone  # noqa: E402
from fabmd.model.transform import tile  # noqa: E402
from fabmd.protocols.common import input_name, write_run_folder  # noqa: E402
from fabmd.protocols.crimp import Crimp  # noqa: E402
from fabmd.protocols.tension import Tension  # noqa: E402
from fabmd.scene.quasi_static import QuasiStatic  # noqa: E402

ROOT = Path(tempfile.mkdtemp(prefix="fabmd-engine-bench-"))
QUIET = Engine(progress=False)


def crimped_cell():
    return Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(plain_weave_cell(), ROOT / "cell",
                                                             QUIET).model


def coupon(cell, nx: int, ny: int):
    return tile(cell, nx, ny, periodic=False)


def timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def best_of(fn, repeat: int) -> float:
    return min(timed(fn) for _ in range(repeat))


def overhead(cell, repeat: int) -> list[list]:
    """Same tension input: fabmd in-process vs lmp -in."""
    model = coupon(cell, 8, 4)
    test = Tension(max_elongation_pct=2.0, speed_fraction=4e-4)
    text = test.input_text(model)
    folder = write_run_folder(ROOT / "overhead", "tension", model, text, {}, overwrite=True)
    bare = best_of(lambda: run_standalone(folder, input_name("tension")), repeat)
    inproc = best_of(lambda: QUIET.run(folder, input_name("tension")), repeat)
    monitored = best_of(lambda: test.run(model, ROOT / "overhead-full", QUIET,
                                         overwrite=True), repeat)
    return [["lmp -in (bare LAMMPS)", model.n_beads, test.steps(model), bare, 1.0],
            ["fabmd in-process, same input", model.n_beads, test.steps(model), inproc,
             inproc / bare],
            ["fabmd Tension.run (+ contact sampling, reduce, plots)", model.n_beads,
             test.steps(model), monitored, monitored / bare]]


def fixed_steps_input(model, steps: int) -> str:
    """Beads, bonds, contact, integration, guards and a fixed number of steps."""
    from fabmd.model.beads import model_bead_parameters
    from fabmd.model.contact import ContactModel
    from fabmd.scene import blocks

    beads = model_bead_parameters(model)
    contact = ContactModel()
    dt = 0.25 * min(b.critical_time_step_s(contact.stability_stiffness_n_per_m(beads))
                    for b in beads)
    return "\n".join([blocks.setup(model, "scaling", "model.data", dt), blocks.bonds(model),
                      blocks.contact(model, contact, beads),
                      "velocity all create 1e-3 4928459 dist gaussian # a little motion",
                      "fix integrate all nve", blocks.guards(model, dt), f"run {steps}"])


def loop_time(log: Path) -> float:
    """Sum of LAMMPS's 'Loop time of X on N procs' lines [s]."""
    total = 0.0
    for line in log.read_text().splitlines():
        if line.startswith("Loop time of"):
            total += float(line.split()[3])
    return total


def scaling(cell, sizes, steps: int = 2000) -> tuple[list[list], float]:
    """Cost per step against bead count: the same fixed-step input on growing coupons."""
    rows, n, t = [], [], []
    for nx, ny in sizes:
        model = coupon(cell, nx, ny)
        folder = write_run_folder(ROOT / f"scale-{nx}x{ny}", "scaling", model,
                                  fixed_steps_input(model, steps), {}, overwrite=True)
        run_standalone(folder, input_name("scaling"))
        seconds = loop_time(folder / "log.lammps")  # the time stepping alone, no start-up
        rows.append([f"{nx} x {ny} cells", model.n_beads, steps, seconds,
                     1e6 * seconds / (steps * model.n_beads)])
        n.append(model.n_beads)
        t.append(seconds / steps)
    exponent = float(np.polyfit(np.log(n), np.log(t), 1)[0])
    return rows, exponent


def parallel(cell, repeat: int) -> list[list]:
    """The fixed-step input on 2 MPI ranks and on 2 OpenMP threads against 1 (loop time)."""
    model = coupon(cell, 32, 16)
    folder = write_run_folder(ROOT / "parallel", "scaling", model,
                              fixed_steps_input(model, 2000), {}, overwrite=True)

    def loop(**kwargs) -> float:
        best = float("inf")
        for _ in range(repeat):
            run_standalone(folder, input_name("scaling"), **kwargs)
            best = min(best, loop_time(folder / "log.lammps"))
        return best

    one, mpi2, omp2 = loop(), loop(ranks=2), loop(threads=2)
    return [["1 rank, 1 thread", model.n_beads, one, 1.0],
            ["2 MPI ranks", model.n_beads, mpi2, one / mpi2],
            ["2 OpenMP threads (-sf omp)", model.n_beads, omp2, one / omp2]]


def skips(cell, repeat: int) -> list[list]:
    """Each skip against not skipping it, same scene."""
    model = coupon(cell, 8, 4)
    rows = []

    def run_text(name, text):
        folder = write_run_folder(ROOT / f"skip-{name}", "tension", model, text, {},
                                  overwrite=True)
        return best_of(lambda: run_standalone(folder, input_name("tension")), repeat)

    base_test = Tension(max_elongation_pct=1.0, speed_fraction=1e-3)
    base = base_test.input_text(model)
    t_base = run_text("base", base)
    # guards every 20 steps vs every step
    t_guard = run_text("guard1", base.replace("halt 20 ", "halt 1 "))
    rows.append(["stability guards every 20 steps (vs every step)", t_base, t_guard,
                 t_guard / t_base])
    # output every ~1/200 of the run vs every 10 steps
    every = base_test.every(model)
    dense = base.replace(f"ave/time 1 {every} {every}", "ave/time 1 10 10").replace(
        f"print {every} ", "print 10 ")
    t_dense = run_text("dense", dense)
    rows.append(["outputs every 1/200 of the run (vs every 10 steps)", t_base, t_dense,
                 t_dense / t_base])
    # neighbour skin 0.2 d vs 1.0 d
    skin = float(model.diameters.min())
    wide = base.replace(f"neighbor        {0.2 * skin:.10g} bin",
                        f"neighbor        {skin:.10g} bin")
    t_wide = run_text("skin", wide)
    rows.append(["neighbour skin 0.2 d (vs 1.0 d)", t_base, t_wide, t_wide / t_base])
    # no bending term vs angle cosine on every fibre
    bent = dataclasses.replace(model)
    from fabmd.model.bead_model import AngleType

    ends = model.fibre_ends()
    triples = [np.column_stack([np.arange(a, b - 1), np.arange(a + 1, b),
                                np.arange(a + 2, b + 1)]) for a, b in ends if b - a >= 2]
    bent.angles = np.vstack(triples)
    bent.angle_types = np.ones(len(bent.angles), np.int64)
    bt = model.bond_type_table[0]
    k_angle = 1e-6 * bt.coefficient * bt.rest_length_m**2
    bent.angle_type_table = [AngleType(k_angle, "warp")]
    folder = write_run_folder(ROOT / "skip-bending", "tension", bent,
                              base_test.input_text(bent), {}, overwrite=True)
    t_bent = best_of(lambda: run_standalone(folder, input_name("tension")), repeat)
    rows.append(["no bending term (vs angle cosine on every fibre)", t_base, t_bent,
                 t_bent / t_base])
    # early stop once quasi-static vs relaxing a fixed number of steps
    cell_loose = plain_weave_cell(cells=(2, 2))
    early = Crimp(expansion={"warp": -0.1, "weft": -0.1})
    t_early = timed(lambda: early.run(cell_loose, ROOT / "early", QUIET, overwrite=True))
    fixed = Crimp(expansion={"warp": -0.1, "weft": -0.1},
                  quasi_static=QuasiStatic(kinetic_ratio=1e-30, force_ratio=1e-30,
                                           max_steps=200_000))
    t_fixed = timed(lambda: fixed.run(cell_loose, ROOT / "fixed", QUIET, overwrite=True))
    rows.append(["crimp: stop once quasi-static (vs the full 200k-step budget)", t_early,
                 t_fixed, t_fixed / t_early])
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller sizes, one repeat")
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    args = parser.parse_args()
    repeat = 1 if args.quick else 3
    cell = crimped_cell()
    parts = []
    rows = overhead(cell, repeat)
    parts.append("### Overhead of fabmd over bare LAMMPS (same input file)\n\n" + table(
        ["run", "beads", "steps", "wall [s]", "ratio to lmp -in"], rows))
    print(parts[-1], flush=True)
    sizes = [(2, 1), (4, 2), (8, 4), (16, 8)] if args.quick else \
        [(2, 1), (4, 2), (8, 4), (16, 8), (32, 16)]
    rows, exponent = scaling(cell, sizes[1:])
    parts.append("### Cost against bead count (2000 steps with contact, lmp -in)\n\n" + table(
        ["coupon", "beads", "steps", "loop time [s]", "us per bead-step"], rows)
        + f"\n\nGrowth exponent of the cost per step with bead count: **{exponent:.3f}**"
          f" (target 0.9–1.15), fitted over {len(sizes) - 1} coupons of growing size.")
    print(parts[-1], flush=True)
    rows = parallel(cell, repeat)
    parts.append("### Parallel speed-up (2 cores, loop time of 2000 steps)\n\n" + table(
        ["run", "beads", "loop time [s]", "speed-up"], rows))
    print(parts[-1], flush=True)
    rows = skips(cell, repeat)
    parts.append("### What each skip saves (same scene)\n\n" + table(
        ["skip", "with the skip [s]", "without [s]", "cost ratio without / with"], rows))
    print(parts[-1], flush=True)
    if args.write:
        update_section("Engine efficiency", "\n\n".join(parts),
                       "python benchmarks/engine.py --write")
    print(f"(run folders in {ROOT})")


if __name__ == "__main__":
    main()
