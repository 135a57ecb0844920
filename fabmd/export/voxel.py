"""Voxel mesh of reconstructed yarns: per voxel the yarn (or matrix), the local fibre
direction and the fibre volume fraction (SI).

A voxel belongs to the yarn whose envelope holds its centre; where two envelopes
overlap (interpenetration) it goes to the yarn in which it lies deeper (smaller
normalised radius r/R(θ)) for its yarn id and direction, its fibre volume fraction is
the sum of the overlapping yarns' (the filaments of both are there: the cell's filament
volume is kept), and the overlap is counted for the report. Matrix voxels
have yarn id 0 and direction (0, 0, 0); their fibre volume fraction is 0 unless part
of a yarn reaches into them (see :func:`voxelise`, ``samples``). Periodic directions of
the domain are handled by testing each voxel centre's images one period either side.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from .yarns import YarnGeometry

#: points classified against a yarn's stations at once (memory: chunk × stations)
_CHUNK = 20000


@dataclass
class VoxelGrid:
    """A regular grid of box-shaped voxels over ``[lo, hi]`` (SI).

    Attributes:
        lo_m, hi_m: (3,) domain corners [m].
        counts: (nx, ny, nz) voxels per axis.
        periodic: periodicity of x, y, z (the domain is then one period).
    """

    lo_m: np.ndarray
    hi_m: np.ndarray
    counts: tuple[int, int, int]
    periodic: tuple[bool, bool, bool] = (False, False, False)

    def __post_init__(self):
        self.lo_m = np.asarray(self.lo_m, float).reshape(3)
        self.hi_m = np.asarray(self.hi_m, float).reshape(3)
        self.counts = tuple(int(c) for c in self.counts)
        self.periodic = tuple(bool(p) for p in self.periodic)
        if any(c < 1 for c in self.counts):
            raise InputError(f"voxel counts must be >= 1, got {self.counts}")
        if np.any(self.hi_m <= self.lo_m):
            raise InputError(f"voxel domain must have hi > lo, got {self.lo_m}, {self.hi_m}")

    @classmethod
    def covering(cls, lo_m, hi_m, periodic, voxels: int | None = None,
                 voxel_size_m: float | None = None) -> VoxelGrid:
        """A grid over a domain: ``voxels`` along its longest edge, or voxels of about
        ``voxel_size_m`` (each axis rounds to a whole number of voxels)."""
        lo, hi = np.asarray(lo_m, float), np.asarray(hi_m, float)
        length = hi - lo
        if (voxels is None) == (voxel_size_m is None):
            raise InputError("give either voxels or voxel_size_m")
        if voxels is not None:
            if int(voxels) < 1:
                raise InputError(f"voxels must be >= 1, got {voxels}")
            voxel_size_m = float(length.max()) / int(voxels)
        if not voxel_size_m > 0:
            raise InputError(f"voxel_size_m must be > 0, got {voxel_size_m}")
        counts = np.maximum(1, np.round(length / voxel_size_m)).astype(int)
        return cls(lo, hi, tuple(counts), periodic)

    @property
    def n_voxels(self) -> int:
        return int(np.prod(self.counts))

    @property
    def size_m(self) -> np.ndarray:
        """(3,) voxel edge lengths [m]."""
        return (self.hi_m - self.lo_m) / np.asarray(self.counts)

    @property
    def voxel_volume_m3(self) -> float:
        return float(np.prod(self.size_m))

    def centres(self) -> np.ndarray:
        """(n_voxels, 3) voxel centres, x fastest, then y, then z [m]."""
        axes = [self.lo_m[k] + (np.arange(self.counts[k]) + 0.5) * self.size_m[k]
                for k in range(3)]
        z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
        return np.column_stack([x.ravel(), y.ravel(), z.ravel()])

    def index_of(self, points: np.ndarray) -> np.ndarray:
        """Flat voxel index of points (periodic axes wrapped; -1 outside the domain)."""
        p = np.asarray(points, float).reshape(-1, 3) - self.lo_m
        length = self.hi_m - self.lo_m
        for k in range(3):
            if self.periodic[k]:
                p[:, k] = np.mod(p[:, k], length[k])
        ijk = np.floor(p / self.size_m).astype(np.int64)
        inside = ((ijk >= 0) & (ijk < np.asarray(self.counts))).all(axis=1)
        nx, ny, _ = self.counts
        flat = (ijk[:, 2] * ny + ijk[:, 1]) * nx + ijk[:, 0]
        return np.where(inside, flat, -1)


@dataclass
class VoxelMesh:
    """A voxelised fabric: the grid and the data of each voxel (flat, x fastest).

    Attributes:
        grid: the voxel grid.
        yarn_id: (n,) 1-based yarn id, 0 = matrix.
        direction: (n, 3) unit fibre direction (0 in the matrix).
        fibre_volume_fraction: (n,) fibre volume fraction (0 in the matrix with one
            sample per voxel; see :func:`voxelise`).
        yarn_names: name of yarn id 1, 2, ...
        overlap_voxels: {(yarn a, yarn b): voxels whose centre lies in both} (ids, a < b).
    """

    grid: VoxelGrid
    yarn_id: np.ndarray
    direction: np.ndarray
    fibre_volume_fraction: np.ndarray
    yarn_names: list[str]
    overlap_voxels: dict[tuple[int, int], int] = field(default_factory=dict)

    def cell_fibre_volume_fraction(self) -> float:
        """Fibre volume fraction of the whole domain (equal voxels: the mean)."""
        return float(self.fibre_volume_fraction.mean())

    def yarn_volume_fraction(self) -> float:
        """Share of the voxels that belong to a yarn."""
        return float(np.mean(self.yarn_id > 0))


def locate(yarn: YarnGeometry, points: np.ndarray) -> tuple[np.ndarray, ...]:
    """Where points lie relative to a yarn's envelope.

    Each point goes to its nearest centreline station i and the neighbouring station j
    on its side; w is its fraction along the segment i→j, (r, θ) its polar position in
    station i's section plane, and R(θ) = (1 − w)·R_i(θ) + w·R_j(θ).

    Returns:
        rho: (k,) r / R(θ) (<= 1 inside; inf beyond the end of an open yarn),
        direction: (k, 3) interpolated unit fibre direction,
        fraction: (k,) interpolated yarn fibre volume fraction.
    """
    y = yarn.extended()
    pts = np.asarray(points, float).reshape(-1, 3)
    n, m = y.n_stations, y.n_angles
    rho = np.full(len(pts), np.inf)
    direction = np.zeros((len(pts), 3))
    fraction = np.zeros(len(pts))
    c = y.centres_m
    c2 = np.einsum("ij,ij->i", c, c)
    for start in range(0, len(pts), _CHUNK):
        p = pts[start:start + _CHUNK]
        d2 = c2[None, :] - 2.0 * p @ c.T
        i = np.argmin(d2, axis=1)
        rel = p - c[i]
        s = np.einsum("ij,ij->i", rel, y.tangents[i])
        j = np.where(s >= 0, i + 1, i - 1)
        beyond = (j < 0) | (j >= n)
        j = np.clip(j, 0, n - 1)
        seg = c[j] - c[i]
        seg2 = np.einsum("ij,ij->i", seg, seg)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.where(seg2 > 0, np.einsum("ij,ij->i", rel, seg) / seg2, 0.0)
        w = np.clip(w, 0.0, 1.0)
        q = rel - w[:, None] * seg
        q = q - np.einsum("ij,ij->i", q, y.tangents[i])[:, None] * y.tangents[i]
        a = np.einsum("ij,ij->i", q, y.axes_u[i])
        b = np.einsum("ij,ij->i", q, y.axes_v[i])
        r = np.hypot(a, b)
        k_float = np.mod(np.arctan2(b, a), 2 * np.pi) / (2 * np.pi) * m
        k0 = np.floor(k_float).astype(np.int64) % m
        f = k_float - np.floor(k_float)
        k1 = (k0 + 1) % m

        r_i = (1 - f) * y.radii_m[i, k0] + f * y.radii_m[i, k1]
        r_j = (1 - f) * y.radii_m[j, k0] + f * y.radii_m[j, k1]
        big_r = (1 - w) * r_i + w * r_j
        out = np.where(beyond, np.inf, r / big_r)
        dirs = (1 - w)[:, None] * y.directions[i] + w[:, None] * y.directions[j]
        sl = slice(start, start + len(p))
        rho[sl] = out
        direction[sl] = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
        fraction[sl] = (1 - w) * y.fibre_volume_fraction[i] + w * y.fibre_volume_fraction[j]
    return rho, direction, fraction


def _image_shifts(grid: VoxelGrid) -> np.ndarray:
    """Shifts of a point to its periodic images one period either side (incl. none)."""
    length = grid.hi_m - grid.lo_m
    options = [(-1, 0, 1) if grid.periodic[k] else (0,) for k in range(3)]
    return np.array([[a * length[0], b * length[1], c * length[2]]
                     for a in options[0] for b in options[1] for c in options[2]])


def _candidates(grid: VoxelGrid, offset: np.ndarray, shift: np.ndarray, lo: np.ndarray,
                hi: np.ndarray) -> np.ndarray:
    """Flat indices of the voxels whose point (centre + offset), moved by ``shift``, lies
    in the box [lo, hi] (index ranges of the regular grid: no test of every voxel)."""
    first = grid.lo_m + offset + shift + 0.5 * grid.size_m  # point of voxel 0 per axis
    ranges = []
    for k in range(3):
        i0 = max(0, int(np.ceil((lo[k] - first[k]) / grid.size_m[k])))
        i1 = min(grid.counts[k] - 1, int(np.floor((hi[k] - first[k]) / grid.size_m[k])))
        if i1 < i0:
            return np.zeros(0, np.int64)
        ranges.append(np.arange(i0, i1 + 1))
    nx, ny, _ = grid.counts
    i, j, k = ranges
    return ((k[:, None, None] * ny + j[None, :, None]) * nx + i[None, None, :]).ravel()


def _classify(yarns: list[YarnGeometry], grid: VoxelGrid, offset: np.ndarray):
    """For the point centre + ``offset`` of every voxel: its yarn id (smallest r/R over
    the yarns holding it), direction, the sum of the yarn fibre volume fractions of every
    yarn holding it, and the overlap counts."""
    n = grid.n_voxels
    offset = np.asarray(offset, float)
    centres = grid.centres() + offset
    shifts = _image_shifts(grid)
    best = np.full(n, np.inf)
    owner = np.zeros(n, np.int64)
    direction = np.zeros((n, 3))
    fraction = np.zeros(n)
    first_inside = np.zeros(n, np.int64)
    overlaps: dict[tuple[int, int], int] = {}
    # this yarn's best image of every point; reset where touched after each yarn
    rho_y = np.full(n, np.inf)
    dir_y = np.zeros((n, 3))
    frac_y = np.zeros(n)
    for yarn in yarns:
        pad = float(yarn.radii_m.max()) + float(np.max(grid.size_m))
        ext = yarn.extended()
        lo, hi = ext.centres_m.min(axis=0) - pad, ext.centres_m.max(axis=0) + pad
        touched = []
        for shift in shifts:
            cand = _candidates(grid, offset, shift, lo, hi)
            if not len(cand):
                continue
            rho, dirs, frac = locate(yarn, centres[cand] + shift)
            better = rho < rho_y[cand]
            take = cand[better]
            rho_y[take], dir_y[take], frac_y[take] = rho[better], dirs[better], frac[better]
            touched.append(cand)
        if not touched:
            continue
        seen = np.unique(np.concatenate(touched))
        hit = seen[rho_y[seen] <= 1.0]
        fraction[hit] += frac_y[hit]
        take = hit[rho_y[hit] < best[hit]]
        best[take], direction[take], owner[take] = rho_y[take], dir_y[take], yarn.yarn_id
        shared = hit[first_inside[hit] > 0]
        for other, count in zip(*np.unique(first_inside[shared], return_counts=True),
                                strict=True):
            key = (int(min(other, yarn.yarn_id)), int(max(other, yarn.yarn_id)))
            overlaps[key] = overlaps.get(key, 0) + int(count)
        first_inside[hit[first_inside[hit] == 0]] = yarn.yarn_id
        rho_y[seen] = np.inf
    outside = best > 1.0
    owner[outside] = 0
    direction[outside] = 0.0
    return owner, direction, fraction, overlaps


def voxelise(yarns: list[YarnGeometry], grid: VoxelGrid, samples: int = 1) -> VoxelMesh:
    """Voxelise reconstructed yarns on a grid (see the module docstring).

    The voxel's yarn and direction are those at its centre; its fibre volume fraction
    is the mean over ``samples``³ points spread evenly through it (the filament volume
    inside it over its volume), so a voxel cut by a yarn surface carries the yarn's share
    whichever side its centre is on, and the cell's filament volume converges faster
    with voxel size. ``samples=1``: the centre value alone (matrix voxels then have 0).
    """
    if int(samples) < 1:
        raise InputError(f"samples must be >= 1, got {samples}")
    samples = int(samples)
    owner, direction, fraction, overlaps = _classify(yarns, grid, np.zeros(3))
    if samples > 1:
        frac = (np.arange(samples) + 0.5) / samples - 0.5
        offsets = np.stack(np.meshgrid(frac, frac, frac, indexing="ij"), -1).reshape(-1, 3)
        offsets = offsets * grid.size_m
        fraction = np.zeros(grid.n_voxels)
        for off in offsets:  # one sub-point per voxel at a time (memory stays n_voxels)
            fraction += _classify(yarns, grid, off)[2]
        fraction /= len(offsets)
    names = [""] * (max((y.yarn_id for y in yarns), default=0))
    for y in yarns:
        names[y.yarn_id - 1] = y.name
    return VoxelMesh(grid, owner, direction, fraction, names, overlaps)
