"""Units at the door and validation when objects are built (no LAMMPS)."""

import math

import pytest

from fabmd.errors import InputError
from fabmd.model.beads import BeadParameters, Discretisation, TimeStep, bead_parameters
from fabmd.model.material import GLASS, FibreMaterial, VirtualFibre
from fabmd.units import quantity


@pytest.mark.parametrize("text,kind,si", [
    ("68 tex", "linear_density", 68e-6),
    ("1200tex", "linear_density", 1.2e-3),
    ("0.3 mm", "length", 3e-4),
    ("70 GPa", "pressure", 70e9),
    ("2.54 g/cm3", "density", 2540.0),
    ("5 ends/cm", "count_per_length", 500.0),
    ("45 deg", "angle", math.pi / 4),
    ("2 mm/min", "speed", 2e-3 / 60),
    (0.004, "length", 0.004),
])
def test_quantities_convert_to_si(text, kind, si):
    assert quantity(text, kind) == pytest.approx(si)


@pytest.mark.parametrize("text", ["3 furlongs", "mm", "abc", ""])
def test_unknown_units_are_named(text):
    with pytest.raises(InputError, match="yarn.width_m"):
        quantity(text, "length", "yarn.width_m")


def test_material_accepts_textile_units():
    m = FibreMaterial("73 GPa", "2.54 g/cm3")
    assert m.modulus_pa == 73e9 and m.density_kg_m3 == pytest.approx(2540)


@pytest.mark.parametrize("kwargs,field", [
    ({"modulus_pa": -1e9, "density_kg_m3": 2500}, "material.modulus_pa"),
    ({"modulus_pa": 1e9, "density_kg_m3": 0}, "material.density_kg_m3"),
    ({"modulus_pa": float("nan"), "density_kg_m3": 2500}, "material.modulus_pa"),
])
def test_bad_material_names_field_value_and_range(kwargs, field):
    with pytest.raises(InputError) as err:
        FibreMaterial(**kwargs)
    assert field in str(err.value) and "must be" in str(err.value)
    assert "\n" not in str(err.value)


def test_zero_fibres_is_an_error():
    with pytest.raises(InputError, match="yarn.n_fibres must be an integer >= 1, got 0"):
        VirtualFibre.from_yarn(GLASS, 1200, 0, 0.2e-3)


def test_yarn_area_from_tex():
    f = VirtualFibre.from_yarn(GLASS, "1200 tex", 19, 0.2e-3)
    assert f.area_m2 * 19 == pytest.approx(1200e-6 / 2540)


def test_spacing_larger_than_diameter_is_an_error():
    with pytest.raises(InputError, match="spacing_ratio must be in \\(0, 1\\], got 1.5"):
        Discretisation(spacing_ratio=1.5)
    with pytest.raises(InputError, match="larger than the bead diameter"):
        BeadParameters(diameter_m=1e-4, bond_length_m=2e-4, mass_kg=1e-9, axial_stiffness_n=1)


def test_bead_parameters_follow_closed_form():
    fibre = VirtualFibre.solid(GLASS, 0.1e-3)
    b = bead_parameters(fibre, Discretisation(spacing_ratio=0.5, mass_scaling=4.0))
    ea = GLASS.modulus_pa * math.pi * 0.1e-3**2 / 4
    l0 = 0.05e-3
    assert b.bond_length_m == pytest.approx(l0)
    assert b.bond_coefficient == pytest.approx(ea / (2 * l0))  # LAMMPS K = EA/(2 l0)
    assert b.mass_kg == pytest.approx(4.0 * GLASS.density_kg_m3 * fibre.area_m2 * l0)
    # bare chain: dt_crit = sqrt(m / k), k = EA / l0
    assert b.critical_time_step_s() == pytest.approx(math.sqrt(b.mass_kg * l0 / ea))
    # mass scaling 4 doubles the critical step
    b1 = bead_parameters(fibre, Discretisation(spacing_ratio=0.5))
    assert b.critical_time_step_s() == pytest.approx(2 * b1.critical_time_step_s())
    # contacts and bending shorten it
    assert b.critical_time_step_s(contact_stiffness_n_per_m=b.spring_n_per_m) < \
        b.critical_time_step_s()


def test_time_step_above_stable_is_an_error():
    with pytest.raises(InputError, match="above the stable time step"):
        TimeStep(value_s=1e-6).resolve(critical_s=1e-8)
    assert TimeStep(factor=0.25).resolve(1e-8) == pytest.approx(2.5e-9)
    with pytest.raises(InputError, match="time_step.factor"):
        TimeStep(factor=1.5)
