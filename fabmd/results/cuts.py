"""Cut images: thin planar slices through the whole fabric, to put beside a micro-CT slice.

A cut (:func:`fabmd.analysis.sections.fabric_cut`) holds the beads the plane passes
through (within ±d/2 of it); each is drawn as a circle of its true diameter, coloured
by yarn family, with the axes spanning the whole fabric (width and thickness, mm).
:func:`cut_png` writes one figure and a CSV of the drawn beads; :func:`cut_pngs` one
figure per position plus a grid overview. Rank 0 only.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..analysis.frame import FabricFrame
from ..analysis.sections import FabricCut, fabric_cut
from ..engine import mpi
from ..model.bead_model import BeadModel
from .plots import _pyplot

COLOURS = {"warp": (0.12, 0.38, 0.75), "weft": (0.84, 0.19, 0.15),
           "binder": (0.15, 0.62, 0.20), "fibre": (0.4, 0.4, 0.4)}
#: matplotlib gid of the bead circles of a cut (tests and users find them by it)
CUT_GID = "fabmd-cut-beads"
_MM = 1e3


def _frame(model: BeadModel | FabricFrame) -> FabricFrame:
    return model if isinstance(model, FabricFrame) else FabricFrame.from_model(model)


def cut_label(normal: str, position_m: float) -> str:
    """``x_5mm``: the file-name stem of a cut (position in mm, 4 significant digits)."""
    return f"{normal}_{_MM * position_m:.4g}mm"


def default_positions(model: BeadModel | FabricFrame) -> list[tuple[str, float]]:
    """Cut planes worth a look: through the centres of the first two warp (or binder) yarns
    (normal y: along the warp) and of the first two weft yarns (normal x: along the weft);
    the fabric's middle where the model says nothing of its yarn positions."""
    frame = _frame(model)
    out: list[tuple[str, float]] = []
    for normal, axis, families in (("y", 1, ("binder", "warp")), ("x", 0, ("weft",))):
        centres = []
        for fam in families:
            for k, f in enumerate(frame.yarn_families):
                if f != fam:
                    continue
                beads = np.isin(frame.fibre_ids,
                                np.flatnonzero(frame.fibre_yarn == k + 1) + 1)
                centres.append(float(np.mean(frame.positions[beads, axis])))
            if centres:
                break
        if not centres:
            centres = [float(np.median(frame.positions[:, axis]))]
        if frame.periodic[axis]:
            lo, length = frame.box_lo[axis], frame.box_lengths[axis]
            centres = [lo + (c - lo) % length for c in centres]
        out += [(normal, c) for c in sorted(centres)[:2]]
    return out


def draw_cut(ax, cut: FabricCut, legend: bool = True):
    """Draw ``cut`` on ``ax``: bead circles of true diameter [mm], axes to the fabric's
    extent, equal aspect, labels with units. Returns the circles' collection."""
    from matplotlib.collections import EllipseCollection
    from matplotlib.patches import Patch

    d = cut.diameters_m * _MM
    rgb = np.array([COLOURS.get(f, (0.5, 0.5, 0.5)) for f in cut.families]).reshape(-1, 3)
    faces = np.column_stack([rgb, np.full(len(rgb), 0.45)])
    coll = EllipseCollection(d, d, np.zeros_like(d), units="xy", offsets=cut.points_m * _MM,
                             offset_transform=ax.transData, facecolors=faces,
                             edgecolors=rgb, linewidths=0.6)
    coll.set_gid(CUT_GID)
    ax.add_collection(coll)
    (a_lo, a_hi), (z_lo, z_hi) = cut.extent_m
    ax.set_xlim(a_lo * _MM, a_hi * _MM)
    ax.set_ylim(z_lo * _MM, z_hi * _MM)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{cut.across} [mm]")
    ax.set_ylabel("z [mm]")
    ax.set_title(f"cut {cut.normal} = {_MM * cut.position_m:.4g} mm "
                 f"({len(cut.indices)} beads within ±d/2)", fontsize=9, loc="left")
    if legend:
        present = list(dict.fromkeys(cut.families))
        ax.legend(handles=[Patch(facecolor=COLOURS.get(f, (0.5, 0.5, 0.5)), label=f)
                           for f in present], loc="lower right", bbox_to_anchor=(1.0, 1.0),
                  ncol=len(present) or 1, fontsize=8, frameon=False)
    return coll


def cut_height_in(cut: FabricCut, width_in: float) -> float:
    """Height [in] of a cut's axes at equal aspect for a figure ``width_in`` wide."""
    (a_lo, a_hi), (z_lo, z_hi) = cut.extent_m
    return float(np.clip(width_in * (z_hi - z_lo) / (a_hi - a_lo), 0.6, 6.0))


def cut_figure(model: BeadModel | FabricFrame, normal: str, position_m: float,
               title: str = "", width_in: float = 10.0):
    """A figure of one cut; returns ``(figure, cut)`` (close the figure when done)."""
    plt = _pyplot()
    cut = fabric_cut(_frame(model), normal, position_m)
    fig = plt.figure(figsize=(width_in, cut_height_in(cut, width_in) + 1.4), layout="constrained")
    ax = fig.add_subplot()
    draw_cut(ax, cut)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig, cut


def write_cut_csv(path: Path, cut: FabricCut, frame: FabricFrame) -> Path:
    """The beads of ``cut`` (1-based bead and fibre ids, family, in-plane position, distance
    from the plane and diameter [m]) as CSV."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["bead_id", "fibre_id", "family", f"{cut.across}_m", "z_m", "distance_m",
                    "diameter_m"])
        for k, i in enumerate(cut.indices):
            w.writerow([int(i) + 1, int(frame.fibre_ids[i]), cut.families[k],
                        repr(float(cut.points_m[k, 0])), repr(float(cut.points_m[k, 1])),
                        repr(float(cut.distances_m[k])), repr(float(cut.diameters_m[k]))])
    return Path(path)


def cut_png(model: BeadModel | FabricFrame, path: Path, normal: str, position_m: float,
            title: str = "") -> FabricCut | None:
    """Write one cut to ``path`` (PNG, 200 dpi) and its beads to ``path`` with ``.csv``."""
    if not mpi.is_root():
        return None
    frame = _frame(model)
    fig, cut = cut_figure(frame, normal, position_m, title)
    fig.savefig(path, dpi=200)
    _pyplot().close(fig)
    write_cut_csv(Path(path).with_suffix(".csv"), cut, frame)
    return cut


def cut_pngs(model: BeadModel | FabricFrame, folder: Path,
             positions: list[tuple[str, float]] | None = None, title: str = "",
             overview: str = "cuts.png") -> list[Path]:
    """One figure per cut (``cut_<normal>_<mm>mm.png`` + ``.csv``) and a grid overview
    (``overview``) of all of them in ``folder``; returns the files written (rank 0)."""
    if not mpi.is_root():
        return []
    frame = _frame(model)
    positions = positions or default_positions(frame)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    cuts = []
    for normal, pos in positions:
        path = folder / f"cut_{cut_label(normal, pos)}.png"
        cuts.append(cut_png(frame, path, normal, pos, title))
        written.append(path)
    plt = _pyplot()
    width = 10.0
    heights = [cut_height_in(c, width) + 0.5 for c in cuts]
    fig = plt.figure(figsize=(width, sum(heights) + 0.9), layout="constrained")
    grid = fig.add_gridspec(len(cuts), 1, height_ratios=heights)
    for k, c in enumerate(cuts):
        draw_cut(fig.add_subplot(grid[k]), c, legend=k == 0)
    fig.suptitle(title or "cuts through the fabric (beads within ±d/2 of each plane, "
                          "true size)", fontsize=10)
    fig.savefig(folder / overview, dpi=150)
    plt.close(fig)
    written.append(folder / overview)
    return written
