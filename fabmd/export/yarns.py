"""Yarn reconstruction: each yarn's centreline, cross-section envelope, fibre direction
and yarn fibre volume fraction at stations along it, from the virtual fibres of a state.

* **stations** — equal arc-length fractions of every fibre of the yarn; the centreline
  point is the mean of the fibres' points there (as :mod:`fabmd.analysis.yarns`). A
  periodic (closed) yarn has ``n`` distinct stations over exactly one period; station
  ``n`` is station 0 shifted by the yarn's ``period_m`` vector, so the yarn stays periodic.
* **section frame** — ``u`` across the yarn (horizontal: z × tangent), ``v`` = tangent × u
  (through the thickness for an in-plane yarn).
* **envelope** — the convex hull of the fibre centres in the section plane grown by one
  fibre radius (the fibres' own extent), stored as its radial function R(θ) about the
  centreline point at ``angles`` equal angles θ from ``u`` towards ``v``, then smoothed
  along the yarn (``smoothing`` passes of a [1, 2, 1]/4 filter).
* **fibre direction** — the mean unit tangent of the fibres at the station.
* **yarn fibre volume fraction** — filament volume per unit centreline length,
  A_f·Σ|dP_f/ds|, over the envelope area: the filament volume of a thin slice of the
  yarn divided by the slice's volume, so the fraction integrated over the yarn volume
  gives back the bead model's filament volume.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..analysis.frame import FabricFrame
from ..analysis.yarns import resample
from ..errors import InputError

#: directions sampled for the support function of the envelope (outer polygon)
_SUPPORT_DIRECTIONS = 128


@dataclass
class YarnGeometry:
    """One reconstructed yarn (SI; ``n`` stations, ``m`` envelope angles).

    Attributes:
        yarn_id: 1-based yarn id of the bead model (0 is the matrix in voxel meshes).
        name, family: the yarn's name and family.
        closed: True for a periodic yarn (station ``n`` = station 0 + ``period_m``).
        period_m: (3,) shift from the first station to the one after the last [m].
        centres_m: (n, 3) centreline points [m].
        tangents: (n, 3) unit centreline tangents (normals of the section planes).
        axes_u, axes_v: (n, 3) unit section axes (across, through the thickness).
        radii_m: (n, m) envelope radius at angle θ_k = 2πk/m from u towards v [m].
        directions: (n, 3) unit mean fibre direction (pointing along the tangent).
        fibre_volume_fraction: (n,) yarn fibre volume fraction.
        area_m2: (n,) envelope area [m²].
    """

    yarn_id: int
    name: str
    family: str
    closed: bool
    period_m: np.ndarray
    centres_m: np.ndarray
    tangents: np.ndarray
    axes_u: np.ndarray
    axes_v: np.ndarray
    radii_m: np.ndarray
    directions: np.ndarray
    fibre_volume_fraction: np.ndarray
    area_m2: np.ndarray

    @property
    def n_stations(self) -> int:
        return len(self.centres_m)

    @property
    def n_angles(self) -> int:
        return self.radii_m.shape[1]

    def ring_points(self) -> np.ndarray:
        """(n, m, 3) envelope points at every station and angle [m]."""
        theta = 2 * np.pi * np.arange(self.n_angles) / self.n_angles
        c, s = np.cos(theta), np.sin(theta)
        offset = (c[None, :, None] * self.axes_u[:, None, :]
                  + s[None, :, None] * self.axes_v[:, None, :])
        return self.centres_m[:, None, :] + self.radii_m[:, :, None] * offset

    def extended(self, ghosts: int = 3) -> YarnGeometry:
        """A closed yarn with ``ghosts`` stations copied, shifted by one period, before its
        first and after its last (so points near the seam find both sides); an open yarn
        unchanged."""
        if not self.closed or ghosts <= 0:
            return self
        g = min(ghosts, self.n_stations)

        def wrap(a, shift=None):
            head, tail = a[-g:], a[:g]
            if shift is not None:
                head, tail = head - shift, tail + shift
            return np.concatenate([head, a, tail])

        return YarnGeometry(self.yarn_id, self.name, self.family, False, self.period_m,
                            wrap(self.centres_m, self.period_m), wrap(self.tangents),
                            wrap(self.axes_u), wrap(self.axes_v), wrap(self.radii_m),
                            wrap(self.directions), wrap(self.fibre_volume_fraction),
                            wrap(self.area_m2))

    def volume_m3(self) -> float:
        """Envelope volume: Σ area × centreline length per station [m³]."""
        return float(np.sum(self.area_m2 * _station_lengths(self.centres_m, self.closed,
                                                            self.period_m)))


def _station_lengths(centres: np.ndarray, closed: bool, period: np.ndarray) -> np.ndarray:
    """Centreline length belonging to each station (half of each neighbouring segment)."""
    if closed:
        nxt = np.vstack([centres[1:], centres[:1] + period])
        seg = np.linalg.norm(nxt - centres, axis=1)
        return 0.5 * (seg + np.roll(seg, 1))
    seg = np.linalg.norm(np.diff(centres, axis=0), axis=1)
    out = np.zeros(len(centres))
    out[:-1] += 0.5 * seg
    out[1:] += 0.5 * seg
    return out


def _derivative(points: np.ndarray, closed: bool, period: np.ndarray) -> np.ndarray:
    """d points / d station (central differences; periodic for a closed yarn)."""
    if closed:
        nxt = np.concatenate([points[1:], points[:1] + period], axis=0)
        prv = np.concatenate([points[-1:] - period, points[:-1]], axis=0)
        return 0.5 * (nxt - prv)
    return np.gradient(points, axis=0)


def _smooth(values: np.ndarray, closed: bool, passes: int) -> np.ndarray:
    """``passes`` of a [1, 2, 1]/4 filter along axis 0 (periodic or end-replicated)."""
    v = np.array(values, float)
    for _ in range(passes):
        if closed:
            prv, nxt = np.roll(v, 1, axis=0), np.roll(v, -1, axis=0)
        else:
            prv = np.concatenate([v[:1], v[:-1]], axis=0)
            nxt = np.concatenate([v[1:], v[-1:]], axis=0)
        v = 0.25 * prv + 0.5 * v + 0.25 * nxt
    return v


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def section_axes(tangents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit section axes (u, v) for unit tangents (n, 3): u = z × t (across the yarn,
    horizontal), v = t × u; a tangent within 18° of z takes u = y × t instead."""
    t = np.asarray(tangents, float)
    ref = np.tile([0.0, 0.0, 1.0], (len(t), 1))
    ref[np.abs(t[:, 2]) > 0.95] = [0.0, 1.0, 0.0]
    u = _unit(np.cross(ref, t))
    return u, np.cross(t, u)


def envelope_radii(points_uv: np.ndarray, radius_m: float, angles: int) -> np.ndarray:
    """Radial function of (convex hull of ``points_uv`` ⊕ disk of ``radius_m``) about the
    origin, at ``angles`` equal angles [m].

    ``points_uv`` is (n, k, 2) (n sections of k points each, the origin inside their
    hull). The support function h(φ) = max_k p_k·e(φ) + r is sampled at 128 directions;
    R(θ) = min over |φ − θ| < 90° of h(φ)/cos(φ − θ) (the outer polygon, within
    r·(1/cos(π/128) − 1) of the exact envelope).
    """
    phi = 2 * np.pi * np.arange(_SUPPORT_DIRECTIONS) / _SUPPORT_DIRECTIONS
    e = np.column_stack([np.cos(phi), np.sin(phi)])
    h = np.einsum("nkd,pd->nkp", points_uv, e).max(axis=1) + radius_m  # (n, P)
    theta = 2 * np.pi * np.arange(angles) / angles
    cos = np.cos(phi[None, :] - theta[:, None])  # (m, P)
    with np.errstate(divide="ignore"):
        ratio = np.where(cos[None] > 1e-9, h[:, None, :] / cos[None], np.inf)
    return ratio.min(axis=2)


def polar_area(radii: np.ndarray) -> np.ndarray:
    """Area of the outline r = R(θ), R linear in θ between the samples (as
    :func:`fabmd.export.voxel.locate` reads it): ½∫R² dθ = Δθ/6 Σ (R_k² + R_k R_k+1 + R_k+1²)."""
    m = radii.shape[-1]
    nxt = np.roll(radii, -1, axis=-1)
    return (np.pi / m / 3.0) * np.sum(radii**2 + radii * nxt + nxt**2, axis=-1)


def reconstruct_yarn(frame: FabricFrame, yarn: str | int, fibre_area_m2: float,
                     stations: int | None = None, angles: int = 24, smoothing: int = 2
                     ) -> YarnGeometry:
    """Reconstruct one yarn of a frame (see the module docstring).

    Args:
        frame: the state (unwrapped positions, fibre diameters).
        yarn: yarn name or 1-based id.
        fibre_area_m2: filament area of one virtual fibre of this yarn [m²].
        stations: stations along the yarn (default: bead count of its longest fibre).
        angles: envelope angles per station (>= 8).
        smoothing: passes of the [1, 2, 1]/4 filter on the envelope along the yarn.
    """
    if angles < 8:
        raise InputError(f"angles must be >= 8, got {angles}")
    if not fibre_area_m2 > 0:
        raise InputError(f"fibre_area_m2 must be > 0, got {fibre_area_m2}")
    yid = frame.yarn_id(yarn)
    fibres = frame.fibres_of_yarn(yid)
    closed = bool(frame.closed[np.asarray(fibres) - 1].all())
    paths = frame.yarn_paths(yid, close=closed)
    n = int(stations or max(len(p) - (1 if closed else 0) for p in paths))
    if n < 3:
        raise InputError(f"yarn {frame.yarn_names[yid - 1]}: needs >= 3 stations, got {n}")
    axis = paths[0][-1] - paths[0][0]
    u = np.linspace(0.0, 1.0, n + 1 if closed else n)
    pts = []
    for p in paths:
        if np.dot(p[-1] - p[0], axis) < 0:
            p = p[::-1]
        pts.append(resample(p, u))
    pts = np.stack(pts)  # (k fibres, n(+1), 3)
    period = np.zeros(3)
    if closed:
        period = np.mean(pts[:, -1] - pts[:, 0], axis=0)
        pts = pts[:, :-1]
    centres = pts.mean(axis=0)
    dc = _derivative(centres, closed, period)
    tangents = _unit(dc)
    fibre_d = np.stack([_derivative(q, closed, period) for q in pts])  # (k, n, 3)
    directions = _unit(_unit(fibre_d).sum(axis=0))
    directions *= np.sign(np.einsum("ij,ij->i", directions, tangents))[:, None]
    axes_u, axes_v = section_axes(tangents)
    rel = pts - centres[None]
    rel = rel - np.einsum("kni,ni->kn", rel, tangents)[..., None] * tangents[None]
    uv = np.stack([np.einsum("kni,ni->kn", rel, axes_u),
                   np.einsum("kni,ni->kn", rel, axes_v)], axis=-1).transpose(1, 0, 2)
    radius = 0.5 * frame.fibre_diameter(yid)
    radii = _smooth(envelope_radii(uv, radius, angles), closed, smoothing)
    area = polar_area(radii)
    filament_per_length = fibre_area_m2 * (np.linalg.norm(fibre_d, axis=2).sum(axis=0)
                                           / np.linalg.norm(dc, axis=1))
    return YarnGeometry(yid, frame.yarn_names[yid - 1], frame.yarn_families[yid - 1], closed,
                        period, centres, tangents, axes_u, axes_v, radii, directions,
                        filament_per_length / area, area)


def fibre_areas(model) -> dict[str, float]:
    """Filament area of one virtual fibre per family [m²] (``model.info['families']`` of a
    rendered fabric, or ``model.info['fibre_area_m2']`` of a synthetic sheet)."""
    areas = {f: v.get("fibre_area_m2") for f, v in model.info.get("families", {}).items()}
    if not areas and isinstance(model.info.get("fibre_area_m2"), dict):
        areas = dict(model.info["fibre_area_m2"])
    missing = [f for f in model.family_names if not areas.get(f)]
    if missing:
        raise InputError(f"model.info['families'][...]['fibre_area_m2'] is missing for "
                         f"{missing}: this state does not say its filament area")
    return {f: float(a) for f, a in areas.items() if a}


def reconstruct_yarns(model, stations: int | None = None, angles: int = 24,
                      smoothing: int = 2) -> list[YarnGeometry]:
    """Every yarn of a :class:`~fabmd.model.bead_model.BeadModel`, in yarn-id order."""
    frame = FabricFrame.from_model(model)
    areas = fibre_areas(model)
    return [reconstruct_yarn(frame, i + 1, areas[y.family], stations, angles, smoothing)
            for i, y in enumerate(model.yarns)]
