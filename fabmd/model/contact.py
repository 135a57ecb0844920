"""Contact between virtual fibres, and between fibres and tools (SI).

Fibre–fibre contact is a granular pair style between beads of *different*
fibres (``neigh_modify exclude molecule/intra all``), with a normal spring
(Hooke, or Hertz matched to Hooke at a reference overlap), normal damping as a
fraction of critical, and a history-dependent tangential spring capped by
Coulomb friction μ·F_n. Tools (walls, punch, die, clamps) have their own μ.

Normal stiffness per unit length of fibre (default). The contact is a property
of the fibre, stated in physical units: ``normal_stiffness_pa`` = k' is the
normal force per unit length of contact per unit overlap of two parallel fibres
[N/m per m = Pa]. Each bead pair gets

    k_n = k' · l0        (l0 = bead spacing),

because two parallel bead chains in register touch once per bead: the force per
unit length is k_n·δ/l0 = k'·δ whatever the spacing (exact while no second
neighbour touches, δ/d < 1 − sqrt(1 − (s/d)²): 13 % of d at s/d = 0.5, 3.2 % at
s/d = 0.25; measured in ``tests/test_contact_scaling.py``; past it the finer chain
is stiffer). A crossing of two fibres is a point contact: in register one bead
pair carries it and its force k'·l0·δ halves when l0 halves; averaged over bead
positions the number of pairs in contact grows as 1/l0² and the force doubles
from s/d 0.5 to 0.25. Crossings are not converged in s/d (:func:`crossing_force_n`).
With k_n ∝ l0 and bead mass ∝ l0 the contact's share of the stability bound
(ω² ≤ (4k + 6k_n)/m) is the same at every spacing.
Default k' (``normal_stiffness_pa`` not given): 0.4·E·A/d² of the stiffest virtual
fibre — a transverse stiffness of the fibre itself (0.1·π·E ≈ 0.31·E for a solid
fibre, the order of a solid rod's line-contact stiffness), chosen so that at the
default spacing s/d = 0.5 every bead pair gets exactly the former default
0.1·E·A/l0; at other spacings k_n = k'·l0 follows the spacing. A yarn of filaments
is far softer across: a compaction law (:mod:`fabmd.model.compaction`) gives k'
from the yarn's own behaviour.

Split contact (``within_family_stiffness_pa``). A yarn of filaments is soft across,
but a crossing of two yarns is not a point contact of two filaments: its pressure is
carried by the whole bundle over a small patch. With one k' for all pairs, a k' as soft
as the yarn's compaction law lets crossing virtual fibres pass through (20 % overlap at
100 kPa on the crimped example), and a k' that holds crossings makes yarns as stiff
across as solid glass (they cannot narrow, the shear locks where the yarn widths meet).
Atom types are one per yarn family, so the contact can be split per type pair:
fibres of the same family (within a yarn, and neighbouring parallel yarns: the lateral
compaction that sets yarn narrowing and shear locking) touch with
``within_family_stiffness_pa`` (e.g. from a compaction law,
:func:`fabmd.model.compaction.contact_for_yarn`), fibres of different families
(warp–weft, binder–others) with ``normal_stiffness_pa`` (default 0.4·E·A/d²). This needs
``pair_style granular`` with one ``pair_coeff i j`` per type pair (the classic
``gran/*`` styles take one global set of coefficients), about 2.5× the loop time
(section "Pair styles"); Hooke only. The time step follows the stiffer of the two.
Measured (RESULTS "Split contact"): with the glass law's secant k' at 100 kPa, crimping the
plain weave towards 1 cN/tex pushes fibres of one yarn through each other (overlap > 0.5 d
at −6 %): a linear contact has no packing limit.

Within-family law (``within_family_law``): same-family pairs follow the compaction law
itself, one table section per family diameter (:mod:`fabmd.model.bundle_contact`); the
energy balance is not measured with it (:mod:`fabmd.scene.energy`).

Crossing per crossing (``crossing = "per_crossing"``, opt-in; default ``"per_length"``).
A crossing is a point contact, so a k_n ∝ l0 makes its force follow the bead spacing
(above). Averaged over the two chains' registers (shifts along each chain, uniform over
one spacing) the bead pairs of two straight chains crossing at angle θ fill the plane
with density 1/(l0²·sin θ), so with Hooke pairs k_n = c·l0² the mean force is an integral
that no longer sees l0:

    F(δ) = (c/sin θ)·∫ (d − r)·(g/r) dA = π·c·g·δ²/sin θ     (g = d − δ: axis gap),

and with c = 2k'/d (the per-length k_n at s/d = 0.5, where both forms agree)

    F(δ) = 2π·k'·δ²·(1 − δ/d)/sin θ   [N],

a law of the crossing alone: the plain-weave example's default k' = 8.9·10⁹ Pa
(d = 0.333 mm) gives 5.4 N at δ = 0.03 d and 90°, at any bead spacing (:func:`crossing_law_force_n`;
``tests/test_contact_crossing.py``: Python sums and LAMMPS probes at s/d 0.5 and 0.25).
One register differs from the mean (the crossing's bumpiness). Every pair of different
families gets k_n = 2k'·l0²/d (l0 the widest spacing, d the smallest diameter: exact for
one bead kind); parallel fibres of different families then carry k'·δ·(2l0/d) per length,
so this needs per-type-pair coefficients — a split contact or the within-family law, whose
same-family pairs stay per unit length (refused otherwise). The time step follows the new
k_n (half the per-length one at s/d 0.25, twice at s/d 1). The within-family law's hard
core stays k'·l0 per pair (parallel chains).

Older settings still work and are flagged as discretisation-dependent:
``stiffness_factor`` (k_n = factor·E·A/l0, transverse stiffness per length ∝ 1/l0²)
and ``stiffness_n_per_m`` (a fixed k_n per bead pair, ∝ 1/l0 per length).

Every run with contact reports the largest overlap it saw
(:func:`fabmd.scene.blocks.overlap_monitor`), warns past ``overlap_warning`` and
stops past ``overlap_limit``.

Pair style (measured, ``benchmarks/RESULTS.md``, section "Pair styles"): on the
same 12,200 beads ``gran/hooke/history`` computes the same forces as ``pair_style
granular`` (hooke + linear_history, to 5e-16) at 1/3.4 of the pair time and 1/2.5 of
the loop time, and it has an OpenMP version; ``gran/hooke`` (no tangential history)
is cheaper again but carries no Coulomb friction. So :meth:`ContactModel.pair_style`
picks ``gran/hooke`` for frictionless Hooke contact, else ``gran/hooke/history`` or
``gran/hertz/history``.

Bead chains are bumpy: a fibre sliding along another sees F_t/F_n ripple between
tan(atan μ ∓ asin(s/2d)) and its mean exceed μ by about (1 + μ²)·asin²(s/2d)/3
(2.3 % at the default s/d = 0.5; section "Bead-chain ripple").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import inputs
from ..errors import InputError
from ..units import quantity
from .beads import BeadParameters
from .bundle_contact import BundleContact, LawSection, check_family_laws, law_sections
from .crossing_law import CROSSING_KEYWORD, CrossingLaw

NORMAL_MODELS = ("hooke", "hertz")
#: ``ContactModel.crossing``: k_n of pairs of different families ∝ l0 (per unit length of
#: fibre) or ∝ l0² (a force law per crossing; module docstring "Crossing per crossing")
CROSSING_FORMS = ("per_length", "per_crossing", "law")
#: s/d at which the per-crossing k_n = k'·l0²/(ratio·d) equals the per-length k'·l0
CROSSING_REFERENCE_RATIO = 0.5
#: the within-family law's table file in the run folder, and its section keyword
WITHIN_FAMILY_TABLE = "within_family.table"
WITHIN_FAMILY_KEYWORD = "WITHIN_FAMILY"
#: default k' = DEFAULT_TRANSVERSE_FACTOR · E·A/d² (module docstring): the former default
#: k_n = 0.1·E·A/l0 at s/d = 0.5, now per unit length
DEFAULT_TRANSVERSE_FACTOR = 0.4


def widest_spacing(beads: list[BeadParameters]) -> float:
    """The widest bead spacing l0 of ``beads`` [m]: what per-pair laws are scaled to."""
    return max(b.bond_length_m for b in beads)


def default_stiffness_pa(beads: list[BeadParameters]) -> float:
    """Default k' [Pa]: 0.4·E·A/d² of the stiffest virtual fibre (module docstring)."""
    return DEFAULT_TRANSVERSE_FACTOR * max(b.axial_stiffness_n / b.diameter_m**2
                                           for b in beads)


def _normal_stiffness(owner: str, per_length_pa: float | None, factor: float | None,
                      explicit: float | None, beads: list[BeadParameters]) -> float:
    """k_n per bead pair [N/m]: explicit, else factor·E·A/l0 (legacy), else k'·l0."""
    if explicit is not None:
        return explicit
    if not beads:
        raise InputError(f"{owner}: no bead parameters given to derive the contact stiffness")
    if factor is not None:
        return factor * max(b.spring_n_per_m for b in beads)
    k_line = per_length_pa if per_length_pa is not None else default_stiffness_pa(beads)
    # the widest spacing: the stiffest pair, which sets the time step and the overlaps
    return k_line * widest_spacing(beads)


def crossing_pair_stiffness_n_per_m(stiffness_pa: float, spacing_m: float,
                                    diameter_m: float, crossing: str = "per_length") -> float:
    """k_n of one bead pair of two crossing chains [N/m]: k'·l0 (``"per_length"``) or
    k'·l0²/(0.5·d) = 2k'·l0²/d (``"per_crossing"``, module docstring)."""
    inputs.one_of("contact.crossing", crossing, CROSSING_FORMS)
    if crossing == "per_length":
        return stiffness_pa * spacing_m
    return stiffness_pa * spacing_m**2 / (CROSSING_REFERENCE_RATIO * diameter_m)


def crossing_law_force_n(stiffness_pa: float, diameter_m: float, overlap_m: float,
                         angle_deg: float = 90.0) -> float:
    """Force [N] of one crossing with ``crossing = "per_crossing"``, averaged over the
    chains' registers: 2π·k'·δ²·(1 − δ/d)/sin θ (exact for Hooke pairs while δ < d;
    module docstring), independent of the bead spacing."""
    delta = inputs.in_range("overlap_m", overlap_m, 0.0, diameter_m, high_open=True)
    sine = math.sin(math.radians(inputs.in_range("angle_deg", angle_deg, 0.0, 180.0,
                                                 low_open=True, high_open=True)))
    return 2.0 * math.pi * stiffness_pa * delta**2 * (1.0 - delta / diameter_m) / sine


def crossing_force_n(stiffness_pa: float, spacing_m: float, diameter_m: float,
                     overlap_m: float, angle_deg: float = 90.0, shift_m: float = 0.0,
                     shift_b_m: float = 0.0, crossing: str = "per_length") -> float:
    """Normal force [N] between two straight bead chains crossing at ``angle_deg`` with
    Hooke bead pairs k_n (:func:`crossing_pair_stiffness_n_per_m` of ``crossing``: k'·l0
    by default), pressed until their axes are d − ``overlap_m`` apart.

    Sums k_n·(d − r) over bead pairs in contact (force along the axis-to-axis
    normal, r = pair distance). ``shift_m``/``shift_b_m``: offsets of the bead
    lattices from the crossing point along each chain. Used to show how a crossing
    scales with the spacing (per length, a point contact: ∝ l0 at small overlap; per
    crossing, averaged over the shifts: :func:`crossing_law_force_n` at any spacing).
    """
    import numpy as np

    k_pair = crossing_pair_stiffness_n_per_m(stiffness_pa, spacing_m, diameter_m, crossing)
    gap = diameter_m - overlap_m
    n = int(np.ceil(2 * diameter_m / spacing_m)) + 2
    s = spacing_m * np.arange(-n, n + 1)
    a = (s + shift_m)[:, None]
    b = (s + shift_b_m)[None, :]
    c = math.cos(math.radians(angle_deg))
    r = np.sqrt(gap * gap + a * a + b * b - 2 * a * b * c)
    pen = np.clip(diameter_m - r, 0.0, None)
    return float(k_pair * np.sum(pen * gap / r))


@dataclass(frozen=True)
class ContactModel:
    """Fibre–fibre contact.

    Args:
        friction: Coulomb coefficient μ (>= 0).
        normal: ``"hooke"`` (linear, default) or ``"hertz"``.
        normal_stiffness_pa: normal stiffness per unit length of fibre contact k'
            [N/m per m = Pa] (> 0; accepts "10 GPa"): two parallel fibres pressed δ
            together carry k'·δ per metre (Hertz: secant at the reference overlap).
            Each bead pair gets k_n = k'·l0. None (default): 0.4·E·A/d² of the stiffest
            fibre (the former default at s/d = 0.5). Used unless one of the two legacy
            keys below is given.
        stiffness_factor: legacy: k_n over the axial bond spring E·A/l0 of the
            stiffest fibre (> 0). Depends on the bead spacing (transverse stiffness
            per length ∝ 1/l0²); prefer ``normal_stiffness_pa``.
        stiffness_n_per_m: legacy: explicit k_n per bead pair [N/m] (> 0); also
            spacing-dependent.
        tangential_ratio: k_t/k_n (> 0; 2/7 is LAMMPS's usual choice); k_t scales
            with l0 like k_n, so it too is a stiffness per unit length.
        damping_ratio: normal damping as a fraction of critical, in (0, 1]. Undamped
            contacts chatter and lose their tangential history at each bounce, which
            lowers friction (capstan on an undamped wall: −11 %; 0.03 is enough).
        reference_overlap: overlap/d at which a Hertz contact has the stiffness
            k_n (secant), in (0, 0.5].
        overlap_warning: overlap/d above which a run warns, in (0, 1).
        overlap_limit: overlap/d at which a run is stopped as unstable
            (cause "overlap"), in (overlap_warning, 1].
        within_family_stiffness_pa: k' [Pa] between fibres of the same family (same
            atom type), > 0 (accepts "230 kPa"); None (default): one contact for all
            pairs. When given, ``normal_stiffness_pa`` (or its default) applies to pairs
            of different families only (module docstring, "Split contact"). Hooke only.
        within_family_law: a :class:`~fabmd.model.bundle_contact.BundleContact`: fibres of
            the same family follow the compaction law itself (nonlinear, hard core past the
            packing limit; module docstring, "Within-family law"); None (default): not.
            Excludes ``within_family_stiffness_pa`` (the law sets the linear part).
        within_family_laws: (family, BundleContact) of every family: that law on each
            family's own fibre (A, d; one table section per diameter); (): the one for all.
        crossing: k_n of pairs of different families: ``"per_length"`` (default, k'·l0)
            or ``"per_crossing"`` (2k'·l0²/d: a crossing of two fibres carries
            2π·k'·δ²·(1 − δ/d)/sin θ whatever the bead spacing, averaged over register;
            module docstring "Crossing per crossing"). ``"per_crossing"`` needs a split
            contact (``within_family_stiffness_pa`` or ``within_family_law``).
            ``"law"``: crossings compact by the within-family law's compaction law through
            their patch (:mod:`fabmd.model.crossing_law`), ``normal_stiffness_pa`` only
            in their hard core; needs ``within_family_law`` and one fibre kind.
        crossing_friction: Coulomb μ of pairs of different families (the warp–weft
            crossings), default ``friction``; ``friction`` then acts within a family
            (fibres of a yarn and neighbouring yarns). Needs a split contact.
    """

    friction: float = 0.3
    normal: str = "hooke"
    normal_stiffness_pa: float | None = None
    stiffness_factor: float | None = None
    stiffness_n_per_m: float | None = None
    tangential_ratio: float = 2.0 / 7.0
    damping_ratio: float = 0.3
    reference_overlap: float = 0.05
    overlap_warning: float = 0.1
    overlap_limit: float = 0.5
    within_family_stiffness_pa: float | None = None
    within_family_law: BundleContact | None = None
    within_family_laws: tuple = ()
    crossing: str = "per_length"
    crossing_friction: float | None = None

    def __post_init__(self):
        inputs.non_negative("contact.friction", self.friction)
        if self.crossing_friction is not None:
            inputs.non_negative("contact.crossing_friction", self.crossing_friction)
            if not self.split:
                raise InputError(
                    "contact.crossing_friction needs per-type-pair coefficients (give "
                    "within_family_stiffness_pa or within_family), got neither")
        inputs.one_of("contact.crossing", self.crossing, CROSSING_FORMS)
        if self.crossing == "per_crossing" and not self.split:
            raise InputError(
                "contact.crossing = 'per_crossing' needs per-type-pair coefficients (give "
                "within_family_stiffness_pa or within_family: same-family pairs stay per "
                "unit length), got neither")
        object.__setattr__(self, "within_family_laws", check_family_laws(
            self.within_family_law, self.within_family_laws, self.within_family_stiffness_pa,
            self.normal, self.per_length))
        if self.crossing == "law" and (
                self.within_family_law is None
                or any(b != self.within_family_law for _, b in self.within_family_laws)):
            raise InputError(
                "contact.crossing = 'law' needs [contact] within_family (the compaction law "
                "the crossings follow) and one fibre kind (every family the same virtual "
                "fibre), got " + ("no within-family law" if self.within_family_law is None
                                  else "families with their own fibres"))
        if self.within_family_stiffness_pa is not None:
            object.__setattr__(self, "within_family_stiffness_pa", inputs.positive(
                "contact.within_family_stiffness_pa",
                quantity(self.within_family_stiffness_pa, "pressure",
                         "contact.within_family_stiffness_pa")))
            if self.normal != "hooke" or not self.per_length:
                raise InputError(
                    "contact.within_family_stiffness_pa: needs normal = 'hooke' and the "
                    "stiffness per unit length (no stiffness_factor / stiffness_n_per_m), "
                    f"got normal = {self.normal!r}")
        inputs.one_of("contact.normal", self.normal, NORMAL_MODELS)
        if self.normal_stiffness_pa is not None:
            object.__setattr__(self, "normal_stiffness_pa", inputs.positive(
                "contact.normal_stiffness_pa",
                quantity(self.normal_stiffness_pa, "pressure", "contact.normal_stiffness_pa")))
        if self.stiffness_factor is not None:
            inputs.positive("contact.stiffness_factor", self.stiffness_factor)
        if self.stiffness_n_per_m is not None:
            inputs.positive("contact.stiffness_n_per_m", self.stiffness_n_per_m)
        inputs.positive("contact.tangential_ratio", self.tangential_ratio)
        inputs.in_range("contact.damping_ratio", self.damping_ratio, 0.0, 1.0, low_open=True)
        inputs.in_range("contact.reference_overlap", self.reference_overlap, 0.0, 0.5,
                        low_open=True)
        inputs.in_range("contact.overlap_warning", self.overlap_warning, 0.0, 1.0,
                        low_open=True, high_open=True)
        inputs.in_range("contact.overlap_limit", self.overlap_limit, self.overlap_warning,
                        1.0, low_open=True)

    def normal_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """Linear(ised) normal stiffness k_n [N/m] (Hertz: secant at the reference overlap);
        of a split contact, that of pairs of different families (``crossing``)."""
        if self.crossing == "law":  # the crossing law's linear part (its table adds the rest)
            return self.crossing_law(beads).linear_pair_stiffness_n_per_m(
                widest_spacing(beads))
        if self.crossing == "per_crossing":  # split, Hooke, per length (checked when built)
            return crossing_pair_stiffness_n_per_m(
                self.crossing_stiffness_pa(beads), widest_spacing(beads),
                min(b.diameter_m for b in beads), self.crossing)
        return _normal_stiffness("contact", self.normal_stiffness_pa, self.stiffness_factor,
                                 self.stiffness_n_per_m, beads)

    @property
    def per_length(self) -> bool:
        """True when k_n follows the bead spacing (k' given per unit length)."""
        return self.stiffness_factor is None and self.stiffness_n_per_m is None

    def stability_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """Highest tangent normal stiffness expected [N/m], for the stable time step.

        Hooke: k_n. Hertz (F ∝ δ^1.5): the tangent 1.5·k_n·sqrt(δ/δ_ref) at the
        warning overlap.
        """
        kn = self.normal_stiffness_n_per_m(beads)
        if self.split:
            kn = max(kn, self.within_family_stiffness_n_per_m(beads))
        for sec in self.law_sections(beads):  # its tables' steepest part
            kn = max(kn, sec.max_pair_stiffness_n_per_m(self.crossing_stiffness_pa(beads)))
        if self.crossing == "law":
            kn = max(kn, self.crossing_law(beads).max_pair_stiffness_n_per_m(
                widest_spacing(beads)))
        if self.normal == "hertz":
            kn *= 1.5 * math.sqrt(max(self.overlap_warning, self.reference_overlap)
                                  / self.reference_overlap)
        return kn

    def overlap_ratio(self, force_n: float, beads: list[BeadParameters]) -> float:
        """Overlap/d a static contact force ``force_n`` [N] causes between the smallest beads.

        Hooke: F/k_n/d; Hertz: (F/(K·sqrt(R_eff)))^(2/3)/d with R_eff = d/4. Use it to
        check a scene's loads against ``overlap_warning`` before running.
        """
        force_n = inputs.non_negative("force_n", force_n)
        d = min(b.diameter_m for b in beads)
        if self.normal == "hooke":
            return force_n / self.normal_stiffness_n_per_m(beads) / d
        k = self.pair_coefficients(beads)["kn"] * math.sqrt(d / 4.0)
        return (force_n / k) ** (2.0 / 3.0) / d

    @property
    def split(self) -> bool:
        """True when same-family pairs have their own stiffness (module docstring)."""
        return self.within_family_stiffness_pa is not None or self.within_family_law is not None

    def within_family_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """k_n per bead pair [N/m] between fibres of one family: k'_within · l0 (widest
        spacing; with a within-family law its linear part); the crossing stiffness when
        the contact is not split."""
        if not self.split:
            return self.normal_stiffness_n_per_m(beads)
        if self.within_family_law is not None:  # several diameters: the softest
            k_cross = self.crossing_stiffness_pa(beads)
            return min(s.linear_pair_stiffness_n_per_m(k_cross) for s in self.law_sections(beads))
        return _normal_stiffness("contact", self.within_family_stiffness_pa, None, None, beads)

    def law_sections(self, beads: list[BeadParameters]) -> list[LawSection]:
        """The within-family law's table sections (none without the law)."""
        return law_sections(self.within_family_law, self.within_family_laws, beads,
                            WITHIN_FAMILY_KEYWORD) if self.within_family_law else []

    def family_law(self, family: str) -> BundleContact | None:
        """The within-family law's bundle of ``family`` (its own fibre where given)."""
        return dict(self.within_family_laws).get(family, self.within_family_law)

    def law_realisation(self, families) -> dict | None:
        """Per family, where the within-family law's virtual fibres touch and the pressure
        the law loses below that state (:meth:`~fabmd.model.bundle_contact.BundleContact.
        realisation`); None without the law."""
        if self.within_family_law is None:
            return None
        return {f: self.family_law(f).realisation() for f in families}

    def crossing_law(self, beads: list[BeadParameters]) -> CrossingLaw:
        """The crossings' law (``crossing = "law"``; the within-family law's bundle)."""
        if self.crossing != "law":
            raise InputError(f"contact.crossing is {self.crossing!r}: no crossing law")
        return CrossingLaw(self.within_family_law, self.crossing_stiffness_pa(beads))

    def crossing_stiffness_pa(self, beads: list[BeadParameters]) -> float:
        """k' of a crossing [Pa] (per unit length; needs the per-length form)."""
        return (self.normal_stiffness_pa if self.normal_stiffness_pa is not None
                else default_stiffness_pa(beads))

    def table_files(self, beads: list[BeadParameters]) -> dict[str, str]:
        """Files the LAMMPS input reads, by name: the within-family law's table
        (:data:`WITHIN_FAMILY_TABLE`, one section per :meth:`law_sections`), else none.
        Each section's excess uses the same bead spacing l0 as its linear part."""
        k_cross = self.crossing_stiffness_pa(beads) if self.within_family_law else None
        if not k_cross:
            return {}
        sections = [sec.table_text(k_cross) for sec in self.law_sections(beads)]
        if self.crossing == "law":
            sections.append(self.crossing_law(beads).table_text(
                widest_spacing(beads), CROSSING_KEYWORD))
        return {WITHIN_FAMILY_TABLE: "\n".join(sections)}

    def softest_normal_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """The smallest k_n of any type pair [N/m] (largest overlap per unit force)."""
        return min(self.normal_stiffness_n_per_m(beads),
                   self.within_family_stiffness_n_per_m(beads))

    def type_pair_coefficients(self, beads: list[BeadParameters], n_types: int,
                               families: tuple[str, ...] = ()
                               ) -> list[tuple[int, int, dict[str, float]]]:
        """``(i, j, coefficients)`` for every atom type pair i <= j of a split contact:
        i == j with the within-family stiffness (the law's linear part of ``families[i -
        1]``), else the crossing one; damping a fraction of critical for each pair's k_n."""
        cross = self.pair_coefficients(beads)
        within = self._coefficients(self.within_family_stiffness_n_per_m(beads), beads)
        sections = {s.bundle: s for s in self.law_sections(beads)}
        own = {i: self._coefficients(sections[law].linear_pair_stiffness_n_per_m(
                   self.crossing_stiffness_pa(beads)), beads)
               for i, law in enumerate(map(self.family_law, families), start=1)
               if len(sections) > 1 and law in sections}
        if self.crossing_friction is not None:
            cross = {**cross, "friction": self.crossing_friction}
        return [(i, j, own.get(i, within) if i == j else cross)
                for i in range(1, n_types + 1) for j in range(i, n_types + 1)]

    def pair_style(self) -> str:
        """The cheapest LAMMPS granular style that carries this physics (measured)."""
        if self.within_family_law is not None:
            return "hybrid/overlay"  # granular + a table on same-family pairs
        if self.split:
            return "granular"  # per-type-pair coefficients
        if self.normal == "hooke" and self.friction == 0.0:
            return "gran/hooke"  # no tangential force: no history to store
        return f"gran/{self.normal}/history"

    def pair_coefficients(self, beads: list[BeadParameters]) -> dict[str, float]:
        """``Kn Kt gamman gammat xmu`` for :meth:`pair_style`.

        Damping is set from the lightest bead (highest critical damping rate).
        LAMMPS multiplies Kn, Kt and both dampings of a Hertz contact by
        sqrt(δ·R_eff); they are divided here by that factor at the reference
        overlap of the smallest pair (R_eff = d/4), so that k_n is the secant
        stiffness there.
        """
        return self._coefficients(self.normal_stiffness_n_per_m(beads), beads)

    def _coefficients(self, kn: float, beads: list[BeadParameters]) -> dict[str, float]:
        m_eff = 0.5 * min(b.mass_kg for b in beads)
        gamma_n = self.damping_ratio * 2.0 * math.sqrt(kn / m_eff)
        if self.normal == "hertz":
            d = min(b.diameter_m for b in beads)
            poly = math.sqrt(self.reference_overlap * d * d / 4.0)  # sqrt(delta * R_eff)
            kn, gamma_n = kn / poly, gamma_n / poly
        return {"kn": kn, "kt": self.tangential_ratio * kn, "gamman": gamma_n,
                "gammat": 0.5 * gamma_n, "friction": self.friction}


@dataclass(frozen=True)
class ToolContact:
    """Contact between fibres and a rigid tool (wall, cylinder, punch, die, clamp).

    Linear (Hooke) normal spring, tangential spring with history capped by
    Coulomb friction μ·F_n: ``fix wall/gran[/region] granular hooke ... tangential
    linear_history ... damping mass_velocity``, which is the classic ``hooke/history``
    model written in the ``granular`` syntax. The classic keyword itself is not used:
    in LAMMPS 22Jul2025 its wall version loses the tangential spring (a bead dragged
    slowly on a wall with μ = 0.3 feels Ft/Fn = 0.012; ``granular``: 0.300), and it
    returns NaN forces when undamped.

    Args:
        friction: Coulomb coefficient μ between tool and fibres (>= 0).
        normal_stiffness_pa: normal stiffness per unit length of fibre on the tool k'
            [Pa] (> 0): a fibre lying on a flat tool carries k'·δ per metre; each bead
            gets k_n = k'·l0 (see :class:`ContactModel`). None (default): 0.4·E·A/d².
        stiffness_factor: legacy: k_n over E·A/l0 of the stiffest fibre (> 0);
            spacing-dependent.
        stiffness_n_per_m: legacy: explicit normal stiffness k_n [N/m] (> 0).
        tangential_ratio: k_t/k_n (> 0).
        damping_ratio: normal damping as a fraction of critical, in (0, 1] (see
            :class:`ContactModel`: undamped contacts chatter and lose friction).
    """

    friction: float = 0.2
    normal_stiffness_pa: float | None = None
    stiffness_factor: float | None = None
    stiffness_n_per_m: float | None = None
    tangential_ratio: float = 2.0 / 7.0
    damping_ratio: float = 0.3

    def __post_init__(self):
        inputs.non_negative("tool_contact.friction", self.friction)
        if self.normal_stiffness_pa is not None:
            object.__setattr__(self, "normal_stiffness_pa", inputs.positive(
                "tool_contact.normal_stiffness_pa",
                quantity(self.normal_stiffness_pa, "pressure",
                         "tool_contact.normal_stiffness_pa")))
        if self.stiffness_factor is not None:
            inputs.positive("tool_contact.stiffness_factor", self.stiffness_factor)
        if self.stiffness_n_per_m is not None:
            inputs.positive("tool_contact.stiffness_n_per_m", self.stiffness_n_per_m)
        inputs.positive("tool_contact.tangential_ratio", self.tangential_ratio)
        inputs.in_range("tool_contact.damping_ratio", self.damping_ratio, 0.0, 1.0,
                        low_open=True)

    def normal_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """Normal stiffness k_n [N/m]."""
        return _normal_stiffness("tool_contact", self.normal_stiffness_pa,
                                 self.stiffness_factor, self.stiffness_n_per_m, beads)

    def stability_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """Highest normal stiffness expected [N/m], for the stable time step: the linear
        wall's k_n (see :mod:`fabmd.model.timestep`)."""
        return self.normal_stiffness_n_per_m(beads)

    def wall_coefficients(self, beads: list[BeadParameters]) -> dict[str, float]:
        """k_n [N/m], k_t [N/m], damping rates γ_n, γ_t [1/s] (force = m·γ·v) and μ.

        The wall's mass is infinite, so m_eff is the bead mass (the lightest bead's).
        """
        kn = self.normal_stiffness_n_per_m(beads)
        m = min(b.mass_kg for b in beads)
        gamma_n = self.damping_ratio * 2.0 * math.sqrt(kn / m)
        return {"kn": kn, "kt": self.tangential_ratio * kn, "gamman": gamma_n,
                "gammat": 0.5 * gamma_n, "friction": self.friction}
