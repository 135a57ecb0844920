"""Contact between virtual fibres, and between fibres and tools (SI).

Fibre–fibre contact is a granular pair style between beads of *different*
fibres (``neigh_modify exclude molecule/intra all``), with a normal spring
(Hooke, or Hertz matched to Hooke at a reference overlap), normal damping as a
fraction of critical, and a history-dependent tangential spring capped by
Coulomb friction μ·F_n. Tools (walls, punch, die, clamps) have their own μ.

Default normal stiffness: k_n = stiffness_factor × E·A/l0 of the stiffest
virtual fibre, so that overlaps stay a small fraction of the bead diameter at
the forces a fibre carries (a run reports the largest overlap it saw).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import inputs
from .beads import BeadParameters

NORMAL_MODELS = ("hooke", "hertz")


@dataclass(frozen=True)
class ContactModel:
    """Fibre–fibre contact.

    Args:
        friction: Coulomb coefficient μ (>= 0).
        normal: ``"hooke"`` (linear) or ``"hertz"``.
        stiffness_factor: k_n over the axial bond spring E·A/l0 (> 0), used
            when ``stiffness_n_per_m`` is not given.
        stiffness_n_per_m: explicit linear normal stiffness k_n [N/m] (> 0).
        tangential_ratio: k_t/k_n (> 0; 2/7 is LAMMPS's usual choice).
        damping_ratio: normal damping as a fraction of critical, in [0, 1].
        reference_overlap: overlap/d at which a Hertz contact matches k_n, in (0, 0.5].
        overlap_warning: overlap/d above which a run warns, in (0, 1).
    """

    friction: float = 0.3
    normal: str = "hooke"
    stiffness_factor: float = 0.1
    stiffness_n_per_m: float | None = None
    tangential_ratio: float = 2.0 / 7.0
    damping_ratio: float = 0.3
    reference_overlap: float = 0.05
    overlap_warning: float = 0.1

    def __post_init__(self):
        inputs.non_negative("contact.friction", self.friction)
        inputs.one_of("contact.normal", self.normal, NORMAL_MODELS)
        inputs.positive("contact.stiffness_factor", self.stiffness_factor)
        if self.stiffness_n_per_m is not None:
            inputs.positive("contact.stiffness_n_per_m", self.stiffness_n_per_m)
        inputs.positive("contact.tangential_ratio", self.tangential_ratio)
        inputs.in_range("contact.damping_ratio", self.damping_ratio, 0.0, 1.0)
        inputs.in_range("contact.reference_overlap", self.reference_overlap, 0.0, 0.5,
                        low_open=True)
        inputs.in_range("contact.overlap_warning", self.overlap_warning, 0.0, 1.0,
                        low_open=True, high_open=True)

    def normal_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        """Linear(ised) normal stiffness k_n [N/m]."""
        if self.stiffness_n_per_m is not None:
            return self.stiffness_n_per_m
        return self.stiffness_factor * max(b.spring_n_per_m for b in beads)

    def pair_style(self) -> str:
        """The cheapest LAMMPS granular style that carries this physics."""
        return f"gran/{self.normal}/history"

    def pair_coefficients(self, beads: list[BeadParameters]) -> dict[str, float]:
        """``Kn Kt gamman gammat xmu`` for ``pair_style gran/<normal>/history``.

        Damping is set from the lightest bead (highest critical damping rate).
        """
        kn = self.normal_stiffness_n_per_m(beads)
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
    """Contact between fibres and a rigid tool (wall, punch, die, blank holder).

    Args:
        friction: Coulomb coefficient μ between tool and fibres (>= 0).
        stiffness_factor: k_n over E·A/l0 of the stiffest fibre (> 0).
        damping_ratio: normal damping as a fraction of critical, in [0, 1].
    """

    friction: float = 0.2
    stiffness_factor: float = 0.1
    damping_ratio: float = 0.3

    def __post_init__(self):
        inputs.non_negative("tool_contact.friction", self.friction)
        inputs.positive("tool_contact.stiffness_factor", self.stiffness_factor)
        inputs.in_range("tool_contact.damping_ratio", self.damping_ratio, 0.0, 1.0)

    def normal_stiffness_n_per_m(self, beads: list[BeadParameters]) -> float:
        return self.stiffness_factor * max(b.spring_n_per_m for b in beads)

    def wall_coefficients(self, beads: list[BeadParameters]) -> dict[str, float]:
        """``Kn Kt gamman gammat xmu`` for ``fix wall/gran hooke/history`` (wall mass infinite)."""
        kn = self.normal_stiffness_n_per_m(beads)
        m = min(b.mass_kg for b in beads)
        gamma_n = self.damping_ratio * 2.0 * math.sqrt(kn / m)
        return {"kn": kn, "kt": 2.0 / 7.0 * kn, "gamman": gamma_n, "gammat": 0.5 * gamma_n,
                "friction": self.friction}
