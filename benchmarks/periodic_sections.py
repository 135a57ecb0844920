"""How the yarns of a sheared periodic cell change their section (periodic shear).

Reads a finished periodic-shear folder's ``trajectory.h5`` (unwrapped positions, box edges
and tilt) and prints per frame: the cell's shear angle (from ly/ly0 = cos γ), the yarns'
mean width and height (spread of their virtual fibres' centres across the yarn in the
fabric's plane and through the thickness, at stations 0.25 mm apart along each yarn, each
fibre first brought to the periodic image nearest its yarn's first fibre) and the width
over the width of a yarn that narrows with the cell's affine deformation (w0·cos γ, w0 the
width after the start-up, frame 1), the fabric's span (bead centres), and what the fibres'
length does: their crimp (path length over its length along the fibre's chord, minus 1,
all fibres), their mean strain since the start-up and their mean tension (bond forces). In
the cell's trellis kinematics the affine field keeps every fibre's length; a yarn that
keeps its width leaves its crossing yarn a shorter run (p − w/cos γ, p the yarn spacing)
to pass from over to under, so its crimp, at a fixed period, can only rise by stretching.

    python benchmarks/periodic_sections.py RUN [RUN ...]
    python benchmarks/periodic_sections.py --fibres RUN [RUN ...]   # fibre by fibre

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
    widths, heights = [], []
    for q, fib in aligned_yarns(pos, lx, ly, xy, fibre, fibre_yarn):
        w, h = station_spreads(q, fib)
        widths += w
        heights += h
    return float(np.mean(widths)), float(np.mean(heights))


def aligned_yarns(pos: np.ndarray, lx: float, ly: float, xy: float, fibre: np.ndarray,
                  fibre_yarn: np.ndarray):
    """Per yarn (in order): its beads' positions with each fibre moved to the periodic image
    nearest the yarn's first fibre, and the beads' fibres (box vectors as
    :func:`cell_sections`)."""
    a, b = np.array([lx, 0.0]), np.array([xy, ly])
    yarn_of_bead = fibre_yarn[fibre - 1]
    for yarn in np.unique(yarn_of_bead):
        sel = yarn_of_bead == yarn
        q, fib = pos[sel].copy(), fibre[sel]
        fibres = np.unique(fib)
        ref = q[fib == fibres[0], :2].mean(axis=0)
        for f in fibres:
            m = fib == f
            d = q[m, :2].mean(axis=0) - ref
            j = np.round(d[1] / ly)
            i = np.round((d[0] - j * xy) / lx)
            q[m, :2] -= i * a + j * b
        yield q, fib


def fibre_paths(pos: np.ndarray, lx: float, ly: float, xy: float, bonds: np.ndarray,
                fibre: np.ndarray) -> tuple[float, float]:
    """The fibres' crimp (summed path length over the summed length of each fibre's chord,
    minus 1) and their summed path length [m], bond vectors taken at their nearest periodic
    image (box vectors as :func:`cell_sections`; ``bonds`` 0-based bead pairs)."""
    d = pos[bonds[:, 1]] - pos[bonds[:, 0]]
    j = np.round(d[:, 1] / ly)
    d[:, 0] -= j * xy
    d[:, 1] -= j * ly
    d[:, 0] -= np.round(d[:, 0] / lx) * lx
    length = np.linalg.norm(d, axis=1)
    chords = 0.0
    for f in np.unique(fibre[bonds[:, 0]]):
        chords += np.linalg.norm(d[fibre[bonds[:, 0]] == f, :2].sum(axis=0))
    return float(length.sum() / chords - 1.0), float(length.sum())


def fibre_offsets(pos: np.ndarray, lx: float, ly: float, xy: float, fibre: np.ndarray,
                  fibre_yarn: np.ndarray) -> list[np.ndarray]:
    """Per yarn: each fibre's offset across it [m] (its mean in-plane position less the
    yarn's, along the normal to the yarn's first fibre's chord), fibres in id order."""
    out = []
    for q, fib in aligned_yarns(pos, lx, ly, xy, fibre, fibre_yarn):
        fibres = np.unique(fib)
        first = q[fib == fibres[0], :2]
        chord = first[-1] - first[0]
        normal = np.array([-chord[1], chord[0]]) / np.linalg.norm(chord)
        means = np.array([q[fib == f, :2].mean(axis=0) for f in fibres])
        out.append((means - means.mean(axis=0)) @ normal)
    return out


def table(run: Path) -> str:
    folder = run_folder(run)
    with open_trajectory(folder / "trajectory.h5") as f:  # checks the format
        pos = read_lengths(f["particles/all/position/value"])
        edges = read_lengths(f["particles/all/box/edges/value"])
        tilt = read_lengths(f["observables/box_tilt/value"])
        fibre = f["particles/all/fibre_id"][:]
        fibre_yarn = f["parameters/fabmd/fibre_yarn"][:]
        bonds = f["connectivity/bonds"][:]
        bond_force = f["observables/bond_force/value"][:]
    lines = [f"{folder}: {len(np.unique(fibre_yarn))} yarns",
             "| angle [°] | yarn width [mm] | width / (w0 cos γ) | yarn height [mm] | "
             "fabric span [mm] | fibre crimp [%] | fibre strain [%] | fibre tension [N] |",
             "|---|---|---|---|---|---|---|---|"]
    sections = [cell_sections(pos[k], edges[k][0], edges[k][1], tilt[k][0], fibre,
                              fibre_yarn) for k in range(len(pos))]
    ref = min(1, len(pos) - 1)  # frame 0 is before the start-up
    w0, ly0 = sections[ref][0], edges[ref][1]
    paths = [fibre_paths(pos[k], edges[k][0], edges[k][1], tilt[k][0], bonds, fibre)
             for k in range(len(pos))]
    for k, (width, height) in enumerate(sections):
        cos_g = min(1.0, edges[k][1] / ly0)
        crimp, length = paths[k]
        strain = length / paths[ref][1] - 1.0
        lines.append(f"| {np.degrees(np.arccos(cos_g)):.1f} | {1e3 * width:.4f} | "
                     f"{width / (w0 * cos_g):.3f} | {1e3 * height:.4f} | "
                     f"{1e3 * np.ptp(pos[k][:, 2]):.4f} | {100 * crimp:.3f} | "
                     f"{100 * strain:.3f} | {np.mean(bond_force[k]):.3f} |")
    return "\n".join(lines)


def fibre_table(run: Path) -> str:
    """Per frame: the range over the yarns' off-centre fibres (offset after the start-up
    above a quarter of the yarn's largest) of offset / (offset after the start-up · cos γ):
    1 where every fibre follows the box's affine field, 1/cos γ where the yarn keeps its
    width."""
    folder = run_folder(run)
    with open_trajectory(folder / "trajectory.h5") as f:
        pos = read_lengths(f["particles/all/position/value"])
        edges = read_lengths(f["particles/all/box/edges/value"])
        tilt = read_lengths(f["observables/box_tilt/value"])
        fibre = f["particles/all/fibre_id"][:]
        fibre_yarn = f["parameters/fabmd/fibre_yarn"][:]
    offsets = [fibre_offsets(pos[k], edges[k][0], edges[k][1], tilt[k][0], fibre, fibre_yarn)
               for k in range(len(pos))]
    ref = min(1, len(pos) - 1)
    lines = [f"{folder}: each fibre's offset across its yarn / (its start-up offset · cos γ)",
             "| angle [°] | smallest | largest | 1/cos γ (width kept) |", "|---|---|---|---|"]
    for k in range(ref + 1, len(pos)):
        cos_g = min(1.0, edges[k][1] / edges[ref][1])
        ratios = np.concatenate([
            (o / o0)[np.abs(o0) > 0.25 * np.abs(o0).max()] / cos_g
            for o, o0 in zip(offsets[k], offsets[ref], strict=True)])
        lines.append(f"| {np.degrees(np.arccos(cos_g)):.1f} | {ratios.min():.3f} | "
                     f"{ratios.max():.3f} | {1 / cos_g:.3f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="periodic-shear folders")
    parser.add_argument("--fibres", action="store_true",
                        help="each fibre's offset across its yarn against the affine one")
    args = parser.parse_args(argv)
    show = fibre_table if args.fibres else table
    print("\n\n".join(show(run) for run in args.runs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
