"""A within-family contact that follows a yarn's compaction law (nonlinear, SI).

The linear split contact (:class:`fabmd.model.contact.ContactModel`,
``within_family_stiffness_pa``) matches the law at one pressure and has no packing limit.
Here same-family bead pairs carry the normal force of a hexagonal bundle that follows
the law all the way. With centre distance r (= the hexagonal axis spacing g) the bundle's
fibre volume fraction is Vf(r) = A/((√3/2)·r²) (A: filament area of one virtual fibre),
the law gives p(Vf) (:class:`~fabmd.model.compaction.CompactionLaw`), shifted so that it is
0 where the virtual fibres just touch (r = d):

    p_s(r) = p(Vf(r)) − p(Vf(d)),

and the line force per unit length between neighbours is q = p_s·r/√3 (the inverse of
:func:`~fabmd.model.compaction.bundle_pressure_pa`'s virial, p = √3·q/g); a bead pair
carries F = q·l0. The shift makes the realised law p(Vf) − p(Vf_touch): at a pressure P the
bundle reaches the law's Vf at P + p(Vf_touch) (:meth:`BundleContact.volume_fraction`).

Packing limit. The van Wyk form stays finite at the densest packing of circular filaments
(Vf = π/(2√3), :data:`~fabmd.model.compaction.PACKING_LIMIT`); a bundle cannot pack denser.
So past the spacing where the bundle reaches it — or, if that comes first, where the law's
tangent reaches the crossing contact's stiffness k'_cross — the force goes on linearly with
slope k'_cross: a hard core as stiff as a crossing. The stable time step
(:mod:`fabmd.model.timestep`) takes the bead pair's steepest tangent: the crossing's k_n in
the core, up to 1.5× it just inside the core at s/d 0.5, where the table takes the second
neighbours' share off (:meth:`BundleContact.pair_force_n`): 3 % shorter on the plain-weave
example, where the bonds bound the step too.

LAMMPS realisation (``pair_style hybrid/overlay granular table linear N``): ``granular``
keeps its per-type-pair Hooke coefficients (crossings stiff; same family a linear part
k_lin·l0·(d − r), so that friction and damping act there), and a ``table`` on the
same-family type pairs adds the excess F − k_lin·l0·(d − r) (:meth:`BundleContact.table_text`,
a file in the run folder). k_lin is the largest line under the law (its tangent where the
fibres touch: the law is convex in the overlap), so the total is the law at every overlap.
Known limit: friction within a family is μ × the granular (linear) part only — about half
the normal force at 100 kPa for the glass law, less at higher pressure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .. import inputs
from ..errors import InputError
from .compaction import HEX_CELL, PACKING_LIMIT, CompactionLaw

SQRT3 = math.sqrt(3.0)
#: rows of the LAMMPS table (r from TABLE_INNER·d to d); also ``pair_style table linear N``
TABLE_POINTS = 4000
#: inner end of the table over d: LAMMPS stops a run with a pair closer than this
TABLE_INNER = 0.02
#: floor of the linear part over the law's first tangent when the law starts below the
#: touching state (Vf_touch < Vf0: no line fits under it but k = 0)
MIN_LINEAR_SHARE = 0.01


@dataclass(frozen=True)
class BundleContact:
    """Same-family normal contact of virtual fibres that follows ``law`` (module docstring).

    Args:
        law: the yarn's compaction law.
        area_m2: filament area carried by one virtual fibre A [m²] (> 0).
        diameter_m: its contact diameter d [m] (> 0); the virtual fibres must touch below
            the packing limit (A/((√3/2)·d²) < π/(2√3)).
    """

    law: CompactionLaw
    area_m2: float
    diameter_m: float

    def __post_init__(self):
        if not isinstance(self.law, CompactionLaw):
            raise InputError(f"bundle_contact.law must be a CompactionLaw, got {self.law!r}")
        inputs.positive("bundle_contact.area_m2", self.area_m2)
        inputs.positive("bundle_contact.diameter_m", self.diameter_m)
        if self.touching_vf >= PACKING_LIMIT:
            raise InputError(
                f"bundle_contact: virtual fibres of d = {self.diameter_m:.4g} m and A = "
                f"{self.area_m2:.4g} m² touch at Vf {self.touching_vf:.3f}, at or above the "
                f"packing limit {PACKING_LIMIT:.3f}; use a larger contact diameter")

    # -- the bundle -----------------------------------------------------------------------
    @property
    def touching_vf(self) -> float:
        """Vf of the hexagonal bundle whose virtual fibres just touch (r = d)."""
        return self.area_m2 / (HEX_CELL * self.diameter_m**2)

    def vf_at(self, spacing_m):
        """Vf of the hexagonal bundle at axis spacing ``spacing_m`` [m] (array or float)."""
        return self.area_m2 / (HEX_CELL * np.asarray(spacing_m, float) ** 2)

    @property
    def touching_pressure_pa(self) -> float:
        """The law's pressure where the virtual fibres touch, p(Vf_touch) [Pa] (the shift)."""
        return self.law.pressure_pa(self.touching_vf)

    @property
    def packing_spacing_m(self) -> float:
        """Axis spacing at which the bundle reaches the packing limit [m]."""
        return math.sqrt(self.area_m2 / (HEX_CELL * PACKING_LIMIT))

    def volume_fraction(self, pressure_pa: float) -> float:
        """Vf the bead bundle reaches at ``pressure_pa`` [Pa] (the shifted law)."""
        return self.law.volume_fraction(inputs.non_negative("pressure_pa", pressure_pa)
                                        + self.touching_pressure_pa)

    def spacing_at(self, pressure_pa: float) -> float:
        """Axis spacing r [m] of the bead bundle at ``pressure_pa`` [Pa]."""
        return math.sqrt(self.area_m2 / (HEX_CELL * self.volume_fraction(pressure_pa)))

    def _law_pressure(self, r: np.ndarray) -> np.ndarray:
        """p(Vf(r)) − p(Vf(d)), 0 where the law carries nothing [Pa]."""
        k = self.law.coefficient * self.law.modulus_pa
        n = self.law.exponent
        p = k * (np.maximum(self.vf_at(r), self.law.vf0) ** n - self.law.vf0**n)
        return np.maximum(0.0, p - self.touching_pressure_pa)

    def _law_slope(self, r: np.ndarray) -> np.ndarray:
        """dq/dδ of the law's line force at spacing r [Pa] (δ = d − r)."""
        k = self.law.coefficient * self.law.modulus_pa
        n = self.law.exponent
        vf = self.vf_at(r)
        loaded = (vf > self.law.vf0) & (r < self.diameter_m)
        return np.where(loaded, (2 * n * k * vf**n - self._law_pressure(r)) / SQRT3, 0.0)

    # -- the contact ----------------------------------------------------------------------
    def linear_stiffness_pa(self) -> float:
        """k_lin [Pa]: the largest line k·(d − r) under the law's line force (its tangent
        where the fibres touch); floored at :data:`MIN_LINEAR_SHARE` of the law's first
        tangent when the law starts only past touching (Vf_touch < Vf0)."""
        d = self.diameter_m
        r = np.linspace(self.packing_spacing_m, d, 2001)[:-1]
        line = self._law_pressure(r) * r / SQRT3 / (d - r)
        first = 2 * self.law.exponent * self.law.coefficient * self.law.modulus_pa \
            * max(self.touching_vf, self.law.vf0) ** self.law.exponent / SQRT3
        return max(float(line.min()), MIN_LINEAR_SHARE * first)

    def core_spacing_m(self, crossing_stiffness_pa: float) -> float:
        """Spacing r_core [m] below which the force goes on linearly with slope
        ``crossing_stiffness_pa`` k'_cross [Pa]: the packing limit, or where the law's
        tangent reaches k'_cross if that comes first (module docstring)."""
        k_cross = inputs.positive("crossing_stiffness_pa", crossing_stiffness_pa)
        r_pack = self.packing_spacing_m
        if self._law_slope(np.array(r_pack)) < k_cross:
            return r_pack
        lo, hi = r_pack, self.diameter_m  # slope(lo) >= k_cross > slope(hi)
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if self._law_slope(np.array(mid)) >= k_cross:
                lo = mid
            else:
                hi = mid
        return lo

    def line_force_n_per_m(self, spacing_m, crossing_stiffness_pa: float):
        """Normal force per unit length q [N/m] between two neighbours at axis spacing
        ``spacing_m`` [m] (array or float): the law's p_s·r/√3 down to the core spacing,
        then linear with slope k'_cross; 0 beyond d."""
        r = np.asarray(spacing_m, float)
        rc = self.core_spacing_m(crossing_stiffness_pa)
        q_core = float(self._law_pressure(np.array(rc)) * rc / SQRT3)
        q = np.where(r > rc, self._law_pressure(np.maximum(r, rc)) * np.maximum(r, rc) / SQRT3,
                     q_core + crossing_stiffness_pa * (rc - r))
        q = np.where(r < self.diameter_m, q, 0.0)
        return float(q) if q.ndim == 0 else q

    def pair_force_n(self, spacing_m: np.ndarray, bond_length_m: float,
                     crossing_stiffness_pa: float) -> np.ndarray:
        """Normal force of one bead pair [N] at centre distance ``spacing_m`` (ascending
        array ending at d) such that two parallel chains *in register* carry the line force
        q per unit length (:meth:`line_force_n_per_m`).

        In register, a bead touches its partner at r and, past δ/d = 1 − sqrt(1 − (l0/d)²),
        also the partner's neighbours at ρ = sqrt(r² + l0²); so F(r) = l0·q(r) −
        2·F(ρ)·r/ρ, solved from r = d inwards (ρ > r is known). Exact while the next
        neighbours (2·l0 along) cannot touch above the core spacing r_core (r_core² + 4·l0² ≥
        d²: s/d ≳ 0.4 for the glass law's core at 0.62 d). Finer chains take F = l0·q: the
        same recursion over several neighbours is unstable there (it oscillates and turns
        negative), so past δ/d = 1 − sqrt(1 − (l0/d)²) they are stiffer than the law
        (3.2 % of d at s/d = 0.25) — the limit the linear contact has too.
        """
        r = np.asarray(spacing_m, float)
        l0 = bond_length_m
        target = l0 * self.line_force_n_per_m(r, crossing_stiffness_pa)
        core = self.core_spacing_m(crossing_stiffness_pa)
        if core**2 + 4 * l0**2 < self.diameter_m**2:
            return target
        force = target.copy()
        rho = np.hypot(r, l0)
        touching = np.nonzero(rho < self.diameter_m)[0]
        for i in touching[::-1]:  # from the largest r inwards: F(rho) is known already
            force[i] = target[i] - 2.0 * np.interp(rho[i], r, force) * r[i] / rho[i]
        return force

    def max_pair_stiffness_n_per_m(self, bond_length_m: float,
                                   crossing_stiffness_pa: float) -> float:
        """Largest tangent stiffness of one bead pair [N/m] (:meth:`pair_force_n`), for the
        stable time step: k'_cross·l0 in the core, up to 1.6× that just inside it where the
        second neighbours' share is taken off (glass law, s/d 0.5)."""
        return _max_pair_stiffness(self, bond_length_m, crossing_stiffness_pa)

    def table_text(self, bond_length_m: float, crossing_stiffness_pa: float,
                   keyword: str = "WITHIN_FAMILY", points: int = TABLE_POINTS) -> str:
        """LAMMPS ``pair_style table`` section of the excess force per bead pair over the
        linear part: F − k_lin·l0·(d − r) [N] (F: :meth:`pair_force_n`) and its energy [J],
        r from :data:`TABLE_INNER`·d to d (``bond_length_m`` = l0)."""
        l0 = inputs.positive("bond_length_m", bond_length_m)
        d = self.diameter_m
        r = np.linspace(TABLE_INNER * d, d, points)
        k_lin = self.linear_stiffness_pa()
        excess = self.pair_force_n(r, l0, crossing_stiffness_pa) - k_lin * l0 * (d - r)
        excess[-1] = 0.0
        # energy: the integral of the force from r to the cutoff d (trapezoid, fine grid)
        seg = 0.5 * (excess[1:] + excess[:-1]) * np.diff(r)
        energy = np.concatenate([np.cumsum(seg[::-1])[::-1], [0.0]])
        lines = [f"# fabmd: within-family contact, {self.law.name} law (excess over the "
                 f"linear part k_lin = {k_lin:.6g} Pa, per bead pair l0 = {l0:.6g} m)",
                 "", keyword, f"N {points} R {r[0]:.12g} {r[-1]:.12g}", ""]
        lines += [f"{i} {ri:.12g} {ei:.12g} {fi:.12g}"
                  for i, (ri, ei, fi) in enumerate(zip(r, energy, excess, strict=True), start=1)]
        return "\n".join(lines) + "\n"


@lru_cache(maxsize=32)
def _max_pair_stiffness(bundle: BundleContact, bond_length_m: float,
                        crossing_stiffness_pa: float) -> float:
    r = np.linspace(TABLE_INNER * bundle.diameter_m, bundle.diameter_m, TABLE_POINTS)
    force = bundle.pair_force_n(r, bond_length_m, crossing_stiffness_pa)
    return float(np.max(-np.diff(force) / np.diff(r)))
