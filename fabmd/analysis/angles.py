"""Local in-plane yarn angles and the shear-angle field.

Every bead-to-bead segment of a fibre has an in-plane direction θ (from the x
axis, in the xy fabric plane). Yarn directions are axial (θ and θ + 180° are the
same yarn), so they are averaged per grid cell as doubled angles, weighted by
the segment's in-plane length: θ̄ = ½·atan2(Σ w sin 2θ, Σ w cos 2θ) in (−90°, 90°].

The shear angle of a cell is γ = 90° − (θ_weft − θ_warp), the difference taken
in [0°, 180°): 0 for an unsheared fabric, positive when the weft has turned
towards the warp.

A *zone* (a set of beads, e.g. those that start in the central square of a
picture-frame or bias-extension coupon: :func:`zone_mask`) has one mean axis per
family (:func:`family_axes_deg`: the segments whose two beads are in the zone);
:func:`zone_shear_angle_deg` is 90° minus the angle between two families' axes
measured across the sector that holds the direction the test stretches, so its sign
does not depend on which family runs at +45° in a bias coupon.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .frame import FabricFrame


@dataclass
class Field:
    """A scalar field on a regular xy grid (cell values; NaN where a cell has no data).

    ``values[j, i]`` belongs to the cell between ``x_edges_m[i:i+2]`` and
    ``y_edges_m[j:j+2]`` (the layout ``matplotlib.pcolormesh`` takes).
    """

    x_edges_m: np.ndarray
    y_edges_m: np.ndarray
    values: np.ndarray
    name: str
    unit: str
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def x_centres_m(self) -> np.ndarray:
        return 0.5 * (self.x_edges_m[1:] + self.x_edges_m[:-1])

    @property
    def y_centres_m(self) -> np.ndarray:
        return 0.5 * (self.y_edges_m[1:] + self.y_edges_m[:-1])

    @property
    def label(self) -> str:
        return f"{self.name} [{self.unit}]"

    def figure(self, **kwargs):
        """A matplotlib figure of the field with units on the axes and colour bar
        (keyword arguments go to :func:`fabmd.analysis.fieldplot.field_figure`)."""
        from .fieldplot import field_figure

        kwargs.setdefault("symmetric", self.unit == "°" and "shear" in self.name)
        return field_figure(self.x_edges_m, self.y_edges_m, self.values, self.label, **kwargs)

    def mean(self) -> float:
        """Mean over the cells that hold a value."""
        v = self.values[np.isfinite(self.values)]
        return float(v.mean()) if v.size else float("nan")


def fibre_segments(frame: FabricFrame, family: str | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bead-to-bead segments of the fibres of one family (or all): (first bead, second
    bead, vector [m]), with the segment that closes a periodic fibre (vector across the
    box by the nearest image)."""
    fibres = np.asarray([f for name in frame.yarns(family) for f in frame.fibres_of_yarn(name)],
                        np.int64)
    if not len(fibres):
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3))
    ids = frame.fibre_ids
    chosen = np.zeros(frame.n_fibres + 1, bool)
    chosen[fibres] = True
    a = np.flatnonzero((ids[:-1] == ids[1:]) & chosen[ids[:-1]])
    b = a + 1
    vec = frame.positions[b] - frame.positions[a]
    closed = fibres[frame.closed[fibres - 1]]
    if len(closed):
        first = np.asarray([frame.fibre_beads(f).start for f in closed], np.int64)
        last = np.asarray([frame.fibre_beads(f).stop - 1 for f in closed], np.int64)
        step = frame.minimum_image(frame.positions[first] - frame.positions[last])
        a, b = np.concatenate([a, last]), np.concatenate([b, first])
        vec = np.vstack([vec, step])
    return a, b, vec


def segment_directions(frame: FabricFrame, family: str | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Midpoints (wrapped into the box where periodic) and vectors of all fibre segments
    of one family (or all), including the segment that closes a periodic fibre [m]."""
    a, _, vec = fibre_segments(frame, family)
    if not len(a):
        return np.zeros((0, 3)), np.zeros((0, 3))
    return frame.wrap(frame.positions[a] + 0.5 * vec), vec


def _grid(frame: FabricFrame, points: np.ndarray, cells, extent):
    nx, ny = (int(c) for c in cells)
    if nx < 1 or ny < 1:
        raise InputError(f"cells must be two integers >= 1, got {cells}")
    if extent is None:
        lo = points[:, :2].min(axis=0) if len(points) else frame.box_lo[:2].copy()
        hi = points[:, :2].max(axis=0) if len(points) else frame.box_hi[:2].copy()
        pad = 1e-9 * np.maximum(hi - lo, 1e-12)  # points on the far edge stay inside
        lo, hi = lo - pad, hi + pad
        for k in range(2):
            if frame.periodic[k]:
                lo[k], hi[k] = frame.box_lo[k], frame.box_hi[k]
        if frame.periodic[0] and frame.tilt is not None:  # a sheared cell: its parallelogram
            lo[0] += min(0.0, frame.tilt[0])
            hi[0] += max(0.0, frame.tilt[0])
    else:
        (lo_x, hi_x), (lo_y, hi_y) = extent
        lo, hi = np.array([lo_x, lo_y], float), np.array([hi_x, hi_y], float)
    return np.linspace(lo[0], hi[0], nx + 1), np.linspace(lo[1], hi[1], ny + 1)


def _cell_index(points: np.ndarray, xe: np.ndarray, ye: np.ndarray):
    nx, ny = len(xe) - 1, len(ye) - 1
    i = np.searchsorted(xe, points[:, 0], side="right") - 1
    j = np.searchsorted(ye, points[:, 1], side="right") - 1
    inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
    return j[inside] * nx + i[inside], inside


def _axial_means(vectors: np.ndarray, index: np.ndarray, n: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Doubled-angle mean in-plane direction [rad] of the vectors in each of ``n`` groups
    (``index``: the group of each vector), weighted by in-plane length, and the summed
    in-plane length; NaN for a group without length or whose directions cancel."""
    v = np.asarray(vectors, float).reshape(-1, 3)
    w = np.hypot(v[:, 0], v[:, 1])
    theta = np.arctan2(v[:, 1], v[:, 0])
    c = np.bincount(index, w * np.cos(2 * theta), n)
    s = np.bincount(index, w * np.sin(2 * theta), n)
    weight = np.bincount(index, w, n)
    angle = 0.5 * np.arctan2(s, c)
    angle[(weight <= 0) | (np.hypot(c, s) <= 1e-12 * weight)] = np.nan
    return angle, weight


def _mean_axial_angle(points, vectors, xe, ye) -> tuple[np.ndarray, np.ndarray]:
    """Doubled-angle mean direction [rad] and summed in-plane length per cell."""
    nx, ny = len(xe) - 1, len(ye) - 1
    flat, inside = _cell_index(points, xe, ye)
    angle, weight = _axial_means(vectors[inside], flat, nx * ny)
    return angle.reshape(ny, nx), weight.reshape(ny, nx)


def in_plane_angle_field(frame: FabricFrame, family: str, cells=(10, 10),
                         extent=None) -> Field:
    """Local in-plane direction of the yarns of one family, in degrees from x.

    Args:
        frame: the fabric state.
        family: yarn family (e.g. ``"warp"``).
        cells: grid cells along x and y.
        extent: ((x_min, x_max), (y_min, y_max)) [m]; default: the box in periodic
            directions, else the extent of the fibres.
    """
    points, vectors = segment_directions(frame, family)
    xe, ye = _grid(frame, points, cells, extent)
    angle, weight = _mean_axial_angle(points, vectors, xe, ye)
    return Field(xe, ye, np.degrees(angle), f"{family} yarn angle", "°",
                 extra={"length_m": weight})


def shear_angle_field(frame: FabricFrame, warp: str = "warp", weft: str = "weft",
                      cells=(10, 10), extent=None) -> Field:
    """Shear angle γ = 90° − (θ_weft − θ_warp) per grid cell, in degrees.

    ``extra`` holds the warp and weft angle fields (``warp_angle_deg``,
    ``weft_angle_deg``). Cells without both families are NaN: make cells at least
    one yarn spacing wide.
    """
    pw, vw = segment_directions(frame, warp)
    pf, vf = segment_directions(frame, weft)
    if not len(pw) or not len(pf):
        raise InputError(f"shear angle needs yarns of both families {warp!r} and {weft!r}; "
                         f"the fabric has {frame.families}")
    xe, ye = _grid(frame, np.vstack([pw, pf]), cells, extent)
    tw, _ = _mean_axial_angle(pw, vw, xe, ye)
    tf, _ = _mean_axial_angle(pf, vf, xe, ye)
    between = np.mod(tf - tw, np.pi)
    gamma = np.degrees(0.5 * np.pi - between)
    return Field(xe, ye, gamma, "shear angle γ", "°",
                 extra={"warp_angle_deg": np.degrees(tw), "weft_angle_deg": np.degrees(tf)})


# -- zones: one mean axis per family ------------------------------------------------------
def zone_mask(positions: np.ndarray, centre, half_size) -> np.ndarray:
    """Beads whose in-plane position lies in the rectangle ``centre ± half_size`` [m]."""
    p = np.asarray(positions)[:, :2]
    return np.all(np.abs(p - np.asarray(centre, float)) <= np.asarray(half_size, float), axis=1)


def axial_mean_deg(vectors: np.ndarray) -> float | None:
    """Mean in-plane axis of segment vectors [deg, in (−90°, 90°]]: the doubled-angle mean
    weighted by in-plane length; None without segments (or when they cancel)."""
    v = np.asarray(vectors, float).reshape(-1, 3)
    angle, _ = _axial_means(v, np.zeros(len(v), np.int64), 1)
    return None if np.isnan(angle[0]) else float(np.degrees(angle[0]))


def family_axes_deg(frame: FabricFrame, mask: np.ndarray | None = None
                    ) -> dict[str, float | None]:
    """Mean in-plane axis of every family's fibre segments whose two beads are in ``mask``
    (default: all beads) [deg, in (−90°, 90°]; None for a family without segments there]."""
    mask = (np.ones(len(frame.positions), bool) if mask is None
            else np.asarray(mask, bool).reshape(-1))
    out: dict[str, float | None] = {}
    for family in frame.families:
        a, b, vec = fibre_segments(frame, family)
        out[family] = axial_mean_deg(vec[mask[a] & mask[b]])
    return out


def shear_between_axes_deg(axis_a: float, axis_b: float, reference_deg: float = 45.0) -> float:
    """90° minus the angle between two axes [deg] measured across the sector that holds
    ``reference_deg``: positive when that sector closes, 0 for axes at right angles."""
    a = (axis_a - reference_deg + 90.0) % 180.0 - 90.0  # in [-90, 90) about the reference
    b = (axis_b - reference_deg + 90.0) % 180.0 - 90.0
    sector = abs(a - b) if a * b <= 0 else 180.0 - abs(a - b)
    return 90.0 - sector


def zone_shear_angle_deg(frame: FabricFrame, mask: np.ndarray | None = None,
                         families: tuple[str, str] = ("warp", "weft"),
                         reference_deg: float = 45.0) -> float | None:
    """Signed shear angle between two families' mean axes in a zone [deg].

    Args:
        mask: the zone's beads (default: all).
        reference_deg: the direction the test stretches — the pulled diagonal of a
            picture frame (45°), the load axis of a bias-extension test (0°); the angle
            is measured across the sector that holds it (see :func:`shear_between_axes_deg`).

    Returns:
        None when a family has no segment in the zone.
    """
    axes = family_axes_deg(frame, mask)
    a, b = axes.get(families[0]), axes.get(families[1])
    if a is None or b is None:
        return None
    return shear_between_axes_deg(a, b, reference_deg)
