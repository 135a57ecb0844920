"""Fibre directions measured on a bead state, and the in-plane shear angle between families.

The direction of a yarn family in a zone is the mean of the in-plane directions
of its bonds (along a fibre) whose both beads lie in the zone, as an axis (a bond and its reverse
count alike): the doubled-angle mean ½·arg Σ |b|·exp(2iα), weighted by in-plane bond
length. The shear angle between two families is 90° minus the angle between their mean
axes across the sector that holds the direction the test stretches (0 for the as-woven
orthogonal fabric; positive when that sector closes).

Trajectories are LAMMPS ``dump custom`` files with ``id mol type x y z`` sorted by
id (:func:`fabmd.protocols.driven.trajectory_commands`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..model.bead_model import BeadModel


def read_dump(path: Path) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Frames of a ``dump custom ... id mol type x y z`` file: (step, ids, positions)."""
    lines = Path(path).read_text().splitlines()
    frames = []
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            n = int(lines[i + 3])
            header = lines[i + 8].split()[2:]
            rows = np.array([r.split() for r in lines[i + 9:i + 9 + n]], dtype=float)
            cols = {name: k for k, name in enumerate(header)}
            ids = rows[:, cols["id"]].astype(np.int64)
            pos = rows[:, [cols["x"], cols["y"], cols["z"]]]
            order = np.argsort(ids)
            frames.append((step, ids[order], pos[order]))
            i += 9 + n
        else:
            i += 1
    return frames


def zone_mask(positions: np.ndarray, centre, half_size) -> np.ndarray:
    """Beads whose in-plane position lies in the rectangle centre ± half_size."""
    p = np.asarray(positions)[:, :2]
    return np.all(np.abs(p - np.asarray(centre, float)) <= np.asarray(half_size, float), axis=1)


def family_axes_deg(model: BeadModel, positions: np.ndarray,
                    mask: np.ndarray | None = None) -> dict[str, float | None]:
    """Mean in-plane axis of every family's bonds inside ``mask`` [deg, in (−90, 90]]."""
    mask = np.ones(model.n_beads, bool) if mask is None else np.asarray(mask, bool)
    b = model.bonds
    # bonds along a fibre only (not, e.g., bonds that join crossing fibres)
    inside = mask[b[:, 0]] & mask[b[:, 1]] & (model.fibre_ids[b[:, 0]] == model.fibre_ids[b[:, 1]])
    vec = positions[b[inside, 1], :2] - positions[b[inside, 0], :2]
    fam = np.asarray(model.family_names)[model.atom_types[b[inside, 0]] - 1]
    out: dict[str, float | None] = {}
    for f in model.family_names:
        v = vec[fam == f]
        if not len(v):
            out[f] = None
            continue
        length = np.hypot(v[:, 0], v[:, 1])
        alpha = np.arctan2(v[:, 1], v[:, 0])
        z = np.sum(length * np.exp(2j * alpha))
        out[f] = float(np.degrees(0.5 * np.angle(z))) if abs(z) > 0 else None
    return out


def angle_between_axes_deg(a: float, b: float) -> float:
    """Acute angle between two axes given by their angles [deg], in [0, 90]."""
    d = abs(a - b) % 180.0
    return float(min(d, 180.0 - d))


def shear_angle_deg(model: BeadModel, positions: np.ndarray, mask: np.ndarray | None = None,
                    families: tuple[str, str] = ("warp", "weft"),
                    reference_deg: float = 45.0) -> float | None:
    """Signed shear angle between two families in ``mask`` [deg].

    90° minus the angle between their mean axes measured across the sector that holds
    ``reference_deg`` — the direction the test stretches (the pulled diagonal of a picture
    frame, 45°; the load axis of a bias-extension test, 0°): positive when that sector
    closes, 0 for fibres at right angles.
    """
    axes = family_axes_deg(model, positions, mask)
    a, b = axes.get(families[0]), axes.get(families[1])
    if a is None or b is None:
        return None
    a = (a - reference_deg + 90.0) % 180.0 - 90.0  # in [-90, 90) about the reference
    b = (b - reference_deg + 90.0) % 180.0 - 90.0
    sector = abs(a - b) if a * b <= 0 else 180.0 - abs(a - b)
    return 90.0 - sector
