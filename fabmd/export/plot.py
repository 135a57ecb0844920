"""Picture of a voxel mesh: the voxels coloured by yarn, and the fibre-direction field on
a section through the thickness (matplotlib, Agg)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .voxel import VoxelMesh


def voxel_figure(mesh: VoxelMesh, path: Path, title: str = "", dpi: int = 90) -> Path:
    """Write a PNG: left, the yarn voxels in 3D coloured by yarn (matrix left out);
    right, the section y = const through the middle of the first warp yarn (or the
    domain's middle), coloured by the out-of-plane angle of the fibre direction
    (asin of its z component, degrees) with the in-section direction as arrows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = mesh.grid
    nx, ny, nz = grid.counts
    ids = mesh.yarn_id.reshape(nz, ny, nx).transpose(2, 1, 0)  # (x, y, z)
    direction = mesh.direction.reshape(nz, ny, nx, 3).transpose(2, 1, 0, 3)
    size_mm = 1e3 * grid.size_m
    lo_mm = 1e3 * grid.lo_m
    fig = plt.figure(figsize=(11, 4.6))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    n_yarns = max(len(mesh.yarn_names), 1)
    cmap = plt.get_cmap("tab20" if n_yarns > 10 else "tab10")
    colours = np.zeros((*ids.shape, 4))
    for k in range(1, n_yarns + 1):
        colours[ids == k] = cmap((k - 1) % cmap.N)
    quads, face_colours = _exposed_faces(ids, colours, lo_mm, size_mm)
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    ax.add_collection3d(Poly3DCollection(quads, facecolors=face_colours, linewidths=0))
    ax.set_xlim(lo_mm[0], lo_mm[0] + 1e3 * (grid.hi_m - grid.lo_m)[0])
    ax.set_ylim(lo_mm[1], lo_mm[1] + 1e3 * (grid.hi_m - grid.lo_m)[1])
    ax.set_zlim(lo_mm[2], lo_mm[2] + 1e3 * (grid.hi_m - grid.lo_m)[2])
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_zlabel("z [mm]")
    span = 1e3 * (grid.hi_m - grid.lo_m)
    ax.set_box_aspect(tuple(span))
    ax.set_title("voxels coloured by yarn")
    ax.view_init(elev=28, azim=-60)

    # section through the middle of the first yarn along x (a warp), else the middle
    along_x = [k for k, _ in enumerate(mesh.yarn_names, start=1)
               if (ids == k).any() and np.abs(direction[ids == k][:, 0]).mean() > 0.7]
    if along_x:
        j = int(np.round(np.mean(np.nonzero((ids == along_x[0]).any(axis=(0, 2)))[0])))
    else:
        j = ny // 2
    sec_ids = ids[:, j, :]
    sec_dir = direction[:, j, :, :]
    angle = np.degrees(np.arcsin(np.clip(sec_dir[..., 2], -1, 1)))
    angle = np.where(sec_ids > 0, angle * np.sign(sec_dir[..., 0] + 1e-12), np.nan)
    ax2 = fig.add_subplot(1, 2, 2)
    extent = (lo_mm[0], lo_mm[0] + span[0], lo_mm[2], lo_mm[2] + span[2])
    lim = float(np.nanmax(np.abs(angle))) if np.isfinite(angle).any() else 1.0
    im = ax2.imshow(angle.T, origin="lower", extent=extent, cmap="coolwarm",
                    vmin=-lim, vmax=lim, aspect="equal", interpolation="nearest")
    xs = lo_mm[0] + size_mm[0] * (np.arange(nx) + 0.5)
    zs = lo_mm[2] + size_mm[2] * (np.arange(nz) + 0.5)
    step = max(1, nx // 30)
    xx, zz = np.meshgrid(xs[::step], zs[::step], indexing="ij")
    d = sec_dir[::step, ::step]
    show = sec_ids[::step, ::step] > 0
    ax2.quiver(xx[show], zz[show], d[..., 0][show], d[..., 2][show], angles="xy",
               pivot="middle", scale=2.2 / (step * size_mm[0]), scale_units="xy",
               headwidth=2, headlength=2, headaxislength=2, width=0.003)
    ax2.set_xlabel("x [mm]")
    ax2.set_ylabel("z [mm]")
    ax2.set_title(f"fibre direction, section y = {lo_mm[1] + size_mm[1] * (j + 0.5):.2f} mm")
    fig.colorbar(im, ax=ax2, shrink=0.7, label="fibre angle out of the plane [deg]")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return Path(path)


#: shading of the faces whose normal is along x, y, z (a fixed light)
_SHADE = (0.75, 0.6, 1.0)


def _exposed_faces(ids: np.ndarray, colours: np.ndarray, lo_mm: np.ndarray,
                   size_mm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quads (q, 4, 3) [mm] of the voxel faces between a yarn voxel and a voxel of
    another yarn, the matrix or the outside, with their shaded colours (one collection
    instead of one artist per voxel: seconds instead of minutes)."""
    quads, cols = [], []
    # corner offsets of the face normal to axis a at the voxel's low (0) or high (1) side
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    for a in range(3):
        b, c = [k for k in range(3) if k != a]
        for side in (0, 1):
            step = np.zeros(3, int)
            step[a] = 1 if side else -1
            padded = np.pad(ids, 1, constant_values=0)
            inner = tuple(slice(1, -1) for _ in range(3))
            shifted = tuple(slice(1 + step[k], padded.shape[k] - 1 + step[k]) for k in range(3))
            face = (padded[inner] > 0) & (padded[shifted] != padded[inner])
            ijk = np.argwhere(face)
            if not len(ijk):
                continue
            corners = np.zeros((len(ijk), 4, 3))
            corners[:, :, a] = (ijk[:, a] + side)[:, None]
            corners[:, :, b] = ijk[:, b][:, None] + square[None, :, 0]
            corners[:, :, c] = ijk[:, c][:, None] + square[None, :, 1]
            quads.append(lo_mm + corners * size_mm)
            rgba = colours[ijk[:, 0], ijk[:, 1], ijk[:, 2]].copy()
            rgba[:, :3] *= _SHADE[a]
            cols.append(rgba)
    if not quads:
        return np.zeros((0, 4, 3)), np.zeros((0, 4))
    return np.concatenate(quads), np.concatenate(cols)
