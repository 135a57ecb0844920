"""What writing a trajectory costs: run time with and without it, and the file sizes.

Two ways to use it::

    # a synthetic plain-weave sheet with contact (default ~30 000 beads)
    python benchmarks/trajectory_cost.py --yarns 8 --steps 10000 --frames 50

    # a finished run folder (e.g. the plain-weave crimp): its input is run twice,
    # as it is and with the trajectory block taken out (or put in, if it has none)
    python benchmarks/trajectory_cost.py --run-dir runs/crimp --frames 100

Cost = (run with trajectory + conversion to trajectory.h5 and ParaView files
− run without) / run without. The target is < 10 %. Times are CPU seconds of
this process (and of its children for the standalone back end), so other jobs
on a shared machine disturb them little; wall times are printed too. Each
variant runs ``--repeat`` times and the fastest counts. LAMMPS's own "Output"
share of the loop time is read from the logs.
"""

from __future__ import annotations

import argparse
import json
import re
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

from fabmd.engine import Engine
from fabmd.engine.script import logical_lines, total_run_steps
from fabmd.model.bead_model import BeadModel
from fabmd.results.trajectory import finalise
from fabmd.scene.outputs import TrajectoryOutput

BOLTZMANN = 1.380649e-23
BEGIN, END = "# >>> fabmd trajectory", "# <<< fabmd trajectory"


def sheet_input(model: BeadModel, steps: int, trajectory: TrajectoryOutput) -> str:
    """Free motion of a sheet with fibre-fibre contact from a small random kick."""
    from fabmd.model.beads import bead_parameters
    from fabmd.model.contact import ContactModel
    from fabmd.model.material import GLASS, VirtualFibre
    from fabmd.protocols.common import DATA_FILE
    from fabmd.scene import blocks
    from fabmd.scene.templates import render

    beads = [bead_parameters(VirtualFibre.solid(GLASS, float(model.diameters[0])))]
    contact = ContactModel()
    dt = 0.25 * beads[0].critical_time_step_s(contact.normal_stiffness_n_per_m(beads))
    temperature = float(model.masses.mean()) * 0.5**2 / BOLTZMANN
    return "\n".join([
        blocks.setup(model, "sheet", DATA_FILE, dt), blocks.bonds(model),
        blocks.contact(model, contact, beads), "fix             integrate all nve",
        f"velocity        all create {temperature:.6g} 4928 dist gaussian loop geom",
        blocks.guards(model, dt), trajectory.commands(steps), render("run", steps=steps),
        trajectory.final_commands(), render("finish", final_data="final.data")])


def without_trajectory(text: str) -> str:
    """The input with every fabmd trajectory block removed."""
    return re.sub(rf"{re.escape(BEGIN)}.*?{re.escape(END)}\n?", "", text, flags=re.S)


def with_trajectory(text: str, trajectory: TrajectoryOutput) -> str:
    """The input with a trajectory block (kept if it has one; else put before the first
    run and its final frame after the last)."""
    if BEGIN in text:
        return text
    steps = total_run_steps(logical_lines(text))
    lines = text.splitlines()
    runs = [i for i, line in enumerate(lines) if re.match(r"^\s*run\s+\d+", line)]
    if not runs:
        raise SystemExit("the input has no run command")
    lines.insert(runs[-1] + 1, trajectory.final_commands())
    lines.insert(runs[0], trajectory.commands(steps))
    return "\n".join(lines) + "\n"


def prepare(source: Path, name: str, text: str, dest: Path) -> Path:
    """A fresh copy of the run folder's inputs with ``text`` as the input."""
    dest.mkdir(parents=True)
    for f in source.iterdir():
        if f.suffix in (".data", ".json") and f.stem in ("model",):
            shutil.copy(f, dest / f.name)
    (dest / name).write_text(text)
    return dest


def cpu_seconds() -> float:
    """CPU time of this process and its finished children [s]."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + children.ru_utime + children.ru_stime


def timed(action) -> tuple[float, float]:
    """(CPU, wall) seconds of ``action()``."""
    c0, w0 = cpu_seconds(), time.perf_counter()
    action()
    return cpu_seconds() - c0, time.perf_counter() - w0


def steps_run(log: Path) -> int | None:
    """Steps LAMMPS ran (a run stopped early by fix halt counts what it did)."""
    found = re.findall(r"^Loop time of \S+ on \d+ procs for (\d+) steps", log.read_text(
        errors="replace"), flags=re.M)
    return sum(int(n) for n in found) if found else None


def output_seconds(log: Path) -> float:
    """Time LAMMPS spent in output (dumps, thermo), summed over the runs of a log [s]."""
    total = 0.0
    for line in log.read_text(errors="replace").splitlines():
        if line.startswith("Output  "):
            total += float(line.split("|")[2])  # the "avg time" column
    return total


def measure(source: Path, name: str, text: str, trajectory: TrajectoryOutput, repeat: int,
            engine: Engine, work: Path) -> dict:
    plain = without_trajectory(text)
    full = with_trajectory(text, trajectory)
    from fabmd.engine.library import new_instance

    new_instance().close()  # load the LAMMPS library before timing anything
    runs: dict[str, list[tuple[float, float]]] = {"without": [], "with": [], "convert": []}
    output = {"without": 0.0, "with": 0.0}
    report: dict = {}
    for k in range(repeat):
        a = prepare(source, name, plain, work / f"without-{k}")
        runs["without"].append(timed(lambda a=a: engine.run(a, name)))
        b = prepare(source, name, full, work / f"with-{k}")
        runs["with"].append(timed(lambda b=b: engine.run(b, name)))
        runs["convert"].append(timed(lambda b=b: finalise(b, paraview=trajectory.paraview)))
        report = json.loads((b / "trajectory.json").read_text())
        output = {"without": output_seconds(a / "log.lammps"),
                  "with": output_seconds(b / "log.lammps")}
    best = {key: (min(c for c, _ in v), min(w for _, w in v)) for key, v in runs.items()}
    (plain_cpu, plain_wall), (full_cpu, full_wall) = best["without"], best["with"]
    convert_cpu, convert_wall = best["convert"]
    steps = steps_run(a / "log.lammps") or total_run_steps(logical_lines(full))
    frames = max(1, report["frames"])
    return {
        "beads": report["n_beads"], "bonds": report["n_bonds"], "steps": steps,
        "frames": report["frames"],
        "run_without_cpu_s": plain_cpu, "run_with_cpu_s": full_cpu, "convert_cpu_s": convert_cpu,
        "run_without_wall_s": plain_wall, "run_with_wall_s": full_wall,
        "convert_wall_s": convert_wall,
        "lammps_output_s": output,
        "dump_mb": report["dump_bytes"] / 1e6,
        "trajectory_h5_mb": report["trajectory_bytes"] / 1e6,
        "paraview_mb": report.get("paraview_bytes", 0) / 1e6,
        "lammps_cost": (full_cpu - plain_cpu) / plain_cpu,
        "total_cost": (full_cpu + convert_cpu - plain_cpu) / plain_cpu,
        "total_cost_wall": (full_wall + convert_wall - plain_wall) / plain_wall,
        # less noisy: LAMMPS's own output time (dumps and the computes they call) + conversion
        "output_cost": (output["with"] - output["without"] + convert_cpu) / plain_cpu,
        # what one frame costs, in time steps of this scene: frames x this / steps = cost
        "frame_cost_steps": (full_cpu + convert_cpu - plain_cpu) / frames
        / (plain_cpu / max(1, steps)),
        "all_runs_cpu_wall_s": runs,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--run-dir", type=Path, help="a finished run folder to measure")
    p.add_argument("--yarns", type=int, default=8, help="warp (= weft) yarns of the sheet")
    p.add_argument("--fibres", default="3x2", help="fibres per yarn, across x through")
    p.add_argument("--steps", type=int, default=10000, help="steps of the sheet run")
    p.add_argument("--frames", type=int, default=50, help="trajectory frames")
    p.add_argument("--velocities", action="store_true", help="store velocities too")
    p.add_argument("--no-paraview", action="store_true", help="skip the ParaView files")
    p.add_argument("--repeat", type=int, default=1, help="runs per variant (fastest counts)")
    p.add_argument("--np", type=int, default=1, dest="ranks",
                   help="MPI ranks (standalone lmp back end when > 1)")
    p.add_argument("--threads", type=int, default=1, help="OpenMP threads")
    p.add_argument("--keep", type=Path, help="keep the run folders here")
    p.add_argument("--json", type=Path, help="also write the result as JSON")
    args = p.parse_args(argv)

    trajectory = TrajectoryOutput(frames=args.frames, velocities=args.velocities,
                                  paraview=not args.no_paraview)
    engine = Engine(backend="standalone" if args.ranks > 1 else "inprocess",
                    ranks=args.ranks, threads=args.threads, progress=False)
    work = Path(tempfile.mkdtemp(prefix="fabmd-bench-")) if args.keep is None else args.keep
    try:
        if args.run_dir is not None:
            source = args.run_dir
            inputs = sorted(source.glob("in.*"))
            if not inputs or not (source / "model.data").exists():
                raise SystemExit(f"{source} has no in.<protocol> or model.data")
            name = inputs[0].name
            text = inputs[0].read_text()
            scene = f"run folder {source}"
        else:
            from fabmd.analysis.synthetic import woven_sheet

            across, through = (int(v) for v in args.fibres.split("x"))
            model = woven_sheet(warp_yarns=args.yarns, weft_yarns=args.yarns,
                                fibres=(across, through))
            source = work / "model"
            model.save(source)
            name = "in.sheet"
            text = sheet_input(model, args.steps, trajectory)
            scene = (f"synthetic plain weave {args.yarns}x{args.yarns} yarns of "
                     f"{across}x{through} fibres, contact on")
        result = measure(source, name, text, trajectory, args.repeat, engine, work)
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    result.update(scene=scene, ranks=args.ranks, threads=args.threads)
    print(f"{scene}: {result['beads']} beads, {result['steps']} steps, "
          f"{result['frames']} frames")
    out = result["lammps_output_s"]
    print(f"  run without trajectory  {result['run_without_cpu_s']:8.2f} s CPU "
          f"({result['run_without_wall_s']:.2f} s wall)")
    print(f"  run with trajectory     {result['run_with_cpu_s']:8.2f} s CPU "
          f"({result['run_with_wall_s']:.2f} s wall; LAMMPS output "
          f"{out['with']:.2f} s vs {out['without']:.2f} s)")
    print(f"  conversion (h5 + VTU)   {result['convert_cpu_s']:8.2f} s CPU "
          f"({result['convert_wall_s']:.2f} s wall)")
    print(f"  total cost              {100 * result['total_cost']:8.1f} % of the run's CPU time "
          f"({'within' if result['total_cost'] < 0.10 else 'ABOVE'} the 10 % target; "
          f"wall: {100 * result['total_cost_wall']:.1f} %)")
    print(f"  LAMMPS output + conversion {100 * result['output_cost']:5.1f} % of the run "
          f"(the same, less disturbed by other jobs)")
    print(f"  one frame costs as much as {result['frame_cost_steps']:.0f} time steps "
          f"(keep steps per frame above {10 * result['frame_cost_steps']:.0f} for < 10 %)")
    print(f"  sizes: dumps {result['dump_mb']:.1f} MB, trajectory.h5 "
          f"{result['trajectory_h5_mb']:.1f} MB, ParaView {result['paraview_mb']:.1f} MB")
    if args.json:
        args.json.write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
