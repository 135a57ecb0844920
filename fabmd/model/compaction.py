"""Lateral compaction of a yarn: a fibre-bundle law and the bead contact that realises it.

The law (van Wyk type, in the form Toll gives for fibre assemblies):

    p = k · E_f · (Vf^n − Vf0^n)        for Vf > Vf0, else 0,

p the transverse pressure on the bundle [Pa], Vf its fibre volume fraction, E_f
the filaments' axial modulus, k a dimensionless coefficient, Vf0 the fraction at
which the bundle starts to carry load, n = 3 for fibres in contact at random
crossings (van Wyk). The defaults below are *representative* anchors, not fits to
a named data set: dry glass and carbon reinforcements typically reach Vf ≈ 0.55
(glass) and ≈ 0.60 (carbon) at 100 kPa from loose states near 0.30 / 0.35 (the
range surveyed by Robitaille & Gauvin, Polym. Compos. 19 (1998) 198, and the van
Wyk / Toll form: Toll, Polym. Eng. Sci. 38 (1998) 1337). The searches for
published numbers done while writing this found none to quote; calibrate the law
on the fabric's own compaction curve (``fabmd test compaction``).

Realisation by the bead contact. A yarn is ``N`` virtual fibres of filament area
A each and contact diameter d. Packed hexagonally with axis spacing g, its fibre
volume fraction is Vf = A / ((√3/2)·g²), and with a line contact q = k'·(d − g)
per unit length between neighbours the virial gives an isotropic transverse
pressure

    p = √3 · q / g = √3 · k' · (d − g) / g.

:func:`contact_for_yarn` picks k' (``ContactModel.normal_stiffness_pa``, Hooke) so
that this bundle reaches the law's Vf at a reference pressure (secant match) and
reports the overlap it takes to get there — the price in pass-through safety of
making virtual fibres as soft across as the yarn. Away from the reference pressure
the bead bundle follows its own curve ``bundle_pressure_pa``; the two are tabulated
side by side by :func:`compare`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError
from ..units import quantity

HEX_CELL = math.sqrt(3.0) / 2.0  # area per fibre of a hexagonal packing, over g²
#: the densest packing of parallel circular fibres (hexagonal), π/(2√3)
PACKING_LIMIT = math.pi / (2.0 * math.sqrt(3.0))


@dataclass(frozen=True)
class CompactionLaw:
    """p = k·E_f·(Vf^n − Vf0^n) (module docstring).

    Args:
        coefficient: k (> 0, dimensionless).
        modulus_pa: E_f, the filaments' axial modulus [Pa] (accepts "73 GPa").
        vf0: fibre volume fraction at which the bundle starts to carry load, (0, 0.9).
        exponent: n (> 0; 3 for van Wyk).
        name: label.
    """

    coefficient: float
    modulus_pa: float
    vf0: float
    exponent: float = 3.0
    name: str = "bundle"

    def __post_init__(self):
        inputs.positive("compaction_law.coefficient", self.coefficient)
        object.__setattr__(self, "modulus_pa", inputs.positive(
            "compaction_law.modulus_pa",
            quantity(self.modulus_pa, "pressure", "compaction_law.modulus_pa")))
        inputs.in_range("compaction_law.vf0", self.vf0, 0.0, 0.9, low_open=True,
                        high_open=True)
        inputs.positive("compaction_law.exponent", self.exponent)

    @classmethod
    def through(cls, modulus_pa: float, vf0: float, vf: float, pressure_pa: float,
                exponent: float = 3.0, name: str = "bundle") -> CompactionLaw:
        """The law that starts at ``vf0`` and passes through (``vf``, ``pressure_pa``)."""
        if not vf0 < vf < 1.0:
            raise InputError(f"compaction_law: the anchor vf must be in ({vf0:g}, 1), "
                             f"got {vf!r}")
        k = pressure_pa / (modulus_pa * (vf**exponent - vf0**exponent))
        return cls(k, modulus_pa, vf0, exponent, name)

    def pressure_pa(self, vf):
        """Transverse pressure at fibre volume fraction ``vf`` [Pa] (float, or array: array);
        0 at and below Vf0."""
        n = self.exponent
        p = np.maximum(0.0, self.coefficient * self.modulus_pa
                       * (np.maximum(vf, self.vf0) ** n - self.vf0**n))
        return float(p) if np.ndim(p) == 0 else p

    def max_pressure_pa(self) -> float:
        """The pressure at which the law reaches :data:`PACKING_LIMIT` [Pa]: the van Wyk
        form itself has no bound, a bundle of circular fibres cannot pack denser."""
        return self.pressure_pa(PACKING_LIMIT)

    def volume_fraction(self, pressure_pa: float) -> float:
        """Fibre volume fraction at ``pressure_pa`` [Pa] (inverse of :meth:`pressure_pa`).

        Raises:
            InputError: ``pressure_pa`` beyond :meth:`max_pressure_pa` (the law would
                pack the fibres denser than hexagonal packing).
        """
        pressure_pa = inputs.non_negative("pressure_pa", pressure_pa)
        if pressure_pa > self.max_pressure_pa():
            raise InputError(
                f"{self.name}: {pressure_pa:.4g} Pa is beyond the law's packing limit "
                f"(Vf {PACKING_LIMIT:.3f}, reached at {self.max_pressure_pa():.4g} Pa)")
        n = self.exponent
        return (self.vf0**n + pressure_pa / (self.coefficient * self.modulus_pa)) ** (1 / n)


#: E-glass rovings: Vf 0.30 → 0.55 at 100 kPa (representative, NOT from a checked source:
#: docs/validation_sources.md finds glass rovings nearer Vf 0.49 at 100 kPa)
GLASS_BUNDLE = CompactionLaw.through(73e9, 0.30, 0.55, 1e5, name="E-glass bundle")
#: carbon tows (T300-like): Vf 0.35 → 0.60 at 100 kPa (representative, NOT from a checked
#: source: docs/validation_sources.md)
CARBON_BUNDLE = CompactionLaw.through(230e9, 0.35, 0.60, 1e5, name="carbon bundle")


def touching_volume_fraction(area_m2: float, diameter_m: float) -> float:
    """Vf of a hexagonal bundle of virtual fibres that just touch (g = d)."""
    return area_m2 / (HEX_CELL * diameter_m**2)


def bundle_volume_fraction(area_m2: float, spacing_m: float) -> float:
    """Vf of a hexagonal bundle with axis spacing g = ``spacing_m``."""
    return area_m2 / (HEX_CELL * spacing_m**2)


def bundle_pressure_pa(stiffness_pa: float, diameter_m: float, spacing_m: float) -> float:
    """Isotropic transverse pressure of a hexagonal bundle of virtual fibres with axis
    spacing g and line contact k'·(d − g) per unit length: √3·k'·(d − g)/g [Pa]."""
    return math.sqrt(3.0) * stiffness_pa * max(0.0, diameter_m - spacing_m) / spacing_m


def contact_for_yarn(law: CompactionLaw, area_m2: float, diameter_m: float,
                     reference_pressure_pa: float = 1e5) -> dict:
    """The line-contact stiffness k' [Pa] with which a hexagonal bundle of these virtual
    fibres reaches the law's Vf at ``reference_pressure_pa``.

    Args:
        area_m2: filament area carried by one virtual fibre A [m²].
        diameter_m: its contact diameter d [m].

    Returns:
        ``normal_stiffness_pa``, ``touching_vf`` (virtual fibres just touching),
        ``reference_vf`` (the law's), ``reference_overlap_ratio`` (δ/d it takes).

    Raises:
        InputError: the virtual fibres already touch at a Vf above the law's at the
            reference pressure (make them thinner or use more of them).
    """
    p_ref = inputs.positive("reference_pressure_pa", quantity(
        reference_pressure_pa, "pressure", "reference_pressure_pa"))
    vf_touch = touching_volume_fraction(area_m2, diameter_m)
    vf_ref = law.volume_fraction(p_ref)
    if vf_ref <= vf_touch:
        raise InputError(
            f"compaction: virtual fibres of d = {diameter_m:.3g} m touch at Vf = "
            f"{vf_touch:.3f}, above the {law.name} law's Vf = {vf_ref:.3f} at "
            f"{p_ref:g} Pa: the bundle cannot be that soft; use a smaller contact diameter")
    g = diameter_m * math.sqrt(vf_touch / vf_ref)
    k = p_ref * g / (math.sqrt(3.0) * (diameter_m - g))
    return {"normal_stiffness_pa": k, "touching_vf": vf_touch, "reference_vf": vf_ref,
            "reference_pressure_pa": p_ref, "reference_overlap_ratio": 1 - g / diameter_m}


def compare(law: CompactionLaw, stiffness_pa: float, area_m2: float, diameter_m: float,
            pressures_pa=(1e4, 1e5, 3e5)) -> list[dict]:
    """Vf the law gives and Vf the bead bundle reaches at each pressure (and δ/d)."""
    rows = []
    for p in pressures_pa:
        vf_law = law.volume_fraction(p)
        # bead bundle: √3 k'(d − g)/g = p  →  g = d / (1 + p/(√3 k'))
        g = diameter_m / (1 + p / (math.sqrt(3.0) * stiffness_pa))
        rows.append({"pressure_pa": p, "vf_law": vf_law,
                     "vf_beads": bundle_volume_fraction(area_m2, g),
                     "overlap_ratio": 1 - g / diameter_m})
    return rows
