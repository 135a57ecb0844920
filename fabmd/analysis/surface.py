"""Shear angle of a fabric draped over a curved surface, from the local yarn tangents.

On a curved surface the in-plane projection of the yarns (:func:`shear_angle_field`)
distorts their angle; the angle between the yarns' 3D *tangent* vectors does not:
both tangents lie in the surface's tangent plane, so their angle is the one the
fabric sees. For every bead the tangent is the central difference of its fibre's
neighbours (one-sided at the fibre's ends), oriented like the family's mean direction
in the reference state, so that averaging does not cancel opposite-running fibres.

The grid is laid over the *reference* (flat, initial) in-plane positions and carried
to the deformed state with the beads: a cell holds the same material in every frame.
In each cell the summed warp and weft tangents t_w, t_f give

    γ = 90° − angle(t_w, t_f)   (in (−90°, 90°); 0 unsheared, > 0 when the weft has
                                 turned towards the warp, as in :func:`shear_angle_field`)

The crimp wave's out-of-plane tangent components cancel over a cell one crimp
wavelength long or more (for a plain weave: one unit cell, two yarn spacings).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .angles import Field


def fibre_tangents(positions: np.ndarray, fibre_ids: np.ndarray) -> np.ndarray:
    """Unit tangent of every bead along its fibre (central differences; one-sided at the
    fibre's ends; zero for a fibre of one bead). Beads must be contiguous per fibre."""
    p = np.asarray(positions, float).reshape(-1, 3)
    fid = np.asarray(fibre_ids).reshape(-1)
    if len(fid) != len(p):
        raise InputError("fibre_tangents: one fibre id per bead needed")
    n = len(p)
    if n == 0:
        return np.zeros((0, 3))
    prev = np.arange(n) - 1
    nxt = np.arange(n) + 1
    first = np.ones(n, bool)
    first[1:] = fid[1:] != fid[:-1]
    last = np.ones(n, bool)
    last[:-1] = fid[1:] != fid[:-1]
    prev[first] = np.flatnonzero(first)
    nxt[last] = np.flatnonzero(last)
    t = p[nxt] - p[prev]
    norm = np.linalg.norm(t, axis=1)
    out = np.zeros_like(t)
    ok = norm > 0
    out[ok] = t[ok] / norm[ok, None]
    return out


def _family_signs(tangents: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """±1 per bead: orient the (axial) tangents of one family like their mean direction,
    taken between −45° and 135° from x (warp along +x, weft along +y), so that the sign of
    γ does not depend on which way the fibres were numbered."""
    t = tangents[mask, :2]
    theta = np.arctan2(t[:, 1], t[:, 0])
    w = np.hypot(t[:, 0], t[:, 1])
    mean = 0.5 * np.arctan2((w * np.sin(2 * theta)).sum(), (w * np.cos(2 * theta)).sum())
    axis = np.array([np.cos(mean), np.sin(mean)])
    if axis[0] + axis[1] < 0:
        axis = -axis
    sign = np.where(t @ axis >= 0, 1.0, -1.0)
    out = np.ones(len(tangents))
    out[mask] = sign
    return out


def grid_edges(lo: float, hi: float, cell_m: float, origin: float = 0.0) -> np.ndarray:
    """Cell edges of width ``cell_m`` anchored at ``origin`` (a symmetry line lies on an
    edge), covering [lo, hi]."""
    if not cell_m > 0:
        raise InputError(f"cell size must be > 0, got {cell_m!r}")
    k0 = int(np.floor((lo - origin) / cell_m + 1e-9))
    k1 = int(np.ceil((hi - origin) / cell_m - 1e-9))
    k1 = max(k1, k0 + 1)
    return origin + cell_m * np.arange(k0, k1 + 1)


def surface_shear_angle_field(reference_positions: np.ndarray, positions: np.ndarray,
                              fibre_ids: np.ndarray, families, x_edges_m, y_edges_m,
                              warp: str = "warp", weft: str = "weft",
                              min_beads: int = 2) -> Field:
    """Shear angle γ per cell of a grid over the reference in-plane positions [°].

    Args:
        reference_positions: (n, 3) bead positions of the flat reference state [m];
            the grid is laid over their x and y.
        positions: (n, 3) positions of the same beads in the deformed state [m].
        fibre_ids: fibre of every bead (beads contiguous per fibre, in fibre order).
        families: family name of every bead (e.g. ``model.families``).
        x_edges_m, y_edges_m: cell edges [m] (see :func:`grid_edges`).
        min_beads: cells with fewer beads of either family are NaN.

    Returns:
        A :class:`~fabmd.analysis.angles.Field` (``values[j, i]``) whose ``extra``
        holds ``warp_beads`` and ``weft_beads`` per cell, and ``bead_shear_deg``:
        the value of each bead's cell (NaN outside the grid or in an empty cell).
    """
    ref = np.asarray(reference_positions, float).reshape(-1, 3)
    cur = np.asarray(positions, float).reshape(-1, 3)
    fam = np.asarray(families, dtype=object).reshape(-1)
    if cur.shape != ref.shape or len(fam) != len(ref):
        raise InputError("surface shear angle: reference, deformed positions and families "
                         "must describe the same beads")
    is_warp, is_weft = fam == warp, fam == weft
    if not is_warp.any() or not is_weft.any():
        raise InputError(f"shear angle needs beads of both families {warp!r} and {weft!r}; "
                         f"got {sorted(set(fam.tolist()))}")
    t0 = fibre_tangents(ref, fibre_ids)
    t1 = fibre_tangents(cur, fibre_ids)
    sign = _family_signs(t0, is_warp) * _family_signs(t0, is_weft)
    t1 = t1 * sign[:, None]
    xe = np.asarray(x_edges_m, float)
    ye = np.asarray(y_edges_m, float)
    nx, ny = len(xe) - 1, len(ye) - 1
    i = np.searchsorted(xe, ref[:, 0], side="right") - 1
    j = np.searchsorted(ye, ref[:, 1], side="right") - 1
    inside = (i >= 0) & (i < nx) & (j >= 0) & (j < ny)
    cell = np.where(inside, j * nx + i, -1)

    def summed(mask):
        sel = mask & inside
        vec = np.column_stack([np.bincount(cell[sel], t1[sel, k], nx * ny) for k in range(3)])
        count = np.bincount(cell[sel], minlength=nx * ny)
        return vec, count

    vw, nw = summed(is_warp)
    vf, nf = summed(is_weft)
    nrm = np.linalg.norm(vw, axis=1) * np.linalg.norm(vf, axis=1)
    ok = (nw >= min_beads) & (nf >= min_beads) & (nrm > 0)
    cos = np.full(nx * ny, np.nan)
    cos[ok] = np.einsum("ij,ij->i", vw[ok], vf[ok]) / nrm[ok]
    gamma = 90.0 - np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    bead = np.full(len(ref), np.nan)
    bead[inside] = gamma[cell[inside]]
    return Field(xe, ye, gamma.reshape(ny, nx), "shear angle γ", "°",
                 extra={"warp_beads": nw.reshape(ny, nx), "weft_beads": nf.reshape(ny, nx),
                        "bead_shear_deg": bead})
