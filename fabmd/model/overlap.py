"""Closest approach between beads of different groups (yarns), with a numpy cell list.

Beads are binned into cubic cells at least ``cutoff`` wide; each bead is compared
with the beads of its own cell and of 13 neighbour cells (half stencil), so each
pair within the cutoff is seen once. Periodic directions use the minimum image.
Work proceeds in chunks so memory stays bounded for millions of beads.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

#: half of the 26 neighbour offsets (plus the own cell, handled separately)
_HALF = [o for o in itertools.product((-1, 0, 1), repeat=3) if o > (0, 0, 0)]


@dataclass(frozen=True)
class ClosestApproach:
    """Smallest surface gap between beads of different groups.

    Attributes:
        gap_m: distance − (d_i + d_j)/2 of the closest pair [m]; negative = overlap;
            ``None`` when no pair lies within the search cutoff (gap > ``cutoff_m`` − d).
        i, j: bead indices of that pair (−1 when none).
        overlaps: number of pairs whose gap is below −tolerance.
        cutoff_m: centre-distance search radius [m].
    """

    gap_m: float | None
    i: int
    j: int
    overlaps: int
    cutoff_m: float


def closest_approach(positions: np.ndarray, diameters: np.ndarray, groups: np.ndarray,
                     box_lo=None, box_hi=None, periodic=(False, False, False),
                     cutoff_m: float | None = None, tolerance_m: float = 0.0,
                     pairs_per_chunk: int = 4_000_000) -> ClosestApproach:
    """Closest pair of beads whose ``groups`` differ (see :class:`ClosestApproach`).

    Args:
        positions: (n, 3) [m].
        diameters: (n,) contact diameters [m].
        groups: (n,) integer label; pairs within one group are ignored.
        box_lo, box_hi: box (needed for periodic directions).
        periodic: periodic flag per direction.
        cutoff_m: search radius for centre distances (default 1.5 × largest diameter).
        tolerance_m: a gap below −tolerance counts as an overlap.
    """
    pos = np.asarray(positions, float)
    diam = np.asarray(diameters, float)
    grp = np.asarray(groups)
    n = len(pos)
    dmax = float(diam.max())
    cutoff = 1.5 * dmax if cutoff_m is None else float(cutoff_m)
    lo = pos.min(axis=0) if box_lo is None else np.asarray(box_lo, float).copy()
    hi = pos.max(axis=0) if box_hi is None else np.asarray(box_hi, float).copy()
    periodic = np.asarray(periodic, bool)
    length = hi - lo
    # non-periodic directions: bin over the beads' own extent
    lo = np.where(periodic, lo, pos.min(axis=0))
    span = np.where(periodic, length, pos.max(axis=0) - lo)
    ncell = np.maximum(1, np.floor(span / cutoff).astype(np.int64))
    cell_size = np.where(span > 0, span / ncell, 1.0)
    c = np.floor((pos - lo) / cell_size).astype(np.int64)
    c = np.where(periodic, np.mod(c, ncell), np.clip(c, 0, ncell - 1))
    key = (c[:, 0] * ncell[1] + c[:, 1]) * ncell[2] + c[:, 2]
    order = np.argsort(key, kind="stable")
    skey = key[order]
    sc = c[order]
    spos, sdiam, sgrp = pos[order], diam[order], grp[order]
    total_cells = int(ncell.prod())
    cell_start = np.searchsorted(skey, np.arange(total_cells + 1))
    # smallest and largest group in each cell: a neighbour cell holding only the bead's
    # own group cannot contribute a pair and is skipped before pairs are formed
    occupied = np.flatnonzero(cell_start[1:] > cell_start[:-1])
    gmin = np.zeros(total_cells, sgrp.dtype)
    gmax = np.zeros(total_cells, sgrp.dtype)
    gmin[occupied] = np.minimum.reduceat(sgrp, cell_start[occupied])
    gmax[occupied] = np.maximum.reduceat(sgrp, cell_start[occupied])

    best = (np.inf, -1, -1)
    n_overlap = 0
    chunk = max(1, pairs_per_chunk // 40)
    for a in range(0, n, chunk):
        idx = np.arange(a, min(n, a + chunk))
        for off in [(0, 0, 0)] + _HALF:
            nc = sc[idx] + np.asarray(off)
            valid = np.ones(len(idx), bool)
            for k in range(3):
                if periodic[k]:
                    nc[:, k] = np.mod(nc[:, k], ncell[k])
                else:
                    valid &= (nc[:, k] >= 0) & (nc[:, k] < ncell[k])
            nk = (nc[:, 0] * ncell[1] + nc[:, 1]) * ncell[2] + nc[:, 2]
            nk = np.where(valid, nk, 0)
            own = sgrp[idx]
            valid &= ~((gmin[nk] == own) & (gmax[nk] == own))
            ii = idx[valid]
            if not len(ii):
                continue
            nk = nk[valid]
            start, stop = cell_start[nk], cell_start[nk + 1]
            if off == (0, 0, 0):
                start = np.maximum(start, ii + 1)
            counts = np.maximum(stop - start, 0)
            m = int(counts.sum())
            if m == 0:
                continue
            first = np.repeat(ii, counts)
            base = np.repeat(start - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
            second = base + np.arange(m)
            keep = sgrp[first] != sgrp[second]
            first, second = first[keep], second[keep]
            if not len(first):
                continue
            d = spos[second] - spos[first]
            for k in range(3):
                if periodic[k]:
                    d[:, k] -= length[k] * np.round(d[:, k] / length[k])
            dist = np.sqrt(np.einsum("ij,ij->i", d, d))
            close = dist < cutoff
            if not close.any():
                continue
            gap = dist[close] - 0.5 * (sdiam[first[close]] + sdiam[second[close]])
            n_overlap += int(np.count_nonzero(gap < -tolerance_m))
            k = int(np.argmin(gap))
            if gap[k] < best[0]:
                best = (float(gap[k]), int(order[first[close][k]]), int(order[second[close][k]]))
    if best[1] < 0:
        return ClosestApproach(None, -1, -1, 0, cutoff)
    return ClosestApproach(best[0], best[1], best[2], n_overlap, cutoff)
