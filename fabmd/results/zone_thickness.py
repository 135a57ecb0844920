"""How much thicker a picture frame's fabric grows next to its clamps than at its centre.

The clamps hold every fibre end at the frame's affine place, so the yarns that run into a
clamp narrow there as w·cos γ, while in the middle of the free square they keep their
width as in a periodic cell. Compacted that way, the band next to the clamps thickens, and
the fibres held at both ends stretch with it: on a small coupon that stretch is much of the
frame force past 15–20° (benchmarks/RESULTS.md "The picture frame's edges"). The band does
not grow with the coupon (about one yarn spacing), so its share of the force falls as the
coupon grows and the frame's force falls towards the periodic cell's.

Zones are material: beads are assigned by where they start. The *centre* is the square
half the free side wide (the zone of the fibre shear angle); the *edge band* is the rest of
the free square (a quarter of the free side wide). A zone's thickness is the span of its
bead centres through the thickness (1st to 99th percentile, so a stray bead does not set
it) plus the mean bead diameter.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.trajectory_file import TRAJECTORY_FILE

#: the shear angles at which both zones' thicknesses are reported [deg]
REPORT_ANGLES_DEG = (10.0, 20.0, 30.0, 40.0)


def zone_thickness_m(z: np.ndarray, diameter_m: float) -> float:
    """Thickness [m] of a zone with bead centres at heights ``z``: 1st-99th percentile span
    plus one bead diameter (NaN for an empty zone)."""
    z = np.asarray(z, float)
    if z.size == 0:
        return float("nan")
    lo, hi = np.percentile(z, [1.0, 99.0])
    return float(hi - lo + diameter_m)


def zone_masks(xy: np.ndarray, inner, centre) -> tuple[np.ndarray, np.ndarray]:
    """(centre, edge band) masks of the beads at in-plane positions ``xy`` (the start):
    the centre square is half the free square ``inner`` (x_lo, x_hi, y_lo, y_hi) wide and
    centred on ``centre``; the band is the rest of the free square."""
    x_lo, x_hi, y_lo, y_hi = inner
    xy = np.asarray(xy, float)
    free = (xy[:, 0] >= x_lo) & (xy[:, 0] <= x_hi) & (xy[:, 1] >= y_lo) & (xy[:, 1] <= y_hi)
    half = (0.25 * (x_hi - x_lo), 0.25 * (y_hi - y_lo))
    middle = ((np.abs(xy[:, 0] - centre[0]) <= half[0])
              & (np.abs(xy[:, 1] - centre[1]) <= half[1]))
    return middle & free, free & ~middle


def frame_zone_thickness(run_dir: Path, inner, centre) -> dict[str, np.ndarray]:
    """Per frame of ``run_dir/trajectory.h5``: its ``step`` and the ``centre_m`` and
    ``edge_m`` thicknesses [m] (empty arrays without a trajectory)."""
    from ..analysis import FabricFrame

    path = Path(run_dir) / TRAJECTORY_FILE
    out = {"step": [], "centre_m": [], "edge_m": []}
    if path.exists():
        masks, diameter = None, 0.0
        for frame in FabricFrame.iter_trajectory(path):
            if masks is None:
                masks = zone_masks(frame.positions[:, :2], inner, centre)
                diameter = (float(np.mean(frame.diameters)) if frame.diameters is not None
                            else 0.0)
            out["step"].append(frame.step)
            out["centre_m"].append(zone_thickness_m(frame.positions[masks[0], 2], diameter))
            out["edge_m"].append(zone_thickness_m(frame.positions[masks[1], 2], diameter))
    return {k: np.asarray(v, float if k != "step" else np.int64) for k, v in out.items()}


def zone_summary(angle_deg, centre_m, edge_m) -> dict:
    """The summary's ``zone_thickness`` block: both zones' thickness per frame and at the
    report angles the run reached, and the edge band's thickening beyond the centre's
    there, as a share of the centre's first thickness ((Δh_edge − Δh_centre) / h_centre)."""
    angle = np.asarray(angle_deg, float)
    centre, edge = np.asarray(centre_m, float), np.asarray(edge_m, float)
    at = {}
    for a in REPORT_ANGLES_DEG:
        if angle.size and angle.max() >= a:
            c, e = float(np.interp(a, angle, centre)), float(np.interp(a, angle, edge))
            at[f"{a:g}"] = {"centre_m": c, "edge_m": e,
                            "edge_excess": ((e - edge[0]) - (c - centre[0])) / centre[0]}
    return {"zones": "centre: the square half the free side wide; edge band: the rest of "
                     "the free square (beads assigned where they start)",
            "thickness": "1-99 % span of the bead centres through the thickness + a bead "
                         "diameter",
            "shear_angle_deg": angle.tolist(), "centre_m": centre.tolist(),
            "edge_m": edge.tolist(), "at_angle": at}
