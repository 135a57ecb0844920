"""How the yarns of a sheared periodic cell change their section (periodic shear).

Reads a finished periodic-shear folder's ``trajectory.h5`` (unwrapped positions, box edges
and tilt) and prints per frame: the cell's shear angle (from ly/ly0 = cos γ), the yarns'
mean width and height (spread of their virtual fibres' centres across the yarn in the
fabric's plane and through the thickness, at stations 0.25 mm apart along each yarn, each
fibre first brought to the periodic image nearest its yarn's first fibre) and the width
over the width of a yarn that narrows with the cell's affine deformation (w0·cos γ, w0 the
width after the start-up, frame 1) and the fabric's span (bead centres).

    python benchmarks/periodic_sections.py RUN [RUN ...]

RUN: a ``fabmd test periodic-shear`` folder (its ``periodic_shear`` subfolder is found) or
that subfolder itself.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from yarn_sections import station_spreads  # the stations along a yarn (0.25 mm)

from fabmd.analysis.trajectory_file import open_trajectory, read_lengths


def run_folder(path: Path) -> Path:
    path = Path(path)
    return path / "periodic_shear" if (path / "periodic_shear" / "trajectory.h5").exists() \
        else path


def cell_sections(pos: np.ndarray, lx: float, ly: float, xy: float, fibre: np.ndarray,
                  fibre_yarn: np.ndarray) -> tuple[float, float]:
    """Mean width and height [m] of the yarns at stations along them, in a cell with box
    vectors a = (lx, 0), b = (xy, ly); ``fibre`` the 1-based fibre of each bead,
    ``fibre_yarn`` the 1-based yarn of each fibre."""
    a, b = np.array([lx, 0.0]), np.array([xy, ly])
    yarn_of_bead = fibre_yarn[fibre - 1]
    widths, heights = [], []
    for yarn in np.unique(yarn_of_bead):
        sel = yarn_of_bead == yarn
        q, fib = pos[sel].copy(), fibre[sel]
        fibres = np.unique(fib)
        ref = q[fib == fibres[0], :2].mean(axis=0)
        for f in fibres:  # the image of each fibre nearest the yarn's first fibre
            m = fib == f
            d = q[m, :2].mean(axis=0) - ref
            j = np.round(d[1] / ly)
            i = np.round((d[0] - j * xy) / lx)
            q[m, :2] -= i * a + j * b
        w, h = station_spreads(q, fib)
        widths += w
        heights += h
    return float(np.mean(widths)), float(np.mean(heights))


def table(run: Path) -> str:
    folder = run_folder(run)
    with open_trajectory(folder / "trajectory.h5") as f:  # checks the format
        pos = read_lengths(f["particles/all/position/value"])
        edges = read_lengths(f["particles/all/box/edges/value"])
        tilt = read_lengths(f["observables/box_tilt/value"])
        fibre = f["particles/all/fibre_id"][:]
        fibre_yarn = f["parameters/fabmd/fibre_yarn"][:]
    lines = [f"{folder}: {len(np.unique(fibre_yarn))} yarns",
             "| angle [°] | yarn width [mm] | width / (w0 cos γ) | yarn height [mm] | "
             "fabric span [mm] |", "|---|---|---|---|---|"]
    sections = [cell_sections(pos[k], edges[k][0], edges[k][1], tilt[k][0], fibre,
                              fibre_yarn) for k in range(len(pos))]
    ref = min(1, len(pos) - 1)  # frame 0 is before the start-up
    w0, ly0 = sections[ref][0], edges[ref][1]
    for k, (width, height) in enumerate(sections):
        cos_g = min(1.0, edges[k][1] / ly0)
        lines.append(f"| {np.degrees(np.arccos(cos_g)):.1f} | {1e3 * width:.4f} | "
                     f"{width / (w0 * cos_g):.3f} | {1e3 * height:.4f} | "
                     f"{1e3 * np.ptp(pos[k][:, 2]):.4f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="periodic-shear folders")
    print("\n\n".join(table(run) for run in parser.parse_args(argv).runs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
