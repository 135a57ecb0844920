"""Yarn cross-sections: where a yarn's fibres cut the plane normal to its centreline.

At a station along the yarn (a fraction of its centreline's arc length) the
plane through the centreline point, normal to its tangent, cuts every fibre of
the yarn once; the cut points in the plane's own axes — ``w`` across the yarn
(in the fabric plane) and ``h`` through the thickness — form the section. Its
outline is their convex hull; width and height are their extent plus one fibre
diameter; an ellipse fitted by second moments (points filling an ellipse of
semi-axes a, b have variances a²/4, b²/4) gives a smooth width and height.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .frame import FabricFrame
from .yarns import FABRIC_NORMAL, resample, yarn_centreline


@dataclass
class CrossSection:
    """A yarn cross-section (SI; 2D coordinates in the section plane).

    Attributes:
        yarn: yarn name.
        centre_m: (3,) centreline point of the section.
        tangent: (3,) unit tangent of the centreline (the plane normal).
        axes: (2, 3) unit vectors of the ``w`` (across) and ``h`` (thickness) axes.
        points_m: (k, 2) fibre cut points (w, h) relative to the centre.
        hull_m: (m, 2) convex hull of the points, counter-clockwise.
        width_m, height_m: extent of the points along w and h plus one fibre diameter.
        area_m2: area of the hull of the fibre centres.
        ellipse_major_m, ellipse_minor_m: full axes 2a >= 2b of the moment-fitted
            ellipse of the fibre centres, plus one fibre diameter.
        ellipse_angle_rad: angle of the fitted major axis from the w axis.
    """

    yarn: str
    centre_m: np.ndarray
    tangent: np.ndarray
    axes: np.ndarray
    points_m: np.ndarray
    hull_m: np.ndarray
    width_m: float
    height_m: float
    area_m2: float
    ellipse_major_m: float
    ellipse_minor_m: float
    ellipse_angle_rad: float


def _turn(o, a, b) -> float:
    """z of (a − o) × (b − o): > 0 for a counter-clockwise turn."""
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def convex_hull(points) -> np.ndarray:
    """Convex hull of 2D points, counter-clockwise (Andrew's monotone chain)."""
    pts = np.unique(np.asarray(points, float).reshape(-1, 2), axis=0)
    if len(pts) < 3:
        return pts

    def half(seq):
        out: list[np.ndarray] = []
        for p in seq:
            while len(out) >= 2 and _turn(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out

    lower = half(pts)
    upper = half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def polygon_area(polygon) -> float:
    """Area of a simple polygon (shoelace) [m²]."""
    p = np.asarray(polygon, float).reshape(-1, 2)
    if len(p) < 3:
        return 0.0
    x, y = p[:, 0], p[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def plane_cut(path: np.ndarray, centre: np.ndarray, normal: np.ndarray) -> np.ndarray | None:
    """The point where a polyline crosses a plane, nearest to ``centre`` (or None)."""
    d = (path - centre) @ normal
    i = np.flatnonzero((d[:-1] <= 0) & (d[1:] > 0) | (d[:-1] >= 0) & (d[1:] < 0))
    if not len(i):
        return None
    t = d[i] / (d[i] - d[i + 1])
    cuts = path[i] + t[:, None] * (path[i + 1] - path[i])
    return cuts[np.argmin(np.linalg.norm(cuts - centre, axis=1))]


def cross_section(frame: FabricFrame, yarn: str | int, station: float = 0.5,
                  stations: int | None = None, up=FABRIC_NORMAL) -> CrossSection:
    """Cross-section of ``yarn`` at ``station`` (fraction of its centreline length).

    Args:
        frame: the fabric state.
        yarn: yarn name or 1-based id.
        station: where along the yarn, in [0, 1].
        stations: centreline resolution (default: beads of the longest fibre).
        up: the fabric normal; the ``h`` axis is its part normal to the yarn.
    """
    if not 0.0 <= station <= 1.0:
        raise InputError(f"cross_section.station must be in [0, 1], got {station:g}")
    name = frame.yarn_names[frame.yarn_id(yarn) - 1]
    line = yarn_centreline(frame, yarn, stations)
    delta = 0.5 / (len(line) - 1)
    a, c, b = resample(line, np.clip([station - delta, station, station + delta], 0, 1))
    tangent = (b - a) / np.linalg.norm(b - a)
    up = np.asarray(up, float)
    h_axis = up - np.dot(up, tangent) * tangent
    if np.linalg.norm(h_axis) < 1e-9:
        raise InputError(f"yarn {name} runs along the fabric normal at station {station:g}")
    h_axis /= np.linalg.norm(h_axis)
    w_axis = np.cross(h_axis, tangent)
    cuts = [plane_cut(p, c, tangent) for p in frame.yarn_paths(yarn)]
    cuts = np.array([q for q in cuts if q is not None]).reshape(-1, 3)
    if not len(cuts):
        raise InputError(f"no fibre of yarn {name} crosses its section at station {station:g}")
    pts = np.column_stack([(cuts - c) @ w_axis, (cuts - c) @ h_axis])
    hull = convex_hull(pts)
    d = frame.fibre_diameter(yarn)
    if len(pts) >= 2:
        centred = pts - pts.mean(axis=0)
        cov = centred.T @ centred / len(pts)
        eigval, eigvec = np.linalg.eigh(cov)
        eigval = np.clip(eigval, 0.0, None)
        major, minor = 4.0 * np.sqrt(eigval[1]), 4.0 * np.sqrt(eigval[0])
        angle = float(np.arctan2(eigvec[1, 1], eigvec[0, 1]))
        angle = (angle + np.pi / 2) % np.pi - np.pi / 2
    else:
        major = minor = angle = 0.0
    return CrossSection(
        yarn=name, centre_m=c, tangent=tangent, axes=np.vstack([w_axis, h_axis]),
        points_m=pts, hull_m=hull, width_m=float(np.ptp(pts[:, 0]) + d),
        height_m=float(np.ptp(pts[:, 1]) + d), area_m2=polygon_area(hull),
        ellipse_major_m=float(major + d), ellipse_minor_m=float(minor + d),
        ellipse_angle_rad=angle)


# -- fabric cuts: thin planar slices through the whole fabric -------------------------------
#: the in-plane axis a cut normal to x (y) shows besides z
_CUT_AXES = {"x": (0, 1), "y": (1, 0)}


@dataclass
class FabricCut:
    """A thin planar cut through a whole fabric, as a micro-CT slice shows it (SI).

    The plane is normal to ``normal`` (``"x"``: the warp direction, so it shows the weft
    paths and the warp cut across; ``"y"``: the reverse) at ``position_m``. A bead is in
    the cut when the plane passes through it: |distance| ≤ its radius (a slice one bead
    diameter thick).

    Attributes:
        normal, position_m: the plane.
        indices: (k,) 0-based bead indices in the cut, ordered by bead.
        points_m: (k, 2) bead centres in the plane: (coordinate along the other in-plane
            axis, z).
        distances_m: (k,) signed distance of every bead centre from the plane.
        diameters_m: (k,) bead diameters.
        families: (k,) yarn family of every bead in the cut.
        extent_m: ((lo, hi) along the other in-plane axis, (lo, hi) in z): the whole
            fabric's extent (bead surfaces; the box along a periodic axis).
    """

    normal: str
    position_m: float
    indices: np.ndarray
    points_m: np.ndarray
    distances_m: np.ndarray
    diameters_m: np.ndarray
    families: list[str]
    extent_m: tuple[tuple[float, float], tuple[float, float]]

    @property
    def across(self) -> str:
        """Name of the in-plane axis the cut shows (``"y"`` for a cut normal to x)."""
        return "y" if self.normal == "x" else "x"


def fabric_cut(frame: FabricFrame, normal: str, position_m: float,
               half_thickness_m: float | np.ndarray | None = None) -> FabricCut:
    """The beads a plane normal to ``normal`` at ``position_m`` [m] passes through.

    Args:
        frame: the fabric state (needs ``diameters``).
        normal: ``"x"`` or ``"y"``.
        position_m: where the plane is, in the model's coordinates [m]; along a periodic
            axis any value (taken modulo the period), else within the fabric's extent.
        half_thickness_m: half the slice thickness [m] (default: each bead's radius, so
            exactly the beads the plane cuts).

    Raises:
        InputError: unknown ``normal``, a position outside the fabric, no diameters.
    """
    if normal not in _CUT_AXES:
        raise InputError(f"cut normal must be 'x' or 'y', got {normal!r}")
    if frame.diameters is None:
        raise InputError("a fabric cut needs the bead diameters (frame.diameters is None)")
    axis, other = _CUT_AXES[normal]
    pos = frame.wrap(frame.positions) if any(frame.periodic) else frame.positions
    d = frame.diameters
    radius = 0.5 * float(d.max())
    position_m = float(position_m)
    if frame.periodic[axis]:
        lo_n, hi_n = frame.box_lo[axis], frame.box_hi[axis]
    else:
        lo_n = float((pos[:, axis] - 0.5 * d).min())
        hi_n = float((pos[:, axis] + 0.5 * d).max())
        if not lo_n <= position_m <= hi_n:
            raise InputError(f"cut position {normal} = {1e3 * position_m:.4g} mm is outside "
                             f"the fabric ({1e3 * lo_n:.4g} to {1e3 * hi_n:.4g} mm)")
    dist = pos[:, axis] - position_m
    if frame.periodic[axis]:
        period = hi_n - lo_n
        dist = dist - period * np.round(dist / period)
    half = 0.5 * d if half_thickness_m is None else np.broadcast_to(
        np.asarray(half_thickness_m, float), d.shape)
    idx = np.flatnonzero(np.abs(dist) <= half)
    if frame.periodic[other]:
        across = (float(frame.box_lo[other]), float(frame.box_hi[other]))
    else:
        across = (float(pos[:, other].min()) - radius, float(pos[:, other].max()) + radius)
    z = (float(pos[:, 2].min()) - radius, float(pos[:, 2].max()) + radius)
    yarn_of_bead = frame.fibre_yarn[frame.fibre_ids[idx] - 1] - 1
    return FabricCut(normal=normal, position_m=position_m, indices=idx,
                     points_m=np.column_stack([pos[idx, other], pos[idx, 2]]),
                     distances_m=dist[idx], diameters_m=d[idx].copy(),
                     families=[frame.yarn_families[y] for y in yarn_of_bead],
                     extent_m=(across, z))
