"""Checks of a voxel mesh against the bead model it came from (SI).

* **fibre volume fraction** of the whole domain: the voxels' mean against the bead
  model's filament volume Σ A_f·(bond length) over the domain volume (for a periodic
  cell: the cell area × the beads' thickness, the definition of ``fabmd measure``);
* **direction**: at every bead, the angle between its fibre's tangent (central
  difference of its neighbours) and the fibre direction of the voxel holding it,
  taken axially (0–90°), over the beads that fall in a voxel of their own yarn.
"""

from __future__ import annotations

import numpy as np

from ..analysis.frame import FabricFrame
from ..results.measure import fibre_volume_m3
from .voxel import VoxelGrid, VoxelMesh


def domain(model) -> tuple[np.ndarray, np.ndarray]:
    """Voxel domain of a state [m]: the box along periodic axes, else the beads' extent
    including their radius."""
    p = model.unwrapped_positions
    r = model.diameters / 2
    lo, hi = (p - r[:, None]).min(axis=0), (p + r[:, None]).max(axis=0)
    for k in range(3):
        if model.periodic[k]:
            lo[k], hi[k] = model.box_lo[k], model.box_hi[k]
    return lo, hi


def bead_fibre_volume_fraction(model, grid: VoxelGrid) -> float:
    """Filament volume of the bead model over the grid's domain volume."""
    return fibre_volume_m3(model) / float(np.prod(grid.hi_m - grid.lo_m))


def bead_tangents(frame: FabricFrame) -> np.ndarray:
    """(N, 3) unit fibre tangent at every bead (central differences; one-sided at the
    ends of an open fibre, across the box for a closed one)."""
    t = np.zeros_like(frame.positions)
    for f in range(1, frame.n_fibres + 1):
        sl = frame.fibre_beads(f)
        p = frame.positions[sl]
        if len(p) < 2:
            continue
        if frame.closed[f - 1] and len(p) > 2:
            step = frame.minimum_image(p[0] - p[-1])[0] + p[-1] - p[0]  # one period
            ext = np.vstack([p[-1:] - step, p, p[:1] + step])
            d = 0.5 * (ext[2:] - ext[:-2])
        else:
            d = np.gradient(p, axis=0)
        t[sl] = d / np.linalg.norm(d, axis=1, keepdims=True)
    return t


def direction_errors(model, mesh: VoxelMesh) -> dict:
    """Angle between bead tangents and voxel fibre directions (axial) [deg].

    Returns mean, median, 95th percentile and max over the beads in a voxel of their own
    yarn, and the shares of beads in matrix voxels or in another yarn's voxels.
    """
    frame = FabricFrame.from_model(model)
    tangents = bead_tangents(frame)
    voxel = mesh.grid.index_of(frame.positions)
    found = voxel >= 0
    owner = np.where(found, mesh.yarn_id[np.maximum(voxel, 0)], -1)
    yarn = model.yarn_ids
    own = owner == yarn
    cos = np.abs(np.einsum("ij,ij->i", tangents[own], mesh.direction[voxel[own]]))
    angle = np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))
    n = len(yarn)
    return {"mean_deg": float(angle.mean()) if len(angle) else None,
            "median_deg": float(np.median(angle)) if len(angle) else None,
            "p95_deg": float(np.percentile(angle, 95)) if len(angle) else None,
            "max_deg": float(angle.max()) if len(angle) else None,
            "beads_compared": int(own.sum()),
            "beads_in_matrix": float(np.sum(owner == 0) / n),
            "beads_in_other_yarn": float(np.sum((owner > 0) & ~own) / n)}
