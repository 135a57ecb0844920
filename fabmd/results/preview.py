"""A preview PNG of a bead model a person can check at a glance.

Three panels, beads drawn to scale and coloured by yarn family:

1. top view (x–y), upper beads drawn over lower ones, lighter when higher;
2. section along the warp (x–z) through a thin slab at one warp (2D) or binder
   plane (3D), one unit cell long: the warp/binder paths and the cut wefts;
3. section along the weft (y–z) through the first weft column.

Large models are thinned (every k-th fibre) in the top view. Rank 0 only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..engine import mpi
from ..model.bead_model import BeadModel
from .measure import thickness_m
from .plots import _pyplot

COLOURS = {"warp": (0.12, 0.38, 0.75), "weft": (0.84, 0.19, 0.15),
           "binder": (0.15, 0.62, 0.20), "fibre": (0.4, 0.4, 0.4)}
#: largest number of beads drawn in the top view
TOP_VIEW_BEADS = 250_000


def _colours(model: BeadModel, idx: np.ndarray, shade: np.ndarray | None = None) -> np.ndarray:
    base = np.array([COLOURS.get(f, (0.5, 0.5, 0.5)) for f in model.family_names])
    rgb = base[model.atom_types[idx] - 1]
    if shade is not None:  # 0 = lowest (darker), 1 = highest (lighter)
        s = shade[:, None]
        rgb = rgb * (0.55 + 0.45 * s) + (1 - (0.55 + 0.45 * s)) * 0.0 + 0.35 * s * (1 - rgb)
    return np.clip(rgb, 0, 1)


def _draw(ax, xy: np.ndarray, d: np.ndarray, colours: np.ndarray) -> None:
    from matplotlib.collections import EllipseCollection

    coll = EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=xy,
                             offset_transform=ax.transData, facecolors=colours,
                             edgecolors="none")
    ax.add_collection(coll)


def _section_axes(ax, axis: str, extent: tuple[float, float], z: tuple[float, float],
                  pad: float, title: str) -> None:
    """Limits (padded by a bead diameter), equal aspect, labels [mm] and title of a
    cross-section panel."""
    ax.set_xlim(extent[0] - pad, extent[1] + pad)
    ax.set_ylim(z[0] - pad, z[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{axis} [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_title(title, fontsize=9)


def _slab(model: BeadModel, axis: int, centre: float, half: float) -> np.ndarray:
    pos = model.positions[:, axis]
    d = pos - centre
    if model.periodic[axis]:
        length = model.box_hi[axis] - model.box_lo[axis]
        d -= length * np.round(d / length)
    return np.flatnonzero(np.abs(d) <= half)


def preview_png(model: BeadModel, path: Path, title: str = "") -> Path | None:
    """Write the preview of ``model`` to ``path`` (PNG, 150 dpi)."""
    if not mpi.is_root():
        return None
    plt = _pyplot()
    from matplotlib.patches import Patch

    info = model.info
    mm = 1e3
    pos = model.positions * mm
    d = model.diameters * mm
    cell = np.array(info.get("unit_cell_m", model.box_hi[:2] - model.box_lo[:2])) * mm
    z_lo, z_hi = pos[:, 2].min(), pos[:, 2].max()
    offsets = np.array(info.get("yarn_offset_m", [np.nan] * len(model.yarns))) * mm
    families = [y.family for y in model.yarns]

    extent = pos[:, :2].max(axis=0) - pos[:, :2].min(axis=0) + 2 * d.max()
    thick = z_hi - z_lo + 2 * d.max()
    span_x = min(cell[0] * 1.25, extent[0])
    span_y = min(cell[1] * 1.25, extent[1])
    width = 9.0
    heights = [float(np.clip(width * extent[1] / extent[0], 2.5, 7.0)) + 0.6,
               float(np.clip(width * thick / span_x, 1.0, 3.5)) + 0.7,
               float(np.clip(width * thick / span_y, 1.0, 3.5)) + 0.7]
    fig = plt.figure(figsize=(width, sum(heights) + 0.8), layout="constrained")
    grid = fig.add_gridspec(3, 1, height_ratios=heights)
    ax_top = fig.add_subplot(grid[0])
    ax_xz = fig.add_subplot(grid[1])
    ax_yz = fig.add_subplot(grid[2])

    # 1. top view
    idx = np.argsort(pos[:, 2], kind="stable")
    if len(idx) > TOP_VIEW_BEADS:  # thin by whole fibres so the chains stay continuous
        every = int(np.ceil(model.n_beads / TOP_VIEW_BEADS))
        idx = idx[(model.fibre_ids[idx] % every) == 0]
    shade = (pos[idx, 2] - z_lo) / max(z_hi - z_lo, 1e-12)
    _draw(ax_top, pos[idx, :2], d[idx], _colours(model, idx, shade))
    lo, hi = pos[:, :2].min(axis=0) - d.max(), pos[:, :2].max(axis=0) + d.max()
    ax_top.set_xlim(lo[0], hi[0])
    ax_top.set_ylim(lo[1], hi[1])
    ax_top.set_aspect("equal")
    ax_top.set_xlabel("x (warp direction) [mm]")
    ax_top.set_ylabel("y (weft direction) [mm]")
    if model.periodic[0]:
        bx = np.array([model.box_lo[0], model.box_hi[0]]) * mm
        by = np.array([model.box_lo[1], model.box_hi[1]]) * mm
        ax_top.plot([bx[0], bx[1], bx[1], bx[0], bx[0]], [by[0], by[0], by[1], by[1], by[0]],
                    "k--", lw=0.8, label="periodic box")
    ax_top.set_title("top view (lighter = higher)", fontsize=9, loc="right")
    handles = [Patch(color=COLOURS.get(f, (0.5, 0.5, 0.5)), label=f) for f in model.family_names]
    ax_top.legend(handles=handles, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=4,
                  fontsize=8, frameon=False)

    # 2. x–z slab through a binder plane (3D) or the first warp (2D)
    warp_like = [k for k, f in enumerate(families) if f == "binder"] or \
                [k for k, f in enumerate(families) if f == "warp"]
    if warp_like and np.isfinite(offsets[warp_like[0]]):
        y0 = offsets[warp_like[0]]
    else:
        y0 = float(np.median(pos[:, 1]))
    fam_w = info.get("families", {})
    wname = families[warp_like[0]] if warp_like else "warp"
    half = 0.5 * fam_w.get(wname, {}).get("width_m", 2 * model.diameters.max()) * mm
    x_lo = float(pos[:, 0].min())
    span = span_x
    sel = _slab(model, 1, y0 / mm, half / mm)
    sel = sel[(pos[sel, 0] >= x_lo) & (pos[sel, 0] <= x_lo + span)]
    order = np.argsort(-model.positions[sel, 1])  # nearer (smaller y) drawn last
    sel = sel[order]
    _draw(ax_xz, pos[sel][:, [0, 2]], d[sel], _colours(model, sel))
    _section_axes(ax_xz, "x", (x_lo, x_lo + span), (z_lo, z_hi), d.max(),
                  f"section along the warp: slab |y − {y0:.2f} mm| ≤ {half:.2f} mm")

    # 3. y–z slab through the first weft column
    wefts = [k for k, f in enumerate(families) if f == "weft"]
    x0 = offsets[wefts[0]] if wefts and np.isfinite(offsets[wefts[0]]) \
        else float(np.median(pos[:, 0]))
    halfx = 0.5 * fam_w.get("weft", {}).get("width_m", 2 * model.diameters.max()) * mm
    y_lo = float(pos[:, 1].min())
    sel = _slab(model, 0, x0 / mm, halfx / mm)
    sel = sel[(pos[sel, 1] >= y_lo) & (pos[sel, 1] <= y_lo + span_y)]
    sel = sel[np.argsort(model.positions[sel, 0])]
    _draw(ax_yz, pos[sel][:, [1, 2]], d[sel], _colours(model, sel))
    _section_axes(ax_yz, "y", (y_lo, y_lo + span_y), (z_lo, z_hi), d.max(),
                  f"section along the weft: slab |x − {x0:.2f} mm| ≤ {halfx:.2f} mm")

    name = info.get("architecture", {}).get("name", "")
    # the clearance was measured on the loose fabric; a later state does not keep it
    clear = info.get("clearance_m") if "crimp" not in info else None
    lines = [title or f"fabmd fabric: {name}",
             f"{model.n_beads:,} beads, {model.n_fibres:,} fibres, {len(model.yarns)} yarns; "
             f"thickness {thickness_m(model) * mm:.3g} mm"
             + (f"; min. gap between yarns {clear * mm:.3g} mm" if clear is not None else "")
             + ("; periodic" if model.periodic[0] else "")]
    fig.suptitle("\n".join(lines), fontsize=10)
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return Path(path)
