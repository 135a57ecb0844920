"""Where a sheared periodic cell's work goes, every 5° of shear (periodic shear).

    python benchmarks/periodic_energy.py RUN [RUN ...]

RUN: a ``fabmd test periodic-shear`` folder (its ``periodic_shear`` subfolder is found) or
that subfolder. For each run and interval: the box's work [µJ], what of it went into the
bonds' strain energy (the fibres' stretch), the contacts' elastic energy, the drag and the
kinetic energy, the rest (friction at the contacts, and what the contacts' tangential
springs keep; "nan": not sampled, e.g. the contacts' energy in a standalone run), and the
work's difference from the *last* run named (the reference). The work is read at the
interval's ends from the cumulative columns of ``curve.csv``.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

#: curve.csv columns: cumulative work and the energies it went into [J]
COLUMNS = {"work": "external_work_j", "bonds": "strain_energy_j",
           "contacts": "contact_energy_j", "drag": "damping_dissipation_j",
           "kinetic": "kinetic_energy_j"}


def run_folder(path: Path) -> Path:
    path = Path(path)
    return path / "periodic_shear" if (path / "periodic_shear" / "curve.csv").exists() else path


def read_curve(path: Path) -> dict[str, np.ndarray]:
    """The columns of a periodic shear's ``curve.csv`` as float arrays (NaN: not sampled)."""
    with (run_folder(path) / "curve.csv").open() as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) if r[k] not in ("", "nan") else np.nan for r in rows])
            for k in rows[0]}


def interval_split(curve: dict[str, np.ndarray], width_deg: float = 5.0) -> list[dict]:
    """Per interval of shear [deg]: the change of each cumulative column [J] and the rest,
    work − (bonds + contacts + drag + kinetic). A column the run did not sample (the
    contacts' energy of a standalone run) reads NaN and the rest then holds it."""
    g = curve["shear_angle_deg"]
    out = []
    for lo in np.arange(0.0, float(g.max()) - 1e-9, width_deg):
        ends = [lo, min(lo + width_deg, float(g.max()))]
        row = {"from": float(lo), "to": ends[1]}
        for name, col in COLUMNS.items():
            values = curve.get(col, np.full(len(g), np.nan))
            ok = np.isfinite(values)
            row[name] = (float(np.diff(np.interp(ends, g[ok], values[ok]))[0]) if ok.any()
                         else float("nan"))
        row["rest"] = row["work"] - sum(row[k] for k in ("bonds", "contacts", "drag",
                                                          "kinetic") if np.isfinite(row[k]))
        out.append(row)
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path)
    args = ap.parse_args(argv)
    splits = [interval_split(read_curve(r)) for r in args.runs]
    reference = splits[-1]
    for run, split in zip(args.runs, splits, strict=True):
        print(f"\n{run}")
        print("| shear [°] | work [µJ] | bonds | contacts | drag | kinetic | rest "
              "| work / reference |")
        print("|---|---|---|---|---|---|---|---|")
        for row, ref in zip(split, reference, strict=False):
            ratio = row["work"] / ref["work"] - 1 if ref["work"] else float("nan")
            cells = " | ".join(f"{1e6 * row[k]:.1f}" for k in ("work", "bonds", "contacts",
                                                               "drag", "kinetic", "rest"))
            print(f"| {row['from']:g}–{row['to']:g} | {cells} | {100 * ratio:+.1f} % |")


if __name__ == "__main__":
    main()
