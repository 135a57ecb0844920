"""Ranks: where a second MPI rank pays, and the demo on the default choice against one rank.

* break-even: the same fixed-step input (beads, bonds, contact, guards) on coupons of
  growing size, run by ``lmp -in`` on 1 and on 2 ranks back to back; wall time of the
  whole process and LAMMPS's loop time. ``fabmd.engine.ranks.MIN_BEADS_PER_RANK`` is
  set from where 2 ranks start to win;
* demo: ``fabmd demo [--fast] --out DIR`` with the default choice of ranks against
  ``--np 1``, back to back, with the output numbers of both: single fibres agree to
  1e-6 on any number of ranks (the suite's MPI tolerance), runs with many contacts differ
  by round-off grown chaotically (README "Validation": ~1 % on a relaxed coupon's tension).

    python benchmarks/ranks.py [--quick] [--repeat N] [--demo fast|full|none] [--write]

The machine may be shared: each pair runs back to back so that both see the same load.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import machine, table, update_section  # noqa: E402
from engine import ROOT, coupon, crimped_cell, fixed_steps_input, loop_time  # noqa: E402

from fabmd.engine.standalone import run_standalone  # noqa: E402
from fabmd.protocols.common import input_name, write_run_folder  # noqa: E402

#: the demo's numbers compared between the two runs (summary.json keys)
DEMO_NUMBERS = (("tension", "initial_stiffness_n_m_per_width"),
                ("tension", "final_stiffness_n_m_per_width"),
                ("tension", "transition_elongation_pct"),
                ("picture_frame", "locking_angle_deg"),
                ("picture_frame", "max_normalised_force_n_m"))


def break_even(sizes, steps: int, repeat: int = 1) -> list[list]:
    """1 against 2 ranks on the fixed-step input, per coupon size (best of ``repeat``
    back-to-back pairs)."""
    cell = crimped_cell()
    rows = []
    for nx, ny in sizes:
        model = coupon(cell, nx, ny)
        folder = write_run_folder(ROOT / f"ranks-{nx}x{ny}", "scaling", model,
                                  fixed_steps_input(model, steps), {}, overwrite=True)
        best = {1: (float("inf"), float("inf")), 2: (float("inf"), float("inf"))}
        for _ in range(repeat):
            for ranks in (1, 2):
                t0 = time.perf_counter()
                run_standalone(folder, input_name("scaling"), ranks=ranks)
                wall = time.perf_counter() - t0
                best[ranks] = (min(best[ranks][0], wall),
                               min(best[ranks][1], loop_time(folder / "log.lammps")))
        (w1, l1), (w2, l2) = best[1], best[2]
        rows.append([f"{nx} x {ny} cells", model.n_beads, model.n_beads // 2, steps,
                     w1, w2, w1 / w2, l1 / l2])
    return rows


def fabmd_demo(out: Path, preset: str, np_option: list[str]) -> tuple[float, dict]:
    """Wall time [s] and summary of one ``fabmd demo`` (its own process)."""
    cmd = [sys.executable, "-m", "fabmd", "demo", "--out", str(out), "--quiet", *np_option]
    if preset != "default":
        cmd.insert(4, f"--{preset}")
    env = {k: v for k, v in os.environ.items() if k != "FABMD_NP"}
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}):\n{done.stderr[-3000:]}")
    chosen = next((line for line in done.stderr.splitlines()
                   if line.startswith("fabmd: ") and "MPI rank" in line), "")
    summary = json.loads((out / "summary.json").read_text())
    summary["chosen"] = chosen.removeprefix("fabmd: ")
    return wall, summary


def demo_runs(preset: str) -> tuple[list[list], list[list], str]:
    """The demo with the default choice and with ``--np 1``, back to back; and with one
    rank per usable core when the default chose fewer (a loaded machine)."""
    from fabmd.engine.ranks import usable_cores

    root = Path(tempfile.mkdtemp(prefix="fabmd-ranks-demo-"))
    name = "demo" if preset == "default" else f"demo --{preset}"
    auto_wall, auto = fabmd_demo(root / "auto", preset, [])
    one_wall, one = fabmd_demo(root / "one", preset, ["--np", "1"])
    times = [[f"{name}, default choice", auto["chosen"] or "1 rank (no line)", auto_wall,
              one_wall / auto_wall],
             [f"{name} --np 1", "1 rank", one_wall, 1.0]]
    runs = {"default choice": auto}
    cores = usable_cores()
    if f"{cores} MPI ranks" not in auto["chosen"] and cores > 1:
        all_wall, every = fabmd_demo(root / "all", preset, ["--np", str(cores)])
        times.append([f"{name} --np {cores}", f"{cores} ranks", all_wall,
                      one_wall / all_wall])
        runs[f"--np {cores}"] = every
    numbers = []
    for stage, key in DEMO_NUMBERS:
        b = one[stage].get(key)
        row = [f"{stage}.{key}", b]
        for summary in runs.values():
            a = summary[stage].get(key)
            row.append(abs(a - b) / abs(b) if isinstance(a, float) and isinstance(b, float)
                       and b else ("same" if a == b else "n/a"))
        numbers.append(row)
    header = ["number", "--np 1"] + [f"relative difference, {k}" for k in runs]
    return times, [header] + numbers, str(root)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller coupons, fewer steps")
    parser.add_argument("--repeat", type=int, default=1, help="pairs per size (best of)")
    parser.add_argument("--demo", choices=["fast", "full", "none"], default="fast",
                        help="which demo pair to run (full: the default preset, minutes)")
    parser.add_argument("--write", action="store_true", help="update RESULTS.md")
    args = parser.parse_args()
    sizes = [(2, 2), (4, 2), (8, 4)] if args.quick else [(2, 2), (4, 2), (8, 4), (8, 8),
                                                         (16, 8), (16, 16)]
    rows = break_even(sizes, 500 if args.quick else 2000, args.repeat)
    load = os.getloadavg()[0]
    body = [f"The machine is shared with other developers' jobs ({machine()}; 1-minute "
            f"load average {load:.1f} after the break-even runs): each pair ran back to "
            f"back, best of {args.repeat}.", "",
            "### Break-even: 1 against 2 MPI ranks (lmp -in, fixed-step input)", "",
            table(["coupon", "beads", "beads per rank (2)", "steps", "wall 1 rank [s]",
                   "wall 2 ranks [s]", "speed-up (wall)", "speed-up (loop)"], rows)]
    print(body[-1])
    if args.demo != "none":
        preset = "default" if args.demo == "full" else "fast"
        times, numbers, where = demo_runs(preset)
        body += ["", f"### fabmd demo{'' if preset == 'default' else ' --' + preset}: "
                 f"default choice against --np 1 (back to back)", "",
                 table(["run", "ranks", "wall [s]", "speed-up over --np 1"], times), "",
                 table(numbers[0], numbers[1:])]
        print("\n".join(body[-4:]), f"\n(run folders in {where})")
    if args.write:
        update_section("Ranks", "\n".join(body),
                       f"python benchmarks/ranks.py --demo {args.demo} --write")


if __name__ == "__main__":
    main()
