"""One yarn family of a fabric: linear density, filaments, section, spacing (SI)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError
from ..units import TEX, quantity
from .material import FibreMaterial
from .section import PACKINGS, Section, section_height

#: largest yarn fibre volume fraction (filament area / section area) a yarn may have
PACKING_LIMIT = 0.8
#: filament count × filament area may differ this much from tex/ρ before a datasheet
#: is refused as inconsistent
FILAMENT_TOLERANCE = 0.1
#: a datasheet areal density may fall this much short of the straight yarns' mass
AREAL_DENSITY_TOLERANCE = 0.03
#: and exceed it by at most this mean crimp
MAX_DATASHEET_CRIMP = 0.3
#: ``bending_stiffness_nm2`` of a yarn whose filaments bend each on its own
FILAMENTS = "filaments"


@dataclass(frozen=True)
class YarnSpec:
    """One yarn family (or, from a datasheet, its tex, fibre and packing).

    Args:
        linear_density_tex: linear density [tex = g/km] (accepts "1200 tex", "1.2 ktex").
        material: filament material.
        width_m: section width in the fabric plane [m] (accepts "2 mm"); default:
            the yarn spacing (a dense fabric whose yarns fill their spacing).
        n_fibres: virtual fibres per yarn (>= 1; 1, 7, 19, 37, 61 are full hexagons).
        height_m: section height [m]; default: the height at which the section holds
            the filament area tex/ρ at ``fibre_volume_fraction``, or = width (circle)
            when that is not given.
        spacing_m: distance between neighbouring yarns of this family [m].
        count_per_m: or yarns per length [1/m] (accepts "4 ends/cm", "3 picks/cm").
        name: label of the family's yarn type in outputs.
        shape: section shape, ``"ellipse"``, ``"lenticular"`` or ``"racetrack"``.
        fibre_volume_fraction: the packing the section is sized for (filament area
            over section area, in (0, 0.8]); used when ``height_m`` is left out.
        filament_diameter_m: diameter of one filament [m] (datasheet; "7 um").
        filament_count: filaments per yarn (datasheet; "3K" = 3000). With the
            diameter, count·π·d²/4 must agree with tex/ρ within 10 %.
        fibre_packing: how the virtual fibres fill the section, ``"inscribed"`` (default: all
            inside, as large as fits) or ``"area"`` (their hexagonal cells tile the
            section's area; :mod:`fabmd.geometry.section`).
        bending_stiffness_nm2: the yarn's bending rigidity E·I [N·m²] (accepts
            "0.3 N·mm2", "0.3 cN·cm2"), shared equally by its virtual fibres; or
            ``"filaments"``: its filaments bending each on its own, E·(tex/ρ)·d_f²/16
            (= count·E·π·d_f⁴/64; needs ``filament_diameter_m``), the lower bound of a dry
            yarn's rigidity (filaments free to slide). Default: none (strings).

    Every yarn's filament area tex/ρ must fit its section at a yarn fibre volume
    fraction of at most :data:`PACKING_LIMIT`.
    """

    linear_density_tex: float
    material: FibreMaterial
    width_m: float | None = None
    n_fibres: int = 7
    height_m: float | None = None
    spacing_m: float | None = None
    count_per_m: float | None = None
    name: str = ""
    shape: str = "ellipse"
    fibre_volume_fraction: float | None = None
    filament_diameter_m: float | None = None
    filament_count: int | None = None
    fibre_packing: str = "inscribed"
    bending_stiffness_nm2: float | str | None = None

    def __post_init__(self):
        tex = self.linear_density_tex
        if isinstance(tex, str):
            tex = quantity(tex, "linear_density", "yarn.linear_density_tex") / TEX
        object.__setattr__(self, "linear_density_tex",
                           inputs.positive("yarn.linear_density_tex", tex))
        if not isinstance(self.material, FibreMaterial):
            raise InputError(f"yarn.material must be a FibreMaterial, got {self.material!r}")
        object.__setattr__(self, "n_fibres", inputs.positive_int("yarn.n_fibres", self.n_fibres))
        if self.fibre_packing not in PACKINGS:
            raise InputError(f"yarn.fibre_packing must be one of {', '.join(PACKINGS)}, got "
                             f"{self.fibre_packing!r}")
        if self.spacing_m is not None and self.count_per_m is not None:
            if isinstance(self.spacing_m, str) or isinstance(self.count_per_m, str) \
                    or not math.isclose(self.spacing_m * self.count_per_m, 1.0, rel_tol=1e-9):
                raise InputError("give yarn.spacing_m or yarn.count_per_m, not both")
            object.__setattr__(self, "spacing_m", None)  # a copy: count_per_m sets it again
        if self.spacing_m is not None:
            object.__setattr__(self, "spacing_m", inputs.positive(
                "yarn.spacing_m", quantity(self.spacing_m, "length", "yarn.spacing_m")))
        if self.count_per_m is not None:
            count = inputs.positive("yarn.count_per_m", quantity(
                self.count_per_m, "count_per_length", "yarn.count_per_m"))
            object.__setattr__(self, "count_per_m", count)
            object.__setattr__(self, "spacing_m", 1.0 / count)
        self._check_filaments()
        self._check_bending()
        width = self.width_m
        if width is None:
            if self.spacing_m is None:
                raise InputError("yarn.width_m is needed when the yarn has no spacing_m or "
                                 "count_per_m (the default width is the spacing)")
            width = self.spacing_m
        width = inputs.positive("yarn.width_m", quantity(width, "length", "yarn.width_m"))
        height = self.height_m
        if self.fibre_volume_fraction is not None:
            vf = inputs.in_range("yarn.fibre_volume_fraction", self.fibre_volume_fraction,
                                 0.0, PACKING_LIMIT, low_open=True)
            object.__setattr__(self, "fibre_volume_fraction", float(vf))
            if height is None:
                height = section_height(self.filament_area_m2 / vf, width, self.shape)
        section = Section(width, height, self.shape)
        object.__setattr__(self, "width_m", section.width_m)
        object.__setattr__(self, "height_m", section.height_m)
        vf = self.yarn_fibre_volume_fraction
        if vf > PACKING_LIMIT * (1 + 1e-9):
            raise InputError(
                f"yarn{' ' + self.name if self.name else ''}: filament area "
                f"{1e6 * self.filament_area_m2:.4g} mm² ({self.linear_density_tex:g} tex / "
                f"{self.material.density_kg_m3:g} kg/m³) in its {1e3 * self.width_m:.4g} x "
                f"{1e3 * self.height_m:.4g} mm {self.shape} section "
                f"({1e6 * section.area_m2:.4g} mm²) is a yarn fibre volume fraction of "
                f"{vf:.3g}, above the packing limit {PACKING_LIMIT:g}: enlarge the section "
                f"(height_m, width_m) or leave height_m out and give fibre_volume_fraction")

    def _check_filaments(self) -> None:
        d, n = self.filament_diameter_m, self.filament_count
        if d is not None:
            d = inputs.positive("yarn.filament_diameter_m",
                                quantity(d, "length", "yarn.filament_diameter_m"))
            object.__setattr__(self, "filament_diameter_m", d)
        if n is not None:
            if isinstance(n, str) and n.strip().upper().endswith("K"):
                try:
                    n = int(round(float(n.strip()[:-1]) * 1000))
                except ValueError:
                    raise InputError(f"yarn.filament_count must be a number or like "
                                     f"'3K', got {self.filament_count!r}") from None
            object.__setattr__(self, "filament_count", inputs.positive_int(
                "yarn.filament_count", n))
            n = self.filament_count
        if d is None or n is None:
            return
        area = n * math.pi * d * d / 4.0
        ratio = area / self.filament_area_m2
        if abs(ratio - 1.0) > FILAMENT_TOLERANCE:
            raise InputError(
                f"yarn datasheet is inconsistent: {n} filaments x pi/4 x "
                f"({1e6 * d:.3g} um)² = {1e6 * area:.4g} mm² but {self.linear_density_tex:g} "
                f"tex / {self.material.density_kg_m3:g} kg/m³ = "
                f"{1e6 * self.filament_area_m2:.4g} mm² ({100 * (ratio - 1):+.0f} %, allowed "
                f"±{100 * FILAMENT_TOLERANCE:.0f} %): check tex, fibre density, filament "
                f"diameter or count")

    def _check_bending(self) -> None:
        value = self.bending_stiffness_nm2
        if value is None:
            return
        if isinstance(value, str) and value.strip() == FILAMENTS:
            if self.filament_diameter_m is None:
                raise InputError(
                    f"yarn{' ' + self.name if self.name else ''}: bending_stiffness_nm2 = "
                    f"\"{FILAMENTS}\" needs filament_diameter_m (the datasheet's filament "
                    f"diameter, e.g. \"17 um\"), or give the rigidity in N·m²")
            object.__setattr__(self, "bending_stiffness_nm2", FILAMENTS)
            return
        object.__setattr__(self, "bending_stiffness_nm2", inputs.non_negative(
            "yarn.bending_stiffness_nm2",
            quantity(value, "bending_stiffness", "yarn.bending_stiffness_nm2")))

    @property
    def yarn_bending_stiffness_nm2(self) -> float:
        """The yarn's bending rigidity E·I [N·m²] (0: none; see ``bending_stiffness_nm2``)."""
        value = self.bending_stiffness_nm2
        if value is None:
            return 0.0
        if value == FILAMENTS:
            d = self.filament_diameter_m
            return self.material.modulus_pa * self.filament_area_m2 * d * d / 16.0
        return float(value)

    @property
    def filament_area_m2(self) -> float:
        """Filament cross-section of the yarn, tex·1e-6/ρ [m²]."""
        return self.linear_density_tex * TEX / self.material.density_kg_m3

    @property
    def yarn_fibre_volume_fraction(self) -> float:
        """Filament area over section area (the yarn's packing)."""
        return self.filament_area_m2 / self.section.area_m2

    @property
    def section(self) -> Section:
        return Section(self.width_m, self.height_m, self.shape)

    @property
    def linear_density_kg_m(self) -> float:
        return self.linear_density_tex * TEX

    def packing(self) -> tuple[np.ndarray, float]:
        """Fibre offsets (n, 2) [m] and contact diameter [m] (see :mod:`.section`)."""
        return self.section.packing(self.n_fibres, self.fibre_packing)

    @property
    def occupied_height_m(self) -> float:
        """Height the virtual fibres fill through the thickness [m]: the section's height,
        or more where the packing's fibres poke out of it (``"area"`` tiles the section's
        area, so its outer fibres can stand past a thin section's outline). The loose build
        stacks crossing yarns by this height, so the clearance is the gap between fibres."""
        return max(self.height_m, self._fibre_extent_m(1))

    @property
    def occupied_width_m(self) -> float:
        """Width the virtual fibres fill across the yarn [m] (as :attr:`occupied_height_m`);
        a crossing yarn keeps its level over it."""
        return max(self.width_m, self._fibre_extent_m(0))

    def _fibre_extent_m(self, axis: int) -> float:
        """Outer extent of the packed fibres across (0) or through (1) the yarn [m]."""
        offsets, d = self.packing()
        return float(np.ptp(offsets[:, axis])) + d
