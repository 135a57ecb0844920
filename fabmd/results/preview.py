"""A preview PNG of a bead model a person can check at a glance.

Three panels, beads drawn to scale and coloured by yarn family:

1. top view (x–y), upper beads drawn over lower ones, lighter when higher;
2. a cut along the warp (x–z plane through the centre of the first warp or binder
   yarn) across the whole fabric: the beads within ±d/2 of the plane, at true size
   (:mod:`fabmd.results.cuts`);
3. a cut along the weft (y–z plane through the centre of the first weft yarn).

Large models are thinned (every k-th fibre) in the top view. Rank 0 only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.frame import FabricFrame
from ..analysis.sections import fabric_cut
from ..engine import mpi
from ..model.bead_model import BeadModel
from .cuts import COLOURS, cut_height_in, default_positions, draw_cut
from .measure import thickness_m
from .plots import _pyplot

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
    z_lo, z_hi = pos[:, 2].min(), pos[:, 2].max()

    extent = pos[:, :2].max(axis=0) - pos[:, :2].min(axis=0) + 2 * d.max()
    # 2, 3: thin cuts (beads within ±d/2 of the plane) across the whole fabric, through a
    # warp (binder) yarn and a weft yarn
    frame = FabricFrame.from_model(model)
    planes = default_positions(frame)
    cuts = [fabric_cut(frame, *next(p for p in planes if p[0] == normal))
            for normal in ("y", "x")]
    width = 9.0
    heights = [float(np.clip(width * extent[1] / extent[0], 2.5, 7.0)) + 0.6] + \
        [cut_height_in(c, width) + 0.7 for c in cuts]
    fig = plt.figure(figsize=(width, sum(heights) + 0.8), layout="constrained")
    grid = fig.add_gridspec(3, 1, height_ratios=heights)
    ax_top = fig.add_subplot(grid[0])
    for k, c in enumerate(cuts):
        draw_cut(fig.add_subplot(grid[k + 1]), c, legend=False)

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
