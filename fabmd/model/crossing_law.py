"""A crossing of two virtual fibres that follows the yarn's compaction law (SI).

A virtual fibre stands for a sub-bundle of filaments, so where two of them cross (warp over
weft, binder over weft) both sub-bundles compact, as the yarn does under a platen: the
crossing is as soft through the thickness as the yarn's compaction law says, not as a solid
glass rod (``contact.crossing = "law"``; the default crossing is the stiff
``normal_stiffness_pa``). Measured on the plain-weave example's periodic cell (RESULTS
"Yarns that keep their width"): with stiff crossings and the weaving tension kept, its yarns
are one row of virtual fibres pressed to the law's core, they keep their width while the
cell shears, the crossing yarn's run from over to under shortens (p − w/cos γ), its crimp
rises at a fixed period and the fibres stretch: the cell locks near 17°.

The crossing's law. Two sub-bundles of contact diameter d cross at angle θ over a patch
d × d/sin θ; pressed together by δ (axis gap g = d − δ), each compacts through its height by
the strain ε = δ/(2d), so its fibre volume fraction rises from the touching bundle's Vf_t
(:attr:`BundleContact.touching_vf`, the within-family law's zero) to Vf_t/(1 − ε), and

    F(δ) = p_s(Vf_t/(1 − δ/(2d))) · d² / sin θ,     p_s(Vf) = p(Vf) − p(Vf_t),

p the compaction law (:class:`~fabmd.model.compaction.CompactionLaw`), shifted as the
within-family law is, so a yarn of crossing virtual fibres and a yarn of parallel ones
compact by one law. Refining the fibres makes the patches smaller and more numerous, the
strain per crossing the yarn's local strain: the physics stays the yarn's.

Bead pairs. Averaged over the two chains' registers, the bead pairs of two straight chains
crossing at θ fill the plane with density 1/(l0²·sin θ); a pair at distance ρ pushes the
chains apart with F(ρ)·g/ρ, so the mean crossing force is

    F_z(g) = (2π·g/(l0²·sin θ)) · ∫_g^d F(ρ) dρ,

and the pair force that gives the law above at every g, with no l0 left, is

    F(ρ) = l0² · (d²/(2π)) · (p_s′(δ)/ρ + p_s(δ)/ρ²),   δ = d − ρ

(p_s′ = dp_s/dδ): the crossing does not see the bead spacing (tests: Python sums over
registers and a LAMMPS probe at s/d 0.5 and 0.25). One register differs from the mean (the
bead chains' bumpiness, as for the Hooke crossing of ``crossing = "per_crossing"``).

Hard core. A crossing cannot pack its sub-bundles denser than the bundle's own neighbours
do: inside the within-family law's core spacing r_core
(:meth:`BundleContact.core_spacing_m`, the packing limit) each pair adds the per-crossing
Hooke core 2k'·l0²·(r_core − r)/d (k' the crossing stiffness ``normal_stiffness_pa``), the
law's pair force is continued with its slope there, and overlaps are counted from r_core
(so ``overlap_warning`` means what it means within a family).

LAMMPS realisation: as within a family (``granular`` keeps a linear part k_lin·(d − r) on
which friction and damping act, a ``table`` section ``CROSSING`` adds the rest). Known
limit: Coulomb friction caps μ × the linear part only (:meth:`CrossingLaw.friction_share`
says how much of the normal force that is).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError
from .bundle_contact import TABLE_INNER, TABLE_POINTS, BundleContact, table_section

#: the crossing's table section keyword (in the within-family law's table file)
CROSSING_KEYWORD = "CROSSING"
#: the linear part's floor, as a share of the pair force's mean secant over the law's range
MIN_LINEAR_SHARE = 0.05


@dataclass(frozen=True)
class CrossingLaw:
    """The crossing of two virtual fibres of ``bundle`` (module docstring).

    Args:
        bundle: the yarn's :class:`BundleContact` (law, filament area, contact diameter).
        crossing_stiffness_pa: k' [Pa] of the hard core (the stiff crossing's per-length
            stiffness; its per-crossing pair form 2k'·l0²/d).
    """

    bundle: BundleContact
    crossing_stiffness_pa: float

    def __post_init__(self):
        if not isinstance(self.bundle, BundleContact):
            raise InputError(f"crossing_law.bundle must be a BundleContact, got {self.bundle!r}")
        inputs.positive("crossing_law.crossing_stiffness_pa", self.crossing_stiffness_pa)

    @property
    def diameter_m(self) -> float:
        return self.bundle.diameter_m

    @property
    def core_spacing_m(self) -> float:
        """r_core [m]: the within-family law's core spacing (the packing limit)."""
        return self.bundle.core_spacing_m(self.crossing_stiffness_pa)

    # -- the crossing ----------------------------------------------------------------------
    def _vf(self, overlap):
        strain = np.asarray(overlap, float) / (2.0 * self.diameter_m)
        return self.bundle.touching_vf / (1.0 - strain)

    def pressure_pa(self, overlap_m):
        """p_s [Pa] of the crossing's patch at overlap δ = ``overlap_m`` (array or float),
        the law continued linearly past the core overlap d − r_core."""
        delta = np.asarray(overlap_m, float)
        dc = self.diameter_m - self.core_spacing_m
        inside = np.minimum(np.maximum(delta, 0.0), dc)
        p = self._law(inside) + self._slope(np.array(dc)) * np.maximum(delta - dc, 0.0)
        p = np.where(delta > 0.0, p, 0.0)
        return float(p) if p.ndim == 0 else p

    def _law(self, delta: np.ndarray) -> np.ndarray:
        """p_s at overlap δ inside the core overlap [Pa] (the within-family law's shift)."""
        return np.maximum(0.0, self.bundle.law.pressure_pa(self._vf(delta))
                          - self.bundle.touching_pressure_pa)

    def _slope(self, delta: np.ndarray) -> np.ndarray:
        """dp_s/dδ [Pa/m] inside the core overlap."""
        law = self.bundle.law
        k = law.coefficient * law.modulus_pa
        vf = self._vf(delta)
        strain = delta / (2.0 * self.diameter_m)
        slope = k * law.exponent * vf**law.exponent / (2.0 * self.diameter_m * (1.0 - strain))
        return np.where(vf > law.vf0, slope, 0.0)

    def force_n(self, overlap_m, angle_deg: float = 90.0):
        """The law's crossing force F(δ) = p_s·d²/sin θ [N], without the hard core (the
        closed form the register-averaged bead pairs give inside the core overlap)."""
        s = math.sin(math.radians(inputs.in_range("angle_deg", angle_deg, 0, 90, low_open=True)))
        return self.pressure_pa(overlap_m) * self.diameter_m**2 / s

    # -- bead pairs ------------------------------------------------------------------------
    def pair_force_n(self, distance_m, bond_length_m: float):
        """Force of one bead pair [N] at centre distance ``distance_m`` (array or float), bead
        spacing ``bond_length_m`` l0: l0²·d²/(2π)·(p_s′/ρ + p_s/ρ²) plus the hard core
        2k'·l0²·(r_core − ρ)/d; 0 at and beyond d."""
        l0 = inputs.positive("bond_length_m", bond_length_m)
        rho = np.asarray(distance_m, float)
        d, rc = self.diameter_m, self.core_spacing_m
        delta = d - rho
        dc = d - rc
        slope = self._slope(np.minimum(np.maximum(delta, 0.0), dc))
        safe = np.maximum(rho, 1e-3 * d)
        law = l0**2 * d**2 / (2.0 * math.pi) * (slope / safe + self.pressure_pa(delta) / safe**2)
        core = 2.0 * self.crossing_stiffness_pa * l0**2 / d * np.maximum(rc - rho, 0.0)
        force = np.where(rho < d, law + core, 0.0)
        return float(force) if force.ndim == 0 else force

    def mean_force_n(self, overlap_m: float, bond_length_m: float, angle_deg: float = 90.0,
                     grid: int = 32) -> float:
        """Normal force [N] of two straight chains crossing at ``angle_deg``, pressed to
        ``overlap_m``, averaged over a ``grid`` × ``grid`` set of registers (Python sums of
        :meth:`pair_force_n`: what the bead model carries)."""
        l0, d = bond_length_m, self.diameter_m
        gap = d - overlap_m
        t = math.radians(angle_deg)
        e2 = np.array([math.cos(t), math.sin(t)])
        reach = math.ceil(2 * d / (l0 * math.sin(t))) + 1
        k = np.arange(-reach, reach + 1)
        total = 0.0
        shifts = (np.arange(grid) + 0.5) / grid
        for u in shifts:
            a = np.column_stack([(k + u) * l0, np.zeros_like(k, float)])
            for v in shifts:
                b = ((k + v) * l0)[:, None] * e2
                s = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
                rho = np.hypot(s, gap)
                total += float(np.sum(self.pair_force_n(rho, l0) * gap / rho))
        return total / grid**2

    def linear_pair_stiffness_n_per_m(self, bond_length_m: float) -> float:
        """k_n of the granular (linear) part [N/m]: the steepest line k·(d − r) under the pair
        force down to the core, floored at :data:`MIN_LINEAR_SHARE` of the mean secant."""
        d = self.diameter_m
        r = np.linspace(self.core_spacing_m, d, 2001)[:-1]
        ratio = self.pair_force_n(r, bond_length_m) / (d - r)
        return max(float(ratio.min()), MIN_LINEAR_SHARE * float(ratio.mean()))

    def friction_share(self, overlap_m: float, bond_length_m: float) -> float:
        """Share of a crossing's normal force [0–1] that friction acts on (the linear part's
        crossing force over the whole), register-averaged at 90°."""
        d, gap = self.diameter_m, self.diameter_m - overlap_m
        rho = np.linspace(gap, d, 4001)
        k_lin = self.linear_pair_stiffness_n_per_m(bond_length_m)
        whole = np.trapezoid(self.pair_force_n(rho, bond_length_m), rho)
        linear = np.trapezoid(k_lin * (d - rho), rho)
        return float(linear / whole) if whole > 0 else 1.0

    def max_pair_stiffness_n_per_m(self, bond_length_m: float) -> float:
        """Largest tangent of one pair [N/m] (the stable time step)."""
        d = self.diameter_m
        r = np.linspace(TABLE_INNER * d, d, TABLE_POINTS)
        force = self.pair_force_n(r, bond_length_m)
        return float(np.max(-np.diff(force)[:-1] / np.diff(r)[:-1]))

    def table_text(self, bond_length_m: float, keyword: str = CROSSING_KEYWORD,
                   points: int = TABLE_POINTS) -> str:
        """LAMMPS ``pair_style table`` section: the pair force's excess over the linear part
        [N] and its energy [J], r from :data:`TABLE_INNER`·d to d."""
        l0 = inputs.positive("bond_length_m", bond_length_m)
        d = self.diameter_m
        r = np.linspace(TABLE_INNER * d, d, points)
        k_lin = self.linear_pair_stiffness_n_per_m(l0)
        excess = self.pair_force_n(r, l0) - k_lin * (d - r)
        return table_section(r, excess, keyword, self.bundle.table_end_text,
                             f"crossing contact, {self.bundle.law.name} law through the patch "
                             f"(excess over the linear part k_n = {k_lin:.6g} N/m, per bead "
                             f"pair l0 = {l0:.6g} m)")
