"""How much of a picture frame's work goes into the fabric's motion, and what taking it off
the force does to the difference between two loading speeds.

The fabric moves with the frame, whose arms turn faster as the shear grows at a constant
corner speed, so its kinetic energy grows throughout the test. fabmd reports the frame
force as (ΔW − ΔKE_c)/Δd (``fabmd.protocols.picture_frame.frame_force_n``), KE_c the
carriage's kinetic energy: the fabric's less its part relative to the frame's affine
field. A curve.csv keeps the work and both kinetic energies, so the force of the work alone
(ΔW/Δd, what was reported before 2026-12-05) can be read back from any run.

    python benchmarks/frame_kinetic.py FAST SLOW [FAST SLOW ...]   # picture-frame folders

For each pair (the same scene at two speeds): per 5° interval the fast run's mean force
over the slow run's, from the work alone and with the kinetic energy taken off, and each
run's inertia share |ΔKE|/ΔW.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from fabmd.results.folder import read_csv  # noqa: E402

WIDTH_DEG = 5.0


def curve_of(folder: Path) -> dict:
    """The curve.csv of a picture-frame run folder (or of its picture_frame/ stage)."""
    folder = Path(folder)
    path = folder / "curve.csv"
    if not path.exists():
        path = folder / "picture_frame" / "curve.csv"
    return read_csv(path)


def interval_forces(curve: dict, edges: np.ndarray) -> dict[str, np.ndarray]:
    """Mean frame force over each interval of shear angle [N]: from the work alone
    (``work``), with the carriage's kinetic energy taken off (``net``: the kinetic energy
    less its part relative to the frame's affine field, where the curve has it); and the
    inertia share |ΔKE|/ΔW of the absolute kinetic energy (``share``, as the verdict)."""
    at = lambda y: np.interp(edges, curve["shear_angle_deg"], y)  # noqa: E731
    ke = curve["kinetic_energy_j"]
    carriage = ke - curve["kinetic_relative_j"] if "kinetic_relative_j" in curve else ke
    dw, dke = np.diff(at(curve["external_work_j"])), np.diff(at(ke))
    dkc, dd = np.diff(at(carriage)), np.diff(at(curve["displacement_m"]))
    return {"work": dw / dd, "net": (dw - dkc) / dd, "share": np.abs(dke) / np.abs(dw)}


def compare(fast: dict, slow: dict, start_deg: float = 5.0) -> list[list[str]]:
    """Table rows: interval, fast/slow − 1 from the work alone and with KE off, shares."""
    top = min(fast["shear_angle_deg"].max(), slow["shear_angle_deg"].max())
    edges = np.arange(start_deg, top + 1e-9, WIDTH_DEG)
    f, s = interval_forces(fast, edges), interval_forces(slow, edges)
    rows = []
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        rows.append([f"{a:g}–{b:g}°", f"{100 * (f['work'][k] / s['work'][k] - 1):+.1f} %",
                     f"{100 * (f['net'][k] / s['net'][k] - 1):+.1f} %",
                     f"{f['share'][k]:.3f} / {s['share'][k]:.3f}"])
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path, help="picture-frame folders: FAST SLOW ...")
    args = p.parse_args(argv)
    if len(args.runs) % 2:
        p.error("give the runs in pairs: FAST SLOW")
    for fast, slow in zip(args.runs[::2], args.runs[1::2], strict=True):
        print(f"\n{fast} against {slow}\n")
        print("| interval | fast / slow − 1, work alone | with the kinetic energy off | "
              "inertia share fast / slow |\n|---|---|---|---|")
        for row in compare(curve_of(fast), curve_of(slow)):
            print("| " + " | ".join(row) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
