"""Measures of the draped shape against the flat blank: the shear-angle grid, wrinkling over
the punch cap, edge draw-in and the whole blank's in-plane shear (positions in m, angles in
degrees).
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import DrapeGeometry


def shear_grid(g: DrapeGeometry, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Cell edges anchored on the symmetry lines, covering the model's blank."""
    from ...analysis.surface import grid_edges

    hx, hy = g.half_size_m
    pad = 0.5 * g.spacing_m
    lo_x, lo_y = (0.0, 0.0) if g.quarter else (-hx - pad, -hy - pad)
    return (grid_edges(lo_x, hx + pad, cell), grid_edges(lo_y, hy + pad, cell))


def wrinkling(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry,
              travel: float) -> dict:
    """Out-of-surface deviation of the beads over the punch cap (where a taut fabric lies on
    the punch): distance to the sphere minus half the fabric thickness."""
    centre = np.array([0.0, 0.0, g.punch_z_m - travel])
    rel = final - centre
    dist = np.linalg.norm(rel, axis=1)
    polar = np.arccos(np.clip(-rel[:, 2] / np.maximum(dist, 1e-300), -1, 1))
    zone = polar < 0.9 * g.contact_angle_rad
    dev = dist - g.radius_m - 0.5 * g.thickness_m
    out = {"zone": "beads over the punch cap within 0.9 x the contact angle",
           "contact_angle_deg": math.degrees(g.contact_angle_rad),
           "beads": int(zone.sum()), "fabric_thickness_m": g.thickness_m,
           "lying_band_m": 0.5 * (g.thickness_m - g.diameter_m),
           "note": "deviation = distance to the punch sphere - R - t/2; a fabric lying on "
                   "the punch has |deviation| <= (t - d)/2 (its bead layers, lying_band_m); "
                   "wrinkle_height_m: how far the largest deviation exceeds that band"}
    if zone.any():
        out.update(max_deviation_m=float(dev[zone].max()),
                   rms_deviation_m=float(np.sqrt(np.mean(dev[zone] ** 2))),
                   min_deviation_m=float(dev[zone].min()),
                   wrinkle_height_m=max(0.0, float(dev[zone].max()) - out["lying_band_m"]))
    else:
        out.update(max_deviation_m=None, rms_deviation_m=None, min_deviation_m=None,
                   wrinkle_height_m=None)
    return out


def draw_in(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry) -> dict:
    """In-plane displacement of the blank's edge towards the centre [m] along warp (x),
    weft (y) and the diagonal; mean over the edge beads within a yarn spacing of where each
    direction meets the edge (symmetric directions averaged in the full model)."""
    hx, hy = g.half_size_m
    s = g.spacing_m
    x, y = reference[:, 0], reference[:, 1]
    u = final[:, :2] - reference[:, :2]
    signs = [(1, 1)] if g.quarter else [(1, 1), (-1, 1), (1, -1), (-1, -1)]
    result = {}
    for name in ("warp", "weft", "diagonal"):
        values = []
        for sx, sy in signs:
            if name == "warp":
                sel = (sx * x > hx - s) & (np.abs(y) < s) & (sy * y >= 0)
                e = np.array([sx, 0.0])
            elif name == "weft":
                sel = (sy * y > hy - s) & (np.abs(x) < s) & (sx * x >= 0)
                e = np.array([0.0, sy])
            else:
                sel = (sx * x > hx - s) & (sy * y > hy - s)
                e = np.array([sx, sy]) / math.sqrt(2)
            if sel.any():
                values.append(float(-(u[sel] @ e).mean()))
        result[f"{name}_m"] = float(np.mean(values)) if values else None
    result["note"] = ("in-plane displacement of the edge beads towards the centre, within a "
                      "yarn spacing of the edge point along x (warp), y (weft) and the corner "
                      "(diagonal)")
    result["blank_shear_deg"] = None if g.quarter else blank_shear_deg(reference, final, g)
    return result


def blank_shear_deg(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry) -> float:
    """Engineering shear of the whole blank in its plane, from its edges [deg]:
    mean(sign(x)·u_y)/hx over the two edges across x plus mean(sign(y)·u_x)/hy over the two
    across y (corners left out). A rigid turn and a pure draw-in give 0. Zero by
    construction in the quarter model, whose mirror planes forbid it; non-zero in the full
    model, it is a mode the quarter model cannot show."""
    hx, hy = g.half_size_m
    s = g.spacing_m
    x, y = reference[:, 0], reference[:, 1]
    u = final[:, :2] - reference[:, :2]
    across_x = (np.abs(x) > hx - s) & (np.abs(y) < hy - s)
    across_y = (np.abs(y) > hy - s) & (np.abs(x) < hx - s)
    shear = (np.mean(np.sign(x[across_x]) * u[across_x, 1]) / hx
             + np.mean(np.sign(y[across_y]) * u[across_y, 0]) / hy)
    return float(np.degrees(shear))


def punch_reach(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry, travel: float,
                zone_radius_m: float) -> dict:
    """How far out the fabric that touches the punch at the end started [m], against the
    radius of the zone of beads given punch contact (``zone_radius_m``): a bead from
    beyond the zone would pass through the punch, so ``zone_holds`` must be true.

    Touching: centre within R + 0.75 d of the punch centre at its final ``travel`` [m].
    """
    centre = np.array([0.0, 0.0, g.punch_z_m - travel])
    touching = np.linalg.norm(final - centre, axis=1) < g.radius_m + 0.75 * g.diameter_m
    r0 = np.hypot(reference[:, 0], reference[:, 1])
    furthest = float(r0[touching].max()) if touching.any() else None
    return {"punch_zone_radius_m": zone_radius_m,
            "furthest_touching_start_radius_m": furthest,
            "touching_beads": int(touching.sum()),
            "zone_holds": furthest is None or furthest <= zone_radius_m,
            "note": "start radius of the furthest bead touching the punch at the end "
                    "(centre within R + 0.75 d of the punch centre) against the radius of "
                    "the beads given punch contact"}
