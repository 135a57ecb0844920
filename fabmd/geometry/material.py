"""Fibre materials and virtual fibres (SI units).

A *virtual fibre* stands for a bundle of real filaments. Two of its sizes are
kept apart on purpose:

* ``area_m2`` — the filament cross-section it carries: sets axial stiffness
  E·A and mass per length ρ·A;
* ``diameter_m`` — the contact diameter of its beads: sets how the virtual
  fibres pack and touch inside the yarn cross-section.

For a yarn of linear density *tex* filled with *N* virtual fibres the filament
area is A = tex·1e-6 / ρ / N (tex = g/km).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import inputs
from ..units import quantity


@dataclass(frozen=True)
class FibreMaterial:
    """Material of the real filaments.

    Args:
        modulus_pa: axial Young's modulus E [Pa] (accepts "73 GPa").
        density_kg_m3: filament density ρ [kg/m³] (accepts "2.54 g/cm3").
        name: label used in outputs.
    """

    modulus_pa: float
    density_kg_m3: float
    name: str = "fibre"

    def __post_init__(self):
        object.__setattr__(self, "modulus_pa", inputs.positive(
            "material.modulus_pa", quantity(self.modulus_pa, "pressure", "material.modulus_pa")))
        object.__setattr__(self, "density_kg_m3", inputs.positive(
            "material.density_kg_m3",
            quantity(self.density_kg_m3, "density", "material.density_kg_m3")))

    @property
    def wave_speed_m_s(self) -> float:
        """Axial wave speed sqrt(E/ρ) [m/s]."""
        return math.sqrt(self.modulus_pa / self.density_kg_m3)


GLASS = FibreMaterial(modulus_pa=73e9, density_kg_m3=2540.0, name="E-glass")
CARBON = FibreMaterial(modulus_pa=230e9, density_kg_m3=1780.0, name="carbon T300")


@dataclass(frozen=True)
class VirtualFibre:
    """One virtual fibre: a chain of beads.

    Args:
        material: filament material.
        area_m2: filament cross-section carried by this virtual fibre [m²].
        diameter_m: contact (bead) diameter [m].
        bending_stiffness_nm2: its share of the yarn's bending rigidity E·I [N·m²]
            (0: a string of beads with no bending term).
    """

    material: FibreMaterial
    area_m2: float
    diameter_m: float
    bending_stiffness_nm2: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "area_m2", inputs.positive(
            "fibre.area_m2", quantity(self.area_m2, "area", "fibre.area_m2")))
        object.__setattr__(self, "diameter_m", inputs.positive(
            "fibre.diameter_m", quantity(self.diameter_m, "length", "fibre.diameter_m")))
        object.__setattr__(self, "bending_stiffness_nm2", inputs.non_negative(
            "fibre.bending_stiffness_nm2", self.bending_stiffness_nm2))

    @classmethod
    def solid(cls, material: FibreMaterial, diameter_m: float) -> VirtualFibre:
        """A virtual fibre that is one solid filament of the given diameter."""
        d = inputs.positive("fibre.diameter_m", quantity(diameter_m, "length", "fibre.diameter_m"))
        return cls(material, math.pi * d * d / 4.0, d)

    @classmethod
    def from_yarn(cls, material: FibreMaterial, linear_density_tex: float, n_fibres: int,
                  diameter_m: float, yarn_bending_stiffness_nm2: float = 0.0) -> VirtualFibre:
        """One of ``n_fibres`` virtual fibres sharing a yarn's filament area (and its
        bending rigidity: each fibre bends about its own axis, so the yarn's E·I is the
        sum of its fibres' whatever their number).

        Args:
            linear_density_tex: yarn linear density [tex = g/km] (accepts "1200 tex").
            n_fibres: virtual fibres per yarn (>= 1).
            diameter_m: contact diameter of each virtual fibre [m].
            yarn_bending_stiffness_nm2: the yarn's bending rigidity E·I [N·m²] (0: none).
        """
        tex = linear_density_tex
        if isinstance(tex, str):
            tex = quantity(tex, "linear_density", "yarn.linear_density_tex") / 1e-6
        tex = inputs.positive("yarn.linear_density_tex", tex)
        n = inputs.positive_int("yarn.n_fibres", n_fibres)
        area = tex * 1e-6 / material.density_kg_m3 / n
        bending = inputs.non_negative("yarn bending stiffness", yarn_bending_stiffness_nm2)
        return cls(material, area, diameter_m, bending / n)

    @property
    def axial_stiffness_n(self) -> float:
        """E·A [N]."""
        return self.material.modulus_pa * self.area_m2

    @property
    def mass_per_length_kg_m(self) -> float:
        """ρ·A [kg/m]."""
        return self.material.density_kg_m3 * self.area_m2

    @property
    def solid_bending_stiffness_nm2(self) -> float:
        """E·I of a solid rod of area A [N·m²] (an upper bound for a filament bundle)."""
        d = math.sqrt(4.0 * self.area_m2 / math.pi)
        return self.material.modulus_pa * math.pi * d**4 / 64.0
