"""What a drape writes besides its curve and summary: the shear-angle field (CSV, NPZ, PNG
map), the final shape (``final.vtu`` with point data, ``shape.png``: top view and a section
along the warp) and the specifications of its curve plots (lengths in m, forces in N).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...engine import mpi
from ...model.bead_model import BeadModel
from ...results.folder import write_csv
from ...results.plots import plot_field
from .geometry import DrapeGeometry

if TYPE_CHECKING:
    from ...analysis.angles import Field
    from .protocol import Drape


def plot_specs(depth: np.ndarray, punch: np.ndarray, holder: np.ndarray, set_force: float,
               notes: str, max_holder_error: float | None) -> list[dict]:
    """Keyword sets of the punch-force and holder-force plots (``DrivenResult.plots``);
    ``depth`` [m], forces [N] for the whole blank."""
    return [
        {"path": "curve.png", "series": [{"x": 1e3 * depth, "y": punch, "label": "punch"}],
         "xlabel": "depth [mm]", "ylabel": "punch force [N]",
         "title": "Hemispherical punch drape", "notes": notes},
        {"path": "holder_force.png",
         "series": [{"x": 1e3 * depth, "y": holder, "label": "blank holder"},
                    {"x": [0.0, 1e3 * float(depth[-1])], "y": [set_force, set_force],
                     "style": "--", "label": "target force", "lw": 1.0}],
         "xlabel": "depth [mm]", "ylabel": "blank-holder force [N]",
         "title": "Blank-holder force (force control)",
         "notes": f"max error after clamping {max_holder_error:.3g}"
         if max_holder_error is not None else ""},
    ]


def write_final(run_dir: Path, model: BeadModel, final: BeadModel, fld: Field,
                g: DrapeGeometry, test: Drape, travel: float) -> None:
    """Shear-angle data and map, the final shape (VTU + PNG); rank 0. ``travel``: the
    punch's final travel [m]."""
    if not mpi.is_root():
        return
    import meshio

    from ...results.vtu import _legend, _open_bonds, _write

    xc, yc = np.meshgrid(fld.x_centres_m, fld.y_centres_m)
    write_csv(run_dir / "shear_angle.csv", {
        "x_m": xc.ravel(), "y_m": yc.ravel(), "shear_angle_deg": fld.values.ravel(),
        "warp_beads": fld.extra["warp_beads"].ravel(),
        "weft_beads": fld.extra["weft_beads"].ravel()})
    np.savez_compressed(run_dir / "shear_angle.npz", x_edges_m=fld.x_edges_m,
                        y_edges_m=fld.y_edges_m, shear_angle_deg=fld.values,
                        bead_shear_angle_deg=fld.extra["bead_shear_deg"],
                        reference_positions_m=model.positions, final_positions_m=final.positions)
    plot_field(run_dir / "shear_angle.png", fld.x_edges_m, fld.y_edges_m, fld.values,
               "shear angle γ [°]", symmetric=True, aspect="equal",
               xlabel="x (warp), initial", ylabel="y (weft), initial",
               title=f"Shear angle after {1e3 * test.depth_m:g} mm "
                     f"({'quarter' if g.quarter else 'full'} model)")
    # final shape: fibres with point data
    centre = np.array([0.0, 0.0, g.punch_z_m - travel])
    dev = np.linalg.norm(final.positions - centre, axis=1) - g.radius_m - 0.5 * g.thickness_m
    keep = _open_bonds(final)
    bonds = final.bonds[keep]
    mesh = meshio.Mesh(
        points=final.positions, cells=[("line", bonds.astype(np.int64))],
        point_data={"diameter_m": final.diameters, "family": final.atom_types.astype(np.int32),
                    "yarn_id": final.yarn_ids.astype(np.int32),
                    "displacement_m": final.positions - model.positions,
                    "shear_angle_deg": fld.extra["bead_shear_deg"],
                    "punch_distance_m": dev},
        cell_data={"fibre_id": [final.fibre_ids[bonds[:, 0]].astype(np.int32)]})
    _write(run_dir / "final.vtu", mesh, _legend(final))
    shape_png(run_dir / "shape.png", model, final, g, travel)


def shape_png(path: Path, model: BeadModel, final: BeadModel, g: DrapeGeometry,
              travel: float) -> None:
    """Top view of the draped blank coloured by height, and a section along the warp
    (``travel``: the punch's final travel [m])."""
    from ...results.plots import _pyplot

    plt = _pyplot()
    p0, p = model.positions, final.positions
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained")
    sc = ax.scatter(1e3 * p[:, 0], 1e3 * p[:, 1], c=1e3 * (p[:, 2] - p0[:, 2]), s=1.0,
                    cmap="viridis")
    fig.colorbar(sc, ax=ax, label="vertical displacement [mm]")
    hx, hy = g.half_size_m
    xs = [0, hx, hx, 0] if g.quarter else [-hx, hx, hx, -hx, -hx]
    ys = [hy, hy, 0, 0] if g.quarter else [-hy, -hy, hy, hy, -hy]
    ax.plot(1e3 * np.asarray(xs), 1e3 * np.asarray(ys), "k--", lw=0.8, label="blank before")
    t = np.linspace(0, np.pi / 2 if g.quarter else 2 * np.pi, 200)
    ax.plot(1e3 * g.die_radius_m * np.cos(t), 1e3 * g.die_radius_m * np.sin(t), "r-", lw=0.8,
            label="die opening")
    ax.set_aspect("equal")
    ax.set_xlabel("x (warp) [mm]")
    ax.set_ylabel("y (weft) [mm]")
    ax.set_title("Draped blank, top view", fontsize=10)
    band = np.abs(p0[:, 1]) < g.spacing_m
    bx.scatter(1e3 * p[band, 0], 1e3 * p[band, 2], s=1.0, c="tab:blue", label="fabric")
    zc = g.punch_z_m - travel
    # the punch over the modelled part only (x >= 0 for a quarter model)
    t = np.linspace(-np.pi / 2 if g.quarter else -np.pi / 2 - 1.2, -np.pi / 2 + 1.2, 200)
    bx.plot(1e3 * g.radius_m * np.cos(t), 1e3 * (zc + g.radius_m * np.sin(t)), "k-", lw=1.0,
            label="punch")
    lo = 0.0 if g.quarter else -hx
    for side in ((lo, -g.die_radius_m), (g.die_radius_m, hx)) if not g.quarter else \
            ((g.die_radius_m, hx),):
        bx.plot(1e3 * np.asarray(side), [1e3 * g.z_die_m] * 2, "r-", lw=1.5,
                label="die" if side[1] == hx else None)
    bx.set_aspect("equal")
    bx.set_xlabel("x (warp) [mm]")
    bx.set_ylabel("z [mm]")
    bx.set_title("Section along the warp\n(beads starting within one spacing of y = 0)",
                 fontsize=10)
    # one legend below both panels: never on the fibres
    handles, labels = [], []
    for a in (ax, bx):
        h, lab = a.get_legend_handles_labels()
        handles += h
        labels += lab
    fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), frameon=False,
               fontsize=8, markerscale=4)
    fig.savefig(path, dpi=150)
    plt.close(fig)
