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
    n = len(pos)
    cutoff = 1.5 * float(diam.max()) if cutoff_m is None else float(cutoff_m)
    cells = _bin(pos, diam, np.asarray(groups), box_lo, box_hi, periodic, cutoff)
    best = (np.inf, -1, -1)
    n_overlap = 0
    chunk = max(1, pairs_per_chunk // 40)
    for a in range(0, n, chunk):
        idx = np.arange(a, min(n, a + chunk))
        for off in [(0, 0, 0)] + _HALF:
            pairs = _pairs(cells, idx, off)
            if pairs is None:
                continue
            first, second = pairs
            d = cells.spos[second] - cells.spos[first]
            for k in range(3):
                if cells.periodic[k]:
                    d[:, k] -= cells.length[k] * np.round(d[:, k] / cells.length[k])
            dist = np.sqrt(np.einsum("ij,ij->i", d, d))
            close = dist < cutoff
            if not close.any():
                continue
            gap = dist[close] - 0.5 * (cells.sdiam[first[close]] + cells.sdiam[second[close]])
            n_overlap += int(np.count_nonzero(gap < -tolerance_m))
            k = int(np.argmin(gap))
            if gap[k] < best[0]:
                best = (float(gap[k]), int(cells.order[first[close][k]]),
                        int(cells.order[second[close][k]]))
    if best[1] < 0:
        return ClosestApproach(None, -1, -1, 0, cutoff)
    return ClosestApproach(best[0], best[1], best[2], n_overlap, cutoff)


@dataclass(frozen=True)
class _Cells:
    """Beads sorted by cell (``order``: sorted → given index) and each cell's range."""

    order: np.ndarray
    sc: np.ndarray  # cell of each sorted bead (3 ints)
    spos: np.ndarray
    sdiam: np.ndarray
    sgrp: np.ndarray
    ncell: np.ndarray
    cell_start: np.ndarray
    gmin: np.ndarray  # smallest and largest group in each cell
    gmax: np.ndarray
    periodic: np.ndarray
    length: np.ndarray  # box length [m] (periodic directions)


def _bin(pos: np.ndarray, diam: np.ndarray, grp: np.ndarray, box_lo, box_hi, periodic,
         cutoff: float) -> _Cells:
    """Bin the beads into cells at least ``cutoff`` [m] wide."""
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
    sgrp = grp[order]
    total_cells = int(ncell.prod())
    cell_start = np.searchsorted(skey, np.arange(total_cells + 1))
    # smallest and largest group in each cell: a neighbour cell holding only the bead's
    # own group cannot contribute a pair and is skipped before pairs are formed
    occupied = np.flatnonzero(cell_start[1:] > cell_start[:-1])
    gmin = np.zeros(total_cells, sgrp.dtype)
    gmax = np.zeros(total_cells, sgrp.dtype)
    gmin[occupied] = np.minimum.reduceat(sgrp, cell_start[occupied])
    gmax[occupied] = np.maximum.reduceat(sgrp, cell_start[occupied])
    return _Cells(order, c[order], pos[order], diam[order], sgrp, ncell, cell_start, gmin,
                  gmax, periodic, length)


def _pairs(cells: _Cells, idx: np.ndarray, off: tuple[int, int, int]
           ) -> tuple[np.ndarray, np.ndarray] | None:
    """Pairs (sorted indices) of the beads ``idx`` with the beads of the cell at offset
    ``off`` from theirs, of different groups (None: none); each pair is seen once."""
    ncell = cells.ncell
    nc = cells.sc[idx] + np.asarray(off)
    valid = np.ones(len(idx), bool)
    for k in range(3):
        if cells.periodic[k]:
            nc[:, k] = np.mod(nc[:, k], ncell[k])
        else:
            valid &= (nc[:, k] >= 0) & (nc[:, k] < ncell[k])
    nk = (nc[:, 0] * ncell[1] + nc[:, 1]) * ncell[2] + nc[:, 2]
    nk = np.where(valid, nk, 0)
    own = cells.sgrp[idx]
    valid &= ~((cells.gmin[nk] == own) & (cells.gmax[nk] == own))
    ii = idx[valid]
    if not len(ii):
        return None
    nk = nk[valid]
    start, stop = cells.cell_start[nk], cells.cell_start[nk + 1]
    if off == (0, 0, 0):
        start = np.maximum(start, ii + 1)
    counts = np.maximum(stop - start, 0)
    m = int(counts.sum())
    if m == 0:
        return None
    first = np.repeat(ii, counts)
    base = np.repeat(start - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    second = base + np.arange(m)
    keep = cells.sgrp[first] != cells.sgrp[second]
    first, second = first[keep], second[keep]
    if not len(first):
        return None
    return first, second
