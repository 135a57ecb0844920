"""From a virtual fibre to bead-chain parameters, and the stable time step.

A virtual fibre of axial stiffness E·A, mass per length ρ·A and contact
diameter d becomes beads of diameter d spaced l0 = (s/d)·d apart:

* bead mass m = ρ·A·l0 × mass_scaling (chain mass is the fibre mass);
* bond spring k = E·A/l0 — LAMMPS ``bond harmonic`` is E = K(r − r0)², so its
  coefficient is K = k/2 = E·A/(2·l0);
* optional bending (``angle cosine``, E = K(1 + cos θ)) with K = E·I/l0.

Stable time step. The highest eigen-frequency of a bead with two bonds, a
bending term and *z* contacts is bounded (Gershgorin) by
ω² ≤ (4k + 16·E·I/l0³ + z·k_n)/m, and central differences are stable for
dt < 2/ω. fabmd uses z = 6 (hexagonal packing in a yarn) and a safety factor
(default 0.25, see :class:`TimeStep`): the bare chain gives dt_crit = sqrt(m/k),
the value LAMMPS-NOTES.md measured (blow-up at 1.1× that).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError
from ..geometry.material import VirtualFibre

#: contacts per bead assumed in the stability bound (hexagonal packing)
STABILITY_CONTACTS = 6
#: ``Discretisation.bead_register`` choices
BEAD_REGISTERS = ("aligned", "staggered")
#: (√5 − 1)/2: the phases frac(k·g) of any n fibres are spread almost evenly over [0, 1)
GOLDEN_FRACTION = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class Discretisation:
    """How a virtual fibre is cut into beads.

    Args:
        spacing_ratio: bead spacing over bead diameter s/d, in (0, 1]. Smaller
            is smoother contact (less bumpy) but costs more beads.
        mass_scaling: factor on every bead mass (> 0). Quasi-static runs may use
            > 1 to take a larger time step; check rate independence when you do.
        bending_factor: fraction of the solid-rod bending stiffness E·I given to
            each virtual fibre, in [0, 1]; 0 (default) adds no bending term. A number
            whose meaning changes with the fibres per yarn: the yarn's own rigidity
            (``[yarns.*] bending_stiffness_nm2``, shared by its fibres) is the physical
            way to give it; a scene takes one or the other.
        bead_register: where each fibre's beads sit along it. ``"aligned"`` (default):
            every fibre's first bead at the yarn's start, so the fibres of a yarn are in
            register. ``"staggered"``: fibre k of a yarn starts φ_k·l0 further on,
            φ_k = frac(k·(√5 − 1)/2), so neighbouring fibres and the fibre crossings of
            a yarn crossing sample many registers (the register average that the
            within-family law and the per-crossing contact assume; README "Bead
            register").
    """

    spacing_ratio: float = 0.5
    mass_scaling: float = 1.0
    bending_factor: float = 0.0
    bead_register: str = "aligned"

    def __post_init__(self):
        inputs.in_range("discretisation.spacing_ratio", self.spacing_ratio, 0.0, 1.0,
                        low_open=True)
        inputs.positive("discretisation.mass_scaling", self.mass_scaling)
        inputs.in_range("discretisation.bending_factor", self.bending_factor, 0.0, 1.0)
        inputs.one_of("discretisation.bead_register", self.bead_register, BEAD_REGISTERS)

    def bead_phases(self, n_fibres: int) -> np.ndarray:
        """Start of each fibre's first bead along it, in bond lengths, in [0, 1)."""
        if self.bead_register == "aligned":
            return np.zeros(n_fibres)
        return np.mod(np.arange(n_fibres) * GOLDEN_FRACTION, 1.0)


@dataclass(frozen=True)
class BeadParameters:
    """Bead-chain parameters of one kind of virtual fibre (SI)."""

    diameter_m: float
    bond_length_m: float
    mass_kg: float
    axial_stiffness_n: float
    bending_stiffness_nm2: float = 0.0
    cohesion_spring_n_per_m: float = 0.0  # sum of a bead's cohesion links (largest bead)

    def __post_init__(self):
        inputs.positive("beads.diameter_m", self.diameter_m)
        inputs.positive("beads.bond_length_m", self.bond_length_m)
        inputs.positive("beads.mass_kg", self.mass_kg)
        inputs.positive("beads.axial_stiffness_n", self.axial_stiffness_n)
        inputs.non_negative("beads.bending_stiffness_nm2", self.bending_stiffness_nm2)
        inputs.non_negative("beads.cohesion_spring_n_per_m", self.cohesion_spring_n_per_m)
        if self.bond_length_m > self.diameter_m * (1 + 1e-9):
            raise InputError(
                f"bead spacing {self.bond_length_m:g} m is larger than the bead diameter "
                f"{self.diameter_m:g} m: neighbouring beads would leave gaps that other "
                f"fibres fall through; use spacing_ratio <= 1")

    @property
    def spring_n_per_m(self) -> float:
        """Axial spring of one bond, k = E·A/l0 [N/m]."""
        return self.axial_stiffness_n / self.bond_length_m

    @property
    def mass_per_length_kg_m(self) -> float:
        """Mass per length of the chain, m/l0 [kg/m] (with the mass scaling)."""
        return self.mass_kg / self.bond_length_m

    @property
    def wave_speed_m_s(self) -> float:
        """Axial wave speed along the chain, c = l0·sqrt(k/m) [m/s]."""
        return self.bond_length_m * math.sqrt(self.spring_n_per_m / self.mass_kg)

    @property
    def bond_coefficient(self) -> float:
        """LAMMPS ``bond harmonic`` K = E·A/(2·l0) [J/m²]."""
        return 0.5 * self.spring_n_per_m

    @property
    def angle_coefficient(self) -> float:
        """LAMMPS ``angle cosine`` K = E·I/l0 [J]."""
        return self.bending_stiffness_nm2 / self.bond_length_m

    @property
    def sphere_density_kg_m3(self) -> float:
        """Density to give a LAMMPS sphere of this diameter so that its mass is ``mass_kg``."""
        return self.mass_kg / (math.pi * self.diameter_m**3 / 6.0)

    def omega_squared(self, contact_stiffness_n_per_m: float = 0.0,
                      contacts: int = STABILITY_CONTACTS) -> float:
        """Upper bound of the squared highest angular frequency of a bead [1/s²]."""
        bending = 16.0 * self.bending_stiffness_nm2 / self.bond_length_m**3
        return (4.0 * self.spring_n_per_m + bending + self.cohesion_spring_n_per_m
                + contacts * contact_stiffness_n_per_m) / self.mass_kg

    def critical_time_step_s(self, contact_stiffness_n_per_m: float = 0.0) -> float:
        """dt_crit = 2/ω_max [s]."""
        return 2.0 / math.sqrt(self.omega_squared(contact_stiffness_n_per_m))


def bead_parameters(fibre: VirtualFibre, discretisation: Discretisation | None = None,
                    bond_length_m: float | None = None) -> BeadParameters:
    """Bead parameters of ``fibre``.

    Args:
        fibre: the virtual fibre.
        discretisation: spacing ratio, mass scaling, bending (defaults if None).
        bond_length_m: force this rest length (e.g. to fit a whole number of beads
            into a periodic length); default spacing_ratio × diameter.
    """
    disc = discretisation or Discretisation()
    l0 = disc.spacing_ratio * fibre.diameter_m if bond_length_m is None else bond_length_m
    l0 = inputs.positive("bond_length_m", l0)
    bending = disc.bending_factor * fibre.solid_bending_stiffness_nm2
    if fibre.bending_stiffness_nm2 > 0:
        if disc.bending_factor > 0:
            raise InputError("the yarns give their bending stiffness (bending_stiffness_nm2) "
                             "and [discretisation] bending_factor gives another: keep one")
        bending = fibre.bending_stiffness_nm2
    return BeadParameters(
        diameter_m=fibre.diameter_m,
        bond_length_m=l0,
        mass_kg=fibre.mass_per_length_kg_m * l0 * disc.mass_scaling,
        axial_stiffness_n=fibre.axial_stiffness_n,
        bending_stiffness_nm2=bending,
    )


@dataclass(frozen=True)
class TimeStep:
    """Time-step policy.

    Args:
        factor: fraction of the critical time step used when ``value_s`` is not
            given, in (0, 1]. Default 0.25 (LAMMPS-NOTES: use 0.2–0.3 dt_crit).
        value_s: an explicit time step [s]; must not exceed the critical one.
        check: refuse time steps above the critical one (default). Only stability
            studies (``benchmarks/stability.py``) turn this off, to find the boundary.
    """

    factor: float = 0.25
    value_s: float | None = None
    check: bool = True

    def __post_init__(self):
        high = 1.0 if self.check else 100.0
        inputs.in_range("time_step.factor", self.factor, 0.0, high, low_open=True)
        if self.value_s is not None:
            inputs.positive("time_step.value_s", self.value_s)

    def resolve(self, critical_s: float) -> float:
        """The time step to use given the critical one [s]."""
        if self.value_s is None:
            return self.factor * critical_s
        if self.value_s > critical_s and self.check:
            raise InputError(
                f"time_step.value_s = {self.value_s:.3g} s is above the stable time step "
                f"{critical_s:.3g} s of the stiffest bead; use at most "
                f"{self.factor * critical_s:.3g} s ({self.factor:g} × critical) or leave it "
                f"unset")
        return self.value_s


def model_bead_parameters(model) -> list[BeadParameters]:
    """Bead parameters of every bond type of a :class:`~fabmd.model.bead_model.BeadModel`.

    Recovered from the model itself (rest length, bond coefficient, and the
    lightest bead and smallest diameter of the type's family, or of its yarn spec
    where the family has several), so a stage that
    receives only a model can still derive its time step and contact stiffness.
    """
    out = []
    spring = np.zeros(model.n_beads)
    cohesion = ~model.fibre_bond_mask()
    if cohesion.any():
        k = np.array([bt.spring_n_per_m for bt in model.bond_type_table])
        k_links = k[model.bond_types[cohesion] - 1]
        for end in (0, 1):
            spring += np.bincount(model.bonds[cohesion, end], weights=k_links,
                                  minlength=model.n_beads)
    table = model.bond_type_table
    for bt in model.fibre_bond_types():
        fam = model.family_names.index(bt.family) + 1 if bt.family in model.family_names else 0
        mask = model.atom_types == fam
        if bt.spec and any(o.spec != bt.spec for o in table if o.family == bt.family):
            # a family with several yarn specs: the beads of this spec's fibres
            same = [k + 1 for k, o in enumerate(table) if o.spec == bt.spec]
            mask = np.zeros(model.n_beads, bool)
            mask[model.bonds[np.isin(model.bond_types, same)].ravel()] = True
        if not mask.any():
            mask = np.ones(model.n_beads, bool)
        bending = [at.coefficient * bt.rest_length_m for at in model.angle_type_table
                   if at.family == bt.family]
        out.append(BeadParameters(
            diameter_m=float(model.diameters[mask].min()),
            bond_length_m=bt.rest_length_m,
            mass_kg=float(model.masses[mask].min()),
            axial_stiffness_n=bt.bond_axial_stiffness_n,
            bending_stiffness_nm2=max(bending, default=0.0),
            cohesion_spring_n_per_m=float(spring[mask].max())))
    return out


def model_critical_time_step_s(model, contact_stiffness_n_per_m: float = 0.0) -> float:
    """Smallest critical time step over the bond types of a model [s], for one contact
    stiffness; with contact objects use :func:`fabmd.model.timestep.critical_time_step_s`."""
    beads = model_bead_parameters(model)
    if not beads:
        raise InputError("model has no bond types: cannot derive a time step")
    return min(b.critical_time_step_s(contact_stiffness_n_per_m) for b in beads)
