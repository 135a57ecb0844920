"""Compare picture-frame curves interval by interval (speed, bead spacing, register ...).

    python benchmarks/interval_compare.py 2e-3=RUN_A/curve.csv 1e-3=RUN_B/curve.csv

For every 5° of shear: the mean normalised force of each run [N/mm], its difference from
the *last* run named (the reference), and each run's largest per-interval measures from
its ``curve.csv`` (inertia share i, kinetic/strain energy k, drag share d; '–' where the
run's curve has no such column). A difference is the curve's, read where it was
measured, not at one report point.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

MEASURES = (("i", "interval_inertia_share"), ("k", "interval_kinetic_to_strain_energy"),
            ("d", "interval_damping_share"))


def read_curve(path: Path) -> dict[str, np.ndarray]:
    """The columns of a picture frame's ``curve.csv`` as float arrays."""
    with Path(path).open() as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) if r[k] not in ("", "nan") else np.nan for r in rows])
            for k in rows[0]}


def interval_table(runs: list[tuple[str, dict]], width_deg: float = 5.0,
                   top_deg: float = 50.0) -> list[dict]:
    """Per interval: each run's mean F_norm [N/mm], its difference from the last run and
    its largest interval measures."""
    out = []
    for lo in np.arange(0.0, top_deg, width_deg):
        hi = lo + width_deg
        cells = []
        for _, curve in runs:
            inside = (curve["shear_angle_deg"] >= lo) & (curve["shear_angle_deg"] < hi)
            force = float(np.nanmean(curve["normalised_force_n_m"][inside])) / 1e3
            measures = {short: (float(np.nanmax(curve[col][inside]))
                                if col in curve and inside.any() else None)
                        for short, col in MEASURES}
            cells.append({"force_n_mm": force, **measures})
        ref = cells[-1]["force_n_mm"]
        for c in cells:
            c["difference"] = c["force_n_mm"] / ref - 1.0 if ref else float("nan")
        out.append({"from": float(lo), "to": float(hi), "runs": cells})
    return out


def _fmt(v):
    return "–" if v is None or not np.isfinite(v) else f"{v:.2f}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", metavar="LABEL=CURVE_CSV",
                        help="the last one is the reference")
    parser.add_argument("--width", type=float, default=5.0, help="interval width [deg]")
    args = parser.parse_args(argv)
    runs = []
    for item in args.runs:
        label, _, path = item.partition("=")
        runs.append((label, read_curve(Path(path))))
    labels = [label for label, _ in runs]
    print("| interval | " + " | ".join(labels) + " |")
    print("|---" * (len(labels) + 1) + "|")
    for row in interval_table(runs, args.width):
        cells = [f"{c['force_n_mm']:.4g} ({100 * c['difference']:+.1f} %) i {_fmt(c['i'])} "
                 f"k {_fmt(c['k'])} d {_fmt(c['d'])}" for c in row["runs"]]
        print(f"| {row['from']:g}–{row['to']:g}° | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
