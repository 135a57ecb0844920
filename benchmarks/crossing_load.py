"""Load, slip and friction power of the warp–weft crossings in a picture-frame run.

    python benchmarks/crossing_load.py LABEL=RUN/picture_frame [LABEL=...] --out DIR
        [--max-deg 36] [--every 40]

Re-runs each picture-frame folder (its ``in.picture_frame`` up to the loading run, verbatim,
without the trajectory dumps), then runs the loading in chunks of ``--every`` steps and
samples every bead pair of different fibre families in contact (``compute pair/local``
of the granular style: normal force, tangential force, centre vector; velocities from
the atoms: the beads do not rotate, ``fix nve``):

* N = Σ|F_n| [N], the crossings' load;
* P = −Σ F_t·v_t [W], the power the tangential forces take from the slip (friction, and
  the tangential springs' elastic rate);
* W = Σ|F_n|·|v_t|: W/N is the load-weighted slip speed [m/s], P/W the friction
  coefficient the slipping crossings work at (μ when all slide);
* the mean bond tension of all fibres [N] (``compute bond/local force``).

Per 5° interval of shear the table gives the means of the samples. Question it answers
(benchmarks/RESULTS.md "Crossing friction: where the coarse excess comes from"): does a
coarse bead chain dissipate more at the crossings because it presses harder, slips
further, or slides at a higher friction coefficient? Needs the split or the within-family
law contact (``pair_style granular`` for the crossing pairs).
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
from pathlib import Path

import numpy as np

from fabmd.engine.library import new_instance

#: the computes :func:`crossing_sample` reads
SAMPLING_COMMANDS = (
    "compute xl_pairs all pair/local fx fy fz p1 p2 p3 p10 p11 p12 cutoff radius",
    "compute xl_atoms all property/local patom1 patom2 cutoff radius",
    "compute xl_bonds all bond/local force",
    "compute xl_tension all reduce ave c_xl_bonds inputs local")
COLUMNS = ("step", "shear_deg", "pairs", "normal_n", "friction_power_w", "slip_load_w",
           "bond_tension_n")


def crossing_sample(lmp) -> dict[str, float]:
    """One sample of the crossing pairs (module docstring)."""
    f = np.array(lmp.numpy.extract_compute("xl_pairs", 2, 2), copy=True).reshape(-1, 9)
    a = np.array(lmp.numpy.extract_compute("xl_atoms", 2, 2), copy=True).astype(int)
    a = a.reshape(-1, 2)
    ids, typ, v = (lmp.numpy.extract_atom(k) for k in ("id", "type", "v"))
    index = np.empty(ids.max() + 1, dtype=int)
    index[ids] = np.arange(len(ids))
    i, j = index[a[:, 0]], index[a[:, 1]]
    cross = typ[i] != typ[j]
    fn = np.linalg.norm(f[cross, 0:3], axis=1)
    n = f[cross, 6:9] / np.linalg.norm(f[cross, 6:9], axis=1)[:, None]
    vr = v[i[cross]] - v[j[cross]]
    vt = vr - np.sum(vr * n, axis=1)[:, None] * n
    return {"pairs": int(cross.sum()), "normal_n": float(fn.sum()),
            "friction_power_w": -float(np.sum(f[cross, 3:6] * vt)),
            "slip_load_w": float(np.sum(fn * np.linalg.norm(vt, axis=1))),
            "bond_tension_n": -float(lmp.extract_compute("xl_tension", 0, 0))}


def sample_run(folder: Path, out: Path, max_deg: float, every: int) -> list[dict]:
    """Re-run ``folder`` in ``out`` and sample the crossings every ``every`` steps up to
    ``max_deg`` of shear; writes ``out/crossings.csv``."""
    out.mkdir(parents=True, exist_ok=True)
    for name in ("in.picture_frame", "model.data", "within_family.table"):
        if (folder / name).exists():
            shutil.copy(folder / name, out / name)
    lines = (out / "in.picture_frame").read_text().splitlines()
    load = [k for k, s in enumerate(lines) if s.startswith("run ")][-2]  # last: "run 0"
    total = int(lines[load].split()[1])
    cwd = os.getcwd()
    os.chdir(out)
    try:
        lmp = new_instance(["-log", "log.lammps", "-screen", "none"])
        lmp.commands_list([s for s in lines[:load] if not s.startswith("dump")])
        lmp.commands_list([*SAMPLING_COMMANDS, "run 0 post no"])
        rows, step = [], 0
        while step < total:
            lmp.command(f"run {every} pre no post no")
            step += every
            rows.append({"step": step, "shear_deg": lmp.extract_variable("shear_deg"),
                         **crossing_sample(lmp)})
            if rows[-1]["shear_deg"] > max_deg:
                break
        lmp.close()
    finally:
        os.chdir(cwd)
    with open(out / "crossings.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return rows


def interval_table(runs: dict[str, list[dict]], width_deg: float = 5.0,
                   up_to_deg: float = 35.0) -> str:
    """Markdown table of the interval means of every run (module docstring)."""
    lines = ["| run | shear [°] | pairs | N [N] | P [W] | slip W/N [m/s] | P/W | "
             "bond tension [N] |", "|---|---|---|---|---|---|---|---|"]
    lo = width_deg
    while lo < up_to_deg:
        for label, rows in runs.items():
            m = [r for r in rows if lo <= r["shear_deg"] < lo + width_deg]
            if not m:
                continue
            mean = {k: float(np.mean([r[k] for r in m])) for k in COLUMNS}
            lines.append(
                f"| {label} | {lo:g}–{lo + width_deg:g} | {mean['pairs']:.0f} | "
                f"{mean['normal_n']:.4g} | {mean['friction_power_w']:.4g} | "
                f"{mean['slip_load_w'] / mean['normal_n']:.4g} | "
                f"{mean['friction_power_w'] / mean['slip_load_w']:.3f} | "
                f"{mean['bond_tension_n']:.3g} |")
        lo += width_deg
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", metavar="LABEL=FOLDER",
                        help="picture_frame folders of finished runs")
    parser.add_argument("--out", type=Path, required=True, help="folder for the re-runs")
    parser.add_argument("--max-deg", type=float, default=36.0)
    parser.add_argument("--every", type=int, default=40, help="steps between samples")
    args = parser.parse_args()
    runs = {}
    for item in args.runs:
        label, _, folder = item.partition("=")
        runs[label] = sample_run(Path(folder).resolve(), args.out.resolve() / label,
                                 args.max_deg, args.every)
    print(interval_table(runs))


if __name__ == "__main__":
    main()
