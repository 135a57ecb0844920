"""Yarn cross-sections and the packing of virtual fibres in them.

A yarn section has a ``width_m`` (in the fabric plane, across the yarn), a
``height_m`` (through the thickness) and a ``shape``:

* ``"ellipse"`` (default; a circle when width = height), area π·w·h/4;
* ``"lenticular"`` — a lens bounded by two parabolic arcs, half-thickness
  (h/2)·(1 − (2u/w)²), area 2·w·h/3 (the usual section of a flattened roving);
* ``"racetrack"`` — a rectangle with semicircular ends of diameter h (w ≥ h),
  area (w − h)·h + π·h²/4.

:meth:`Section.area_m2` gives the area, so a yarn's fibre volume fraction is its
filament area (tex/ρ) over it.

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

Two packing rules (:data:`PACKINGS`, ``[yarns.*] fibre_packing``):

* ``"inscribed"`` (default): the contact diameter below — every fibre inside the section,
  as large as fits.
* ``"area"``: the fibres' hexagonal cells tile the section's area, N·(√3/2)·d² = area, so
  d = sqrt(area/(N·√3/2)), and of the lattice selections above the one whose second
  moments (of the fibre discs, across and through the thickness) best match the section's
  is kept. The fibres then span the section (19 fibres in a 4.2 × 0.638 mm ellipse: 4.29 ×
  0.67 mm, against 2.93 × 0.55 mm inscribed) and poke out a little at thin ends (the loose
  build stacks yarns by what their fibres fill, ``YarnSpec.occupied_height_m``); touching
  virtual fibres are at the yarn's own fibre volume fraction whatever N is (with the
  within-family law, :mod:`fabmd.model.bundle_contact`, the law then starts at the same
  state for every fibre count; inscribed, it starts at Vf 0.58 for 7 and 0.90 for 19
  fibres of that yarn).

Contact diameter d (``"inscribed"``): the lattice is scaled to spacing d, with d the largest value
for which every fibre lies inside the section — for an ellipse each fibre centre
inside the ellipse of semi-axes (w/2 − d/2, h/2 − d/2); for the other shapes each
fibre centre inside the shape and at least d/2 from its (finely sampled)
outline. Neighbouring fibres then touch and the outer ones touch the yarn
boundary: for a circle of diameter D this is
d = D/3 for 7 fibres, D/5 for 19, D/7 for 37, D/9 for 61. The mechanical
(filament) area of each fibre comes from the linear density, not from d (see
:meth:`fabmd.geometry.material.VirtualFibre.from_yarn`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError
from ..units import quantity

#: section shapes (see the module docstring)
SHAPES = ("ellipse", "lenticular", "racetrack")
#: rules that place the virtual fibres in a section (see the module docstring)
PACKINGS = ("inscribed", "area")


@functools.lru_cache(maxsize=64)
def _hex_packing(n: int, aspect: float, shift: tuple[float, float] = (0.0, 0.0)) -> np.ndarray:
    # the n nearest sites lie well within these ranges (rows j, sites i along a row);
    # a flat section needs long rows but few of them
    kj = int(math.ceil(math.sqrt(n) * max(1.0 / aspect, 1.0))) + 3
    ki = int(math.ceil(math.sqrt(n) * max(aspect, 1.0))) + 3 + kj
    i, j = np.meshgrid(np.arange(-2 * ki, 2 * ki + 1), np.arange(-2 * kj, 2 * kj + 1))
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


def area_factor(shape: str, aspect: float = 1.0) -> float:
    """Section area over width × height for a shape at width/height ``aspect``."""
    if shape == "ellipse":
        return math.pi / 4.0
    if shape == "lenticular":
        return 2.0 / 3.0
    if shape == "racetrack":
        return 1.0 - (1.0 - math.pi / 4.0) / aspect
    raise InputError(f"yarn.shape must be one of {', '.join(SHAPES)}, got {shape!r}")


def section_height(area_m2: float, width_m: float, shape: str) -> float:
    """Height [m] of a section of ``shape`` and width ``width_m`` [m] whose area is ``area_m2``.

    Raises:
        InputError: a racetrack that cannot hold the area at that width (its height
            would exceed its width).
    """
    if shape == "racetrack":
        k = 1.0 - math.pi / 4.0  # area = w·h − k·h²
        disc = width_m * width_m - 4.0 * k * area_m2
        h = (width_m - math.sqrt(disc)) / (2.0 * k) if disc >= 0 else math.inf
        if h > width_m:
            raise InputError(f"a racetrack section {1e3 * width_m:.4g} mm wide holds at most "
                             f"{1e6 * math.pi * width_m ** 2 / 4:.4g} mm², not "
                             f"{1e6 * area_m2:.4g} mm²: widen it or raise the packing")
        return h
    return area_m2 / (area_factor(shape) * width_m)


@dataclass(frozen=True)
class Section:
    """Yarn cross-section (see the module docstring for the shapes).

    Args:
        width_m: extent across the yarn in the fabric plane [m] (accepts "2 mm").
        height_m: extent through the thickness [m]; default = width (circle).
        shape: ``"ellipse"``, ``"lenticular"`` or ``"racetrack"``.
    """

    width_m: float
    height_m: float | None = None
    shape: str = "ellipse"

    def __post_init__(self):
        w = inputs.positive("yarn.width_m", quantity(self.width_m, "length", "yarn.width_m"))
        h = w if self.height_m is None else inputs.positive(
            "yarn.height_m", quantity(self.height_m, "length", "yarn.height_m"))
        object.__setattr__(self, "width_m", w)
        object.__setattr__(self, "height_m", h)
        area_factor(self.shape)  # validates the name
        if self.shape == "racetrack" and w < h * (1 - 1e-12):
            raise InputError(f"yarn.width_m = {w:g} m of a racetrack section must be >= its "
                             f"height_m = {h:g} m (semicircular ends of diameter = height)")

    @property
    def aspect(self) -> float:
        return self.width_m / self.height_m

    @property
    def area_m2(self) -> float:
        """Section area [m²]."""
        return area_factor(self.shape, self.aspect) * self.width_m * self.height_m

    def half_thickness_m(self, across_m: np.ndarray) -> np.ndarray:
        """Half of the section's height at ``across_m`` from its centre line [m] (0 outside)."""
        u = np.abs(np.asarray(across_m, float))
        a, b = 0.5 * self.width_m, 0.5 * self.height_m
        q = np.clip(1.0 - (u / a) ** 2, 0.0, None)
        if self.shape == "ellipse":
            return b * np.sqrt(q)
        if self.shape == "lenticular":
            return b * q
        flat = a - b  # racetrack: straight part, then semicircles of radius b
        return np.where(u <= flat, b, np.sqrt(np.clip(b * b - (u - flat) ** 2, 0.0, None)))

    def packing(self, n_fibres: int, rule: str = "inscribed") -> tuple[np.ndarray, float]:
        """Fibre centre offsets (n, 2) [m] (across, through-thickness) and contact diameter
        [m], by ``rule`` (:data:`PACKINGS`, module docstring)."""
        n = int(inputs.positive_int("yarn.n_fibres", n_fibres))
        if rule == "area":
            unit, d = _area_packing(n, float(self.width_m), float(self.height_m), self.shape)
        elif rule == "inscribed":
            unit, d = _best_packing(n, float(self.width_m), float(self.height_m), self.shape)
        else:
            raise InputError(f"yarn.fibre_packing must be one of {', '.join(PACKINGS)}, "
                             f"got {rule!r}")
        return d * unit, d

    def second_moments_m2(self) -> tuple[float, float]:
        """Mean u² and v² over the section's area [m²] (u across, v through the thickness)."""
        u = np.linspace(-0.5 * self.width_m, 0.5 * self.width_m, 4001)
        t = self.half_thickness_m(u)
        area = np.trapezoid(2 * t, u)
        return (float(np.trapezoid(u * u * 2 * t, u) / area),
                float(np.trapezoid(2 * t**3 / 3, u) / area))

    def fill_fraction(self, n_fibres: int) -> float:
        """Share of the section covered by the fibres' contact circles, N·d²/(w·h)."""
        _, d = self.packing(n_fibres)
        return n_fibres * d * d / (self.width_m * self.height_m)


#: points sampling the outline of a non-elliptical section (per half)
_OUTLINE_POINTS = 200


def _outline(section: Section) -> np.ndarray:
    u = 0.5 * section.width_m * np.cos(np.linspace(0.0, math.pi, _OUTLINE_POINTS))
    t = section.half_thickness_m(u)
    return np.vstack([np.column_stack([u, t]), np.column_stack([u, -t])[::-1]])  # closed loop


def _fit(unit: np.ndarray, a: float, b: float, shape: str = "ellipse") -> float:
    """Largest d with every fibre of ``d·unit`` (radius d/2) inside the section of
    half-width a, half-height b."""
    if shape == "ellipse":
        def fits(d: float) -> bool:
            ra, rb = a - 0.5 * d, b - 0.5 * d
            if ra <= 0 or rb <= 0:
                return False
            return bool(np.all((d * unit[:, 0] / ra) ** 2 + (d * unit[:, 1] / rb) ** 2
                               <= 1.0 + 1e-12))
    else:
        sec = Section(2 * a, 2 * b, shape)
        outline = _outline(sec)
        start, edge = outline, np.roll(outline, -1, axis=0) - outline
        length2 = np.maximum(np.einsum("mk,mk->m", edge, edge), 1e-300)

        def fits(d: float) -> bool:
            c = d * unit
            if np.any(np.abs(c[:, 1]) >= sec.half_thickness_m(c[:, 0])):
                return False
            # distance to the outline's segments (not just its vertices)
            rel = c[:, None, :] - start[None]
            t = np.clip(np.einsum("nmk,mk->nm", rel, edge) / length2, 0.0, 1.0)
            dist = np.linalg.norm(rel - t[..., None] * edge[None], axis=2).min(axis=1)
            return bool(np.all(dist >= 0.5 * d))

    lo, hi = 0.0, 2.0 * min(a, b)
    if fits(hi):
        return hi
    for _ in range(60 if shape == "ellipse" else 32):  # the outline is sampled anyway
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if fits(mid) else (lo, mid)
    return lo


#: lattice origins tried: a site, a bond middle, a triangle centre, between two rows
_SHIFTS = ((0.0, 0.0), (0.5, 0.0), (0.5, math.sqrt(3.0) / 6.0), (0.0, math.sqrt(3.0) / 4.0))


@functools.lru_cache(maxsize=256)
def _best_packing(n: int, width: float, height: float,
                  shape: str = "ellipse") -> tuple[np.ndarray, float]:
    aspect = width / height
    best = None
    for k in sorted(range(-8, 17), key=abs):
        for shift in _SHIFTS:
            unit = _hex_packing(n, aspect * 2.0 ** (k / 8.0), shift)
            d = _fit(unit, 0.5 * width, 0.5 * height, shape)
            if best is None or d > best[1] * (1 + 1e-9):
                best = (unit, d)
    return best


@functools.lru_cache(maxsize=256)
def _area_packing(n: int, width: float, height: float,
                  shape: str = "ellipse") -> tuple[np.ndarray, float]:
    """Unit-spacing centres and d of the ``"area"`` rule (module docstring)."""
    section = Section(width, height, shape)
    d = math.sqrt(section.area_m2 / (n * math.sqrt(3.0) / 2.0))
    uu, vv = section.second_moments_m2()
    best = None
    for k in sorted(range(-16, 33), key=abs):
        for shift in _SHIFTS:
            unit = _hex_packing(n, section.aspect * 2.0 ** (k / 8.0), shift)
            # a disc of diameter d adds d²/16 to either second moment
            mu = d * d * (np.mean(unit[:, 0] ** 2) + 1.0 / 16.0)
            mv = d * d * (np.mean(unit[:, 1] ** 2) + 1.0 / 16.0)
            mismatch = abs(math.log(mu / uu)) + abs(math.log(mv / vv))
            if best is None or mismatch < best[1] - 1e-12:
                best = (unit, mismatch)
    return best[0], d
