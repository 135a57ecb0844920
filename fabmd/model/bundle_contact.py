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
:func:`~fabmd.model.compaction.bundle_pressure_pa`'s virial, p = √3·q/g). The shift makes
the realised law p(Vf) − p(Vf_touch): at a pressure P the bundle reaches the law's Vf at
P + p(Vf_touch) (:meth:`BundleContact.volume_fraction`).

From line force to bead pairs (register average). Two parallel bead chains at axis
distance h touch through every pair closer than d, so the force per length depends on
their register (how one chain's beads sit along the other's). Fibres in a yarn have no
register to keep, so the pair force F(ρ) is chosen so that the *average over register*
is q(h) at every h:

    q(h) = (2h/l0²) · ∫_h^d F(ρ)/sqrt(ρ² − h²) dρ,

an Abel transform, inverted once on a grid (:func:`_unit_pair_force`): F = l0²·f(ρ) with
f independent of the bead spacing l0, so refining the beads changes the resolution, not
the mean force per length (tests: two fibres at s/d 0.5 and 0.25, averaged over
register). One register differs from the mean — the bead chain's bumpiness,
:meth:`BundleContact.mean_line_force_n_per_m` with ``register``: on the glass law at s/d
0.5 from 0–1.36× at δ = 0.03 d (half-offset chains do not touch yet) to 0.96–1.03× at
0.2 d; at s/d 0.25 0.68–1.12× and 0.97–1.02×. (Matching one register exactly instead —
this module's first form — needs a recursion over the second, third … neighbours that
oscillates for fine chains: at s/d 0.25 and δ = 0.2 d that form carried 2.6× the law.)

Packing limit. The van Wyk form stays finite at the densest packing of circular filaments
(Vf = π/(2√3), :data:`~fabmd.model.compaction.PACKING_LIMIT`); a bundle cannot pack denser.
So past the spacing where the bundle reaches it — or, if that comes first, where the law's
tangent reaches the crossing contact's stiffness k'_cross — each pair adds a hard core
k'_cross·l0·(r_core − r), as stiff as a crossing (per pair, so bumpy like a crossing);
the law's line force is continued past r_core with its own slope there before the
inversion, so the inverted force keeps a finite tangent. The stable time step
(:mod:`fabmd.model.timestep`) takes the pair's steepest tangent: the core's plus the law's
(about 1.05× the crossing's k_n on the glass law).

LAMMPS realisation (``pair_style hybrid/overlay granular table linear N``): ``granular``
keeps its per-type-pair Hooke coefficients (crossings stiff; same family a linear part
k_n,lin·(d − r), so that friction and damping act there), and a ``table`` on the
same-family type pairs adds the excess F − k_n,lin·(d − r) (:meth:`BundleContact.table_text`,
a file in the run folder). k_n,lin is the steepest line under F down to the core
(:meth:`BundleContact.linear_pair_stiffness_n_per_m`), so the total is F at every overlap.
Known limit: friction within a family is μ × the granular (linear) part only.

Families of different fibre diameters (:func:`law_sections`): each family's virtual fibre
has its own A and d, so each gets its own :class:`BundleContact` of the same law — its own
shift p(Vf_touch), core, linear part and table section at its own bead spacing; the law
per unit length is the stated one for every family. Pairs of different families are
crossings (the crossing contact), so no mixed-diameter section is needed.
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

    @property
    def table_end_text(self) -> str:
        """The table's outer end d as written in the table file."""
        return f"{self.diameter_m:.12g}"

    @property
    def cutoff_text(self) -> str:
        """The table's ``pair_coeff`` cutoff: 1e-9 of d inside the table's end. LAMMPS stops
        on a cutoff past the end ("Pair table cutoff outside of table": a 10-digit d rounded
        up did, on a 19-fibre Twintex yarn), and on a pair at the cutoff itself, whose
        table index rounds to the last row ("Pair distance > table outer cutoff": fibres
        built touching, at d to 1e-16, did). The law's force is 0 there anyway."""
        return f"{self.diameter_m * (1.0 - 1e-9):.12g}"

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

    def realisation(self) -> dict:
        """How the bead bundle realises the law: where its virtual fibres touch (Vf), the
        law's own start Vf0, and the pressure cut off below the touching state [Pa] (0
        when they touch at or below Vf0: the law acts as stated from Vf0). The contact
        diameter, and so the cut, comes from how the yarn's section packs its fibres."""
        return {"touching_vf": self.touching_vf, "law_vf0": self.law.vf0,
                "cut_pressure_pa": self.touching_pressure_pa}

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
        return np.maximum(0.0, self.law.pressure_pa(self.vf_at(r)) - self.touching_pressure_pa)

    def _law_slope(self, r: np.ndarray) -> np.ndarray:
        """dq/dδ of the law's line force at spacing r [Pa] (δ = d − r)."""
        k = self.law.coefficient * self.law.modulus_pa
        n = self.law.exponent
        vf = self.vf_at(r)
        loaded = (vf > self.law.vf0) & (r < self.diameter_m)
        return np.where(loaded, (2 * n * k * vf**n - self._law_pressure(r)) / SQRT3, 0.0)

    # -- the contact ----------------------------------------------------------------------
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

    def _line_force_for_inversion(self, r: np.ndarray, crossing_stiffness_pa: float):
        """The line force the pair force is inverted from [N/m]: the law down to the core
        spacing, then continued with the law's own slope there (C¹, so the inverted pair
        force keeps a finite tangent; the core's stiffness is added per pair)."""
        rc = self.core_spacing_m(crossing_stiffness_pa)
        slope = float(self._law_slope(np.array(rc)))
        q_core = float(self._law_pressure(np.array(rc)) * rc / SQRT3)
        law = self._law_pressure(np.maximum(r, rc)) * np.maximum(r, rc) / SQRT3
        q = np.where(r > rc, law, q_core + slope * (rc - r))
        return np.where(r < self.diameter_m, q, 0.0)

    def pair_force_n(self, spacing_m, bond_length_m: float,
                     crossing_stiffness_pa: float):
        """Normal force of one bead pair [N] at centre distance ``spacing_m`` [m] (array or
        float), bead spacing ``bond_length_m`` l0: two parallel chains carry the law's line
        force q per unit length *on average over their register* (module docstring), plus
        the hard core k'_cross·l0·(r_core − r) inside the core spacing.

        The register average of a pair force F over a chain of spacing l0 at axis distance
        h is q̄(h) = (2h/l0²)·∫_h^d F(ρ)/sqrt(ρ² − h²) dρ — an Abel transform, so
        F = l0²·f(ρ) with f independent of l0 (:func:`_unit_pair_force`): bead spacing
        changes the resolution, not the mean force per length.
        """
        r = np.asarray(spacing_m, float)
        l0 = inputs.positive("bond_length_m", bond_length_m)
        grid, unit = _unit_pair_force(self, crossing_stiffness_pa)
        core = self.core_spacing_m(crossing_stiffness_pa)
        force = l0**2 * np.interp(r, grid, unit, right=0.0) \
            + crossing_stiffness_pa * l0 * np.maximum(0.0, core - r)
        return float(force) if force.ndim == 0 else force

    def mean_line_force_n_per_m(self, spacing_m: float, bond_length_m: float,
                                crossing_stiffness_pa: float, register: float | None = None,
                                offsets: int = 64) -> float:
        """Force per unit length [N/m] between two parallel bead chains at axis distance
        ``spacing_m``: averaged over ``offsets`` registers, or at one ``register`` (the
        offset of one chain's beads along the other, as a fraction of l0): the in-register
        spread is the bead chain's bumpiness."""
        l0 = bond_length_m
        shifts = (np.arange(offsets) / offsets if register is None
                  else np.array([register])) * l0
        k = np.arange(-math.ceil(self.diameter_m / l0) - 1, math.ceil(self.diameter_m / l0) + 2)
        x = k[None, :] * l0 + shifts[:, None]
        rho = np.hypot(spacing_m, x)
        force = self.pair_force_n(rho, l0, crossing_stiffness_pa)
        return float(np.mean(np.sum(force * spacing_m / rho, axis=1)) / l0)

    def linear_pair_stiffness_n_per_m(self, bond_length_m: float,
                                      crossing_stiffness_pa: float) -> float:
        """k_n of the granular (linear) part of one bead pair [N/m]: the steepest line
        k·(d − r) under the pair force down to the core (friction and damping act on it);
        floored at :data:`MIN_LINEAR_SHARE` of the pair force's mean slope over the law's
        range when the law starts only past touching (Vf_touch < Vf0)."""
        d = self.diameter_m
        core = self.core_spacing_m(crossing_stiffness_pa)
        r = np.linspace(core, d, 2001)[:-1]
        ratio = self.pair_force_n(r, bond_length_m, crossing_stiffness_pa) / (d - r)
        return max(float(ratio.min()), MIN_LINEAR_SHARE * float(ratio[0]))

    def linear_stiffness_pa(self, bond_length_m: float, crossing_stiffness_pa: float) -> float:
        """The linear part per unit length of bead spacing [Pa]:
        :meth:`linear_pair_stiffness_n_per_m` / l0 (it grows with l0: the pair force
        scales as l0²)."""
        return self.linear_pair_stiffness_n_per_m(bond_length_m, crossing_stiffness_pa) \
            / bond_length_m

    def max_pair_stiffness_n_per_m(self, bond_length_m: float,
                                   crossing_stiffness_pa: float) -> float:
        """Largest tangent stiffness of one bead pair [N/m] (:meth:`pair_force_n`), for the
        stable time step: the core's k'_cross·l0 plus the law's own tangent there."""
        r = np.linspace(TABLE_INNER * self.diameter_m, self.diameter_m, TABLE_POINTS)
        force = self.pair_force_n(r, bond_length_m, crossing_stiffness_pa)
        return float(np.max(-np.diff(force) / np.diff(r)))

    def table_text(self, bond_length_m: float, crossing_stiffness_pa: float,
                   keyword: str = "WITHIN_FAMILY", points: int = TABLE_POINTS) -> str:
        """LAMMPS ``pair_style table`` section of the excess force per bead pair over the
        linear part: F − k_n,lin·(d − r) [N] (F: :meth:`pair_force_n`; k_n,lin:
        :meth:`linear_pair_stiffness_n_per_m`) and its energy [J], r from
        :data:`TABLE_INNER`·d to d (``bond_length_m`` = l0)."""
        l0 = inputs.positive("bond_length_m", bond_length_m)
        d = self.diameter_m
        r = np.linspace(TABLE_INNER * d, d, points)
        k_lin = self.linear_pair_stiffness_n_per_m(l0, crossing_stiffness_pa)
        excess = self.pair_force_n(r, l0, crossing_stiffness_pa) - k_lin * (d - r)
        return table_section(r, excess, keyword, self.table_end_text,
                             f"within-family contact, {self.law.name} law, register-averaged "
                             f"(excess over the linear part k_n = {k_lin:.6g} N/m, per bead "
                             f"pair l0 = {l0:.6g} m)")


def table_section(r: np.ndarray, excess: np.ndarray, keyword: str, end_text: str,
                  title: str) -> str:
    """A LAMMPS ``pair_style table`` section: forces ``excess`` [N] at distances ``r`` [m]
    (the last row set to 0, the cutoff) and their energy [J], the integral of the force from
    r to the cutoff (trapezoid); ``end_text`` the outer end as written, ``title`` its
    comment."""
    excess = np.array(excess, float)
    excess[-1] = 0.0
    seg = 0.5 * (excess[1:] + excess[:-1]) * np.diff(r)
    energy = np.concatenate([np.cumsum(seg[::-1])[::-1], [0.0]])
    lines = [f"# fabmd: {title}", "", keyword, f"N {len(r)} R {r[0]:.12g} {end_text}", ""]
    lines += [f"{i} {ri:.12g} {ei:.12g} {fi:.12g}"
              for i, (ri, ei, fi) in enumerate(zip(r, energy, excess, strict=True), start=1)]
    return "\n".join(lines) + "\n"


#: rows of the grid the pair force is inverted on (r from TABLE_INNER·d to d)
INVERSION_POINTS = 4000


@lru_cache(maxsize=32)
def _unit_pair_force(bundle: BundleContact, crossing_stiffness_pa: float):
    """(r, f) with F = l0²·f: the pair force whose register average is the law's line
    force, by inverting q̄(h)·l0²/(2h) = ∫_h^d F(ρ)/sqrt(ρ² − h²) dρ on a grid from d
    inwards (F piecewise linear, each segment's integral in closed form; a triangular
    solve — stable, unlike matching one register, whose recursion over several neighbours
    oscillates)."""
    d = bundle.diameter_m
    r = np.linspace(TABLE_INNER * d, d, INVERSION_POINTS)
    target = bundle._line_force_for_inversion(r, crossing_stiffness_pa) / (2.0 * r)
    f = np.zeros_like(r)
    for i in range(len(r) - 2, -1, -1):
        h = r[i]
        lo, hi = r[i:-1], r[i + 1:]
        s_lo = np.sqrt(np.maximum(lo * lo - h * h, 0.0))
        s_hi = np.sqrt(hi * hi - h * h)
        i0 = np.log((hi + s_hi) / (lo + s_lo))  # ∫ dρ/sqrt(ρ² − h²)
        i1 = s_hi - s_lo  # ∫ ρ dρ/sqrt(ρ² − h²)
        w_lo = (hi * i0 - i1) / (hi - lo)  # weights of f at each segment's two ends
        w_hi = (i1 - lo * i0) / (hi - lo)
        known = np.dot(w_lo[1:], f[i + 1:-1]) + np.dot(w_hi, f[i + 1:])
        f[i] = (target[i] - known) / w_lo[0]
    return r, f


@dataclass(frozen=True)
class LawSection:
    """One section of the within-family table: a family's bundle at its bead spacing.

    Attributes:
        keyword: the section's keyword in the table file (``pair_coeff ... table``).
        bundle: the family's :class:`BundleContact` (its own A and d, the stated law).
        bond_length_m: the bead spacing l0 [m] its pair force is scaled to (F = l0²·f).
    """

    keyword: str
    bundle: BundleContact
    bond_length_m: float

    def table_text(self, crossing_stiffness_pa: float) -> str:
        """The section's text (:meth:`BundleContact.table_text`)."""
        return self.bundle.table_text(self.bond_length_m, crossing_stiffness_pa,
                                      self.keyword, TABLE_POINTS)

    def linear_pair_stiffness_n_per_m(self, crossing_stiffness_pa: float) -> float:
        """k_n of its granular (linear) part [N/m] at its bead spacing."""
        return self.bundle.linear_pair_stiffness_n_per_m(self.bond_length_m,
                                                         crossing_stiffness_pa)

    def max_pair_stiffness_n_per_m(self, crossing_stiffness_pa: float) -> float:
        """Its steepest pair tangent [N/m] at its bead spacing (the time step)."""
        return self.bundle.max_pair_stiffness_n_per_m(self.bond_length_m,
                                                      crossing_stiffness_pa)


def check_family_laws(reference: BundleContact | None, family_laws,
                      stiffness_pa: float | None = None, normal: str = "hooke",
                      per_length: bool = True) -> tuple:
    """Check a contact's within-family law ``reference`` (with the contact's
    ``within_family_stiffness_pa``, ``normal`` and whether its stiffness is per length) and
    return ``family_laws`` as a tuple of (family, :class:`BundleContact`), each of
    ``reference``'s law on that family's own fibre; raises InputError."""
    if reference is not None:
        if not isinstance(reference, BundleContact):
            raise InputError("contact.within_family_law must be a BundleContact, got "
                             f"{reference!r}")
        if stiffness_pa is not None:
            raise InputError("contact.within_family_law: give it or "
                             "within_family_stiffness_pa, not both (the law sets the "
                             f"linear part), got {stiffness_pa!r}")
        if normal != "hooke" or not per_length:
            raise InputError(
                "contact.within_family_law: needs normal = 'hooke' and the stiffness per "
                "unit length (no stiffness_factor / stiffness_n_per_m), got normal = "
                f"{normal!r}")
    pairs = tuple(tuple(item) for item in family_laws)
    if pairs and reference is None:
        raise InputError("contact.within_family_laws: needs within_family_law (the law), "
                         f"got families {[name for name, *_ in pairs]}")
    for item in pairs:
        if len(item) != 2 or not isinstance(item[1], BundleContact) \
                or item[1].law != reference.law:
            raise InputError("contact.within_family_laws: each entry must be (family, "
                             f"BundleContact of the law {reference.law.name!r}), got {item!r}")
    return pairs


def law_sections(reference: BundleContact, family_laws, beads, keyword: str
                 ) -> list[LawSection]:
    """The within-family table's sections for bead kinds ``beads`` (each with
    ``diameter_m`` and ``bond_length_m``).

    One bundle for all families (one fibre kind, or ``family_laws`` empty): one section
    ``keyword`` at the widest spacing of all beads. Several: one section per distinct
    family bundle, ``<keyword>_<FAMILY>`` (the first family that has it), at the widest
    spacing of the beads of its diameter; a bundle no bead has is left out.
    """
    distinct: list[tuple[str, BundleContact]] = []
    for name, bundle in family_laws:
        if all(bundle != other for _, other in distinct):
            distinct.append((name, bundle))
    if len(distinct) <= 1:
        return [LawSection(keyword, reference, max(b.bond_length_m for b in beads))]
    out = []
    for name, bundle in distinct:
        d = bundle.diameter_m
        spacings = [b.bond_length_m for b in beads if abs(b.diameter_m - d) <= 1e-9 * d]
        if spacings:
            out.append(LawSection(f"{keyword}_{name.upper()}", bundle, max(spacings)))
    return out
