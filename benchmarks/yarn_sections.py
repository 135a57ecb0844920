"""How the yarns of a picture-frame run change their section as the fabric shears.

Reads a finished picture-frame folder's ``trajectory.h5`` (H5MD, positions in the file's
unit) and ``curve.csv``, and prints per frame: shear angle, F_norm, the yarns' width and
height (spread of their virtual fibres' centres across the yarn in the fabric's plane, and
through the thickness, at stations 0.25 mm apart along each yarn, averaged over the yarns
and stations of the free square's central 80 %), the width over the width of a yarn that
narrows with the fabric's affine deformation (w0·cos γ: fibres that keep their place
along the crossing yarns), the fabric's span through the thickness (bead centres) and the
mean tension of the fibres there.

    python benchmarks/yarn_sections.py RUN [RUN ...] [--every 2]

RUN: a ``fabmd test picture-frame`` folder (its ``picture_frame`` subfolder is found) or
the ``picture_frame`` folder itself.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np

from fabmd.analysis.trajectory_file import open_trajectory, read_lengths

STATION_M = 0.25e-3  # length of a station along a yarn
CENTRAL = 0.8  # share of the free square's half side that counts as its interior


def run_folder(path: Path) -> Path:
    path = Path(path)
    return path / "picture_frame" if (path / "picture_frame" / "trajectory.h5").exists() \
        else path


def read(folder: Path) -> dict:
    """Positions [m] per frame, frame times, bonds and their forces, fibre and yarn ids,
    and the curve's angle and F_norm against time."""
    with open_trajectory(folder / "trajectory.h5") as f:  # checks the format
        data = {"pos": read_lengths(f["particles/all/position/value"]),
                "time": f["observables/bond_force/time"][:],
                "bond_force": f["observables/bond_force/value"][:],
                "bonds": f["connectivity/bonds"][:],
                "fibre": f["particles/all/fibre_id"][:],
                "fibre_yarn": f["parameters/fabmd/fibre_yarn"][:]}
    with open(folder / "curve.csv") as fh:
        rows = list(csv.DictReader(fh))
    data["curve_time"] = np.array([float(r["time_s"]) for r in rows])
    data["angle"] = np.array([float(r["shear_angle_deg"]) for r in rows])
    data["f_norm"] = np.array([float(r["normalised_force_n_m"]) for r in rows])
    data["free_side_m"] = json.loads((folder / "summary.json").read_text())["free_side_m"]
    return data


def interior(data: dict) -> np.ndarray:
    """Beads that start in the central part of the free square."""
    p0 = data["pos"][0]
    centre = p0[:, :2].mean(axis=0)
    half = 0.5 * CENTRAL * data["free_side_m"]
    return np.all(np.abs(p0[:, :2] - centre) < half, axis=1)


def whole_yarns(data: dict, inside: np.ndarray) -> list[int]:
    """Yarns whose every fibre crosses the interior (at the start): a yarn that straddles
    the interior's edge is left out, not cut."""
    p0 = data["pos"][0]
    yarn_of_bead = data["fibre_yarn"][data["fibre"] - 1]
    keep = []
    for yarn in np.unique(yarn_of_bead):
        mine = yarn_of_bead == yarn
        fibres = np.unique(data["fibre"][mine])
        if (mine & inside).sum() >= 30 and all(
                (inside & (data["fibre"] == f)).any() for f in fibres):
            axis = np.argmax(np.ptp(p0[mine, :2], axis=0))
            across = p0[mine & inside, 1 - axis]
            if np.ptp(across) >= 0.9 * np.ptp(p0[mine, 1 - axis]):
                keep.append(int(yarn))
    return keep


def sections(pos: np.ndarray, data: dict, inside: np.ndarray,
             yarns: list[int]) -> tuple[float, float]:
    """Mean width and height [m] of the yarns' fibre centres at stations along them (a
    station counts where it holds every fibre of its yarn)."""
    widths, heights = [], []
    yarn_of_bead = data["fibre_yarn"][data["fibre"] - 1]
    for yarn in yarns:
        sel = (yarn_of_bead == yarn) & inside
        w, h = station_spreads(pos[sel], data["fibre"][sel])
        widths += w
        heights += h
    return float(np.mean(widths)), float(np.mean(heights))


def station_spreads(q: np.ndarray, fib: np.ndarray) -> tuple[list, list]:
    """One yarn's width and height [m] at each station along it: the spread of its fibre
    centres ``q`` (fibre of each: ``fib``) across it in the plane and through the
    thickness, where a station holds every fibre (also used by periodic_sections.py)."""
    n_fibres = len(np.unique(fib))
    # the yarn's direction: its fibres' end-to-end chords (the cloud's principal axis
    # tilts once the interior is a parallelogram)
    chords = [q[fib == f][-1, :2] - q[fib == f][0, :2] for f in np.unique(fib)]
    chords = [c if c @ chords[0] >= 0 else -c for c in chords]
    axis = np.sum(chords, axis=0)
    axis /= np.linalg.norm(axis)
    c = q[:, :2] - q[:, :2].mean(axis=0)
    along, across = c @ axis, c @ np.array([-axis[1], axis[0]])
    widths, heights = [], []
    for start in np.arange(along.min(), along.max(), STATION_M):
        m = (along >= start) & (along < start + STATION_M)
        if len(np.unique(fib[m])) == n_fibres:
            widths.append(np.ptp(across[m]))
            heights.append(np.ptp(q[m, 2]))
    return widths, heights


def table(run: Path, every: int) -> str:
    folder = run_folder(run)
    data = read(folder)
    inside = interior(data)
    yarns = whole_yarns(data, inside)
    bonds = data["bonds"]
    inner_bond = inside[bonds[:, 0]] & inside[bonds[:, 1]]
    lines = [f"{folder}: {inside.sum()} beads in the interior, {len(yarns)} whole yarns",
             "| angle [°] | F_norm [N/mm] | yarn width [mm] | width / (w0 cos γ) | "
             "yarn height [mm] | fabric span [mm] | fibre tension [N] |",
             "|---|---|---|---|---|---|---|"]
    w0 = None
    for k in range(0, len(data["time"]), every):
        angle = float(np.interp(data["time"][k], data["curve_time"], data["angle"]))
        force = float(np.interp(data["time"][k], data["curve_time"], data["f_norm"]))
        pos = data["pos"][k]
        width, height = sections(pos, data, inside, yarns)
        if w0 is None and angle > 1.0:  # the relaxed start (frame 0 is before relaxing)
            w0 = width / np.cos(np.radians(angle))
        ratio = width / (w0 * np.cos(np.radians(angle))) if w0 else float("nan")
        lines.append(f"| {angle:.1f} | {force / 1e3:.4g} | {1e3 * width:.3f} | {ratio:.3f} | "
                     f"{1e3 * height:.3f} | {1e3 * np.ptp(pos[inside, 2]):.3f} | "
                     f"{data['bond_force'][k][inner_bond].mean():.3g} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--every", type=int, default=2, help="every n-th frame")
    args = p.parse_args(argv)
    for run in args.runs:
        print(table(run, args.every) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
