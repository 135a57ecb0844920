"""Yarn cross-sections and the packing of virtual fibres in them.

A yarn section is an ellipse of ``width_m`` (in the fabric plane, across the
yarn) and ``height_m`` (through the thickness); a circle when both are equal.

Packing of N virtual fibres (:func:`hex_packing`, documented rule): take the
sites of a hexagonal lattice with unit spacing (rows along the width) and keep
the N sites nearest the centre in the metric sqrt((u/a')² + v²), ties broken by
the angle from the width axis, and centre them. :meth:`Section.packing` tries
a' = a·2^(k/8), k = −8 … 16 (a = width/height) and four lattice origins (a site,
a bond middle, a triangle centre, half-way between rows) and keeps the
selection that allows the largest contact diameter (a' nearest a, origin at a
site, on ties). For a
circle this gives the full hexagonal shells for N = 1, 7, 19, 37, 61, …; a flat
ellipse gets flat, wide packings (e.g. rows of 4 + 3 for N = 7 at width/height
= 2). Any N >= 1 works.

Contact diameter d: the lattice is scaled to spacing d, with d the largest value
for which every fibre lies inside the section — each fibre centre inside the
ellipse of semi-axes (w/2 − d/2, h/2 − d/2). Neighbouring fibres then touch and
the outer ones touch the yarn boundary: for a circle of diameter D this is
d = D/3 for 7 fibres, D/5 for 19, D/7 for 37, D/9 for 61. The mechanical
(filament) area of each fibre comes from the linear density, not from d (see
:meth:`fabmd.model.material.VirtualFibre.from_yarn`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..units import quantity


@functools.lru_cache(maxsize=64)
def _hex_packing(n: int, aspect: float, shift: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    k = int(math.ceil(math.sqrt(n) * max(aspect, 1.0 / aspect, 1.0))) + 3
    i, j = np.meshgrid(np.arange(-2 * k, 2 * k + 1), np.arange(-2 * k, 2 * k + 1))
    u = (i + 0.5 * j).ravel() - shift[0]
    v = (j * math.sqrt(3.0) / 2.0).ravel() - shift[1]
    dist = np.round(np.hypot(u / aspect, v), 9)
    angle = np.round(np.mod(np.arctan2(v, u), 2 * math.pi), 9)
    order = np.lexsort((angle, dist))[:n]
    pts = np.column_stack([u[order], v[order]])
    pts -= 0.5 * (pts.max(axis=0) + pts.min(axis=0))
    return pts


def hex_packing(n: int, aspect: float = 1.0) -> np.ndarray:
    """(n, 2) fibre centres (across, through-thickness) of unit spacing; see module doc.

    Args:
        n: number of virtual fibres (>= 1).
        aspect: section width over height (> 0).
    """
    n = inputs.positive_int("yarn.n_fibres", n)
    aspect = inputs.positive("section.aspect", aspect)
    return _hex_packing(n, float(aspect)).copy()


@dataclass(frozen=True)
class Section:
    """Elliptical yarn cross-section.

    Args:
        width_m: extent across the yarn in the fabric plane [m] (accepts "2 mm").
        height_m: extent through the thickness [m]; default = width (circle).
    """

    width_m: float
    height_m: float | None = None

    def __post_init__(self):
        w = inputs.positive("yarn.width_m", quantity(self.width_m, "length", "yarn.width_m"))
        h = w if self.height_m is None else inputs.positive(
            "yarn.height_m", quantity(self.height_m, "length", "yarn.height_m"))
        object.__setattr__(self, "width_m", w)
        object.__setattr__(self, "height_m", h)

    @property
    def aspect(self) -> float:
        return self.width_m / self.height_m

    def packing(self, n_fibres: int) -> tuple[np.ndarray, float]:
        """Fibre centre offsets (n, 2) [m] (across, through-thickness) and contact diameter [m]."""
        unit, d = _best_packing(int(inputs.positive_int("yarn.n_fibres", n_fibres)),
                                float(self.width_m), float(self.height_m))
        return d * unit, d

    def fill_fraction(self, n_fibres: int) -> float:
        """Share of the section covered by the fibres' contact circles, N·d²/(w·h)."""
        _, d = self.packing(n_fibres)
        return n_fibres * d * d / (self.width_m * self.height_m)


def _fit(unit: np.ndarray, a: float, b: float) -> float:
    """Largest d with every fibre of ``d·unit`` (radius d/2) inside the ellipse (a, b)."""
    def fits(d: float) -> bool:
        ra, rb = a - 0.5 * d, b - 0.5 * d
        if ra <= 0 or rb <= 0:
            return False
        return bool(np.all((d * unit[:, 0] / ra) ** 2 + (d * unit[:, 1] / rb) ** 2
                           <= 1.0 + 1e-12))

    lo, hi = 0.0, 2.0 * min(a, b)
    if fits(hi):
        return hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


#: lattice origins tried: a site, a bond middle, a triangle centre, between two rows
_SHIFTS = ((0.0, 0.0), (0.5, 0.0), (0.5, math.sqrt(3.0) / 6.0), (0.0, math.sqrt(3.0) / 4.0))


@functools.lru_cache(maxsize=256)
def _best_packing(n: int, width: float, height: float) -> tuple[np.ndarray, float]:
    aspect = width / height
    best = None
    for k in sorted(range(-8, 17), key=abs):
        for shift in _SHIFTS:
            unit = _hex_packing(n, aspect * 2.0 ** (k / 8.0), shift)
            d = _fit(unit, 0.5 * width, 0.5 * height)
            if best is None or d > best[1] * (1 + 1e-9):
                best = (unit, d)
    return best
