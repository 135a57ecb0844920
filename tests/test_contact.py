"""Contact and friction: inputs, style choice, command text (no LAMMPS)."""

import math

import pytest

from fabmd.engine.script import logical_lines
from fabmd.errors import InputError
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.contact import ContactModel, ToolContact
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.capstan import Capstan
from fabmd.protocols.sliding import Sliding
from fabmd.scene import blocks

from .conftest import run_cli

BEADS = [bead_parameters(VirtualFibre.solid(GLASS, 0.1e-3))]


@pytest.mark.parametrize("make,words", [
    (lambda: ContactModel(friction=-0.1), "contact.friction must be >= 0, got -0.1"),
    (lambda: ContactModel(stiffness_factor=0), "contact.stiffness_factor must be > 0, got 0"),
    (lambda: ContactModel(stiffness_n_per_m=-5.0),
     "contact.stiffness_n_per_m must be > 0, got -5"),
    (lambda: ContactModel(normal="jkr"), "contact.normal must be one of 'hooke', 'hertz'"),
    (lambda: ContactModel(overlap_warning=0.3, overlap_limit=0.2),
     "contact.overlap_limit must be in (0.3, 1]"),
    (lambda: ToolContact(friction=-1), "tool_contact.friction must be >= 0, got -1"),
    (lambda: ToolContact(stiffness_factor=-1), "tool_contact.stiffness_factor must be > 0"),
    (lambda: ToolContact(stiffness_n_per_m=0.0), "tool_contact.stiffness_n_per_m must be > 0"),
    (lambda: ToolContact(damping_ratio=0.0), "tool_contact.damping_ratio must be in (0, 1]"),
    (lambda: ContactModel(damping_ratio=0.0), "contact.damping_ratio must be in (0, 1]"),
    (lambda: Capstan(tool=ToolContact(friction=-0.2)),
     "tool_contact.friction must be >= 0, got -0.2"),
    (lambda: Capstan(wrap_angle_rad=0.0), "capstan.wrap_angle_rad must be in (0, 6.28319)"),
])
def test_bad_input_is_one_line_naming_the_field(make, words):
    with pytest.raises(InputError) as err:
        make()
    message = str(err.value)
    assert words in message and "\n" not in message


def test_pair_style_is_the_cheapest_that_carries_the_physics():
    assert ContactModel(friction=0.0).pair_style() == "gran/hooke"  # no history needed
    assert ContactModel(friction=0.3).pair_style() == "gran/hooke/history"
    assert ContactModel(friction=0.0, normal="hertz").pair_style() == "gran/hertz/history"


def test_default_stiffness_is_per_unit_length_of_fibre():
    b = BEADS[0]
    c = ContactModel(normal_stiffness_pa="2 GPa")
    assert c.per_length and c.normal_stiffness_pa == 2e9
    # k_n = k'·l0: a bead pair carries the force of one bead spacing of line contact
    assert c.normal_stiffness_n_per_m(BEADS) == pytest.approx(2e9 * b.bond_length_m)
    finer = [bead_parameters(VirtualFibre.solid(GLASS, 0.1e-3), Discretisation(0.25))]
    assert c.normal_stiffness_n_per_m(finer) == pytest.approx(
        0.5 * c.normal_stiffness_n_per_m(BEADS))
    # legacy keys keep their meaning (and are not per unit length)
    assert ContactModel(stiffness_n_per_m=7.0).normal_stiffness_n_per_m(BEADS) == 7.0
    legacy = ContactModel(stiffness_factor=0.1)
    assert not legacy.per_length
    assert legacy.normal_stiffness_n_per_m(BEADS) == pytest.approx(0.1 * b.spring_n_per_m)
    assert ToolContact(normal_stiffness_pa=3e9).normal_stiffness_n_per_m(BEADS) == \
        pytest.approx(3e9 * b.bond_length_m)
    # the default k' = 0.4·E·A/d²: the former 0.1·E·A/l0 per pair at s/d = 0.5, and a
    # stiffness per unit length that does not change with the spacing
    assert ContactModel().normal_stiffness_n_per_m(BEADS) == pytest.approx(
        0.1 * b.spring_n_per_m)
    assert ContactModel().normal_stiffness_n_per_m(finer) == pytest.approx(
        0.4 * b.axial_stiffness_n / b.diameter_m**2 * finer[0].bond_length_m)


def test_overlap_ratio_of_a_force():
    b = BEADS[0]
    # a force of 1 % of E·A overlaps δ/d = (F/E·A)·(s/d)/0.1 = 5 % at the default stiffness
    f = 0.01 * b.axial_stiffness_n
    assert ContactModel().overlap_ratio(f, BEADS) == pytest.approx(0.05)
    hertz = ContactModel(normal="hertz")
    f_ref = hertz.normal_stiffness_n_per_m(BEADS) * hertz.reference_overlap * b.diameter_m
    assert hertz.overlap_ratio(f_ref, BEADS) == pytest.approx(hertz.reference_overlap)


def test_hertz_matches_hooke_stiffness_at_the_reference_overlap():
    hooke = ContactModel()
    hertz = ContactModel(normal="hertz")
    d = BEADS[0].diameter_m
    delta = hertz.reference_overlap * d
    c = hertz.pair_coefficients(BEADS)
    force_hertz = c["kn"] * math.sqrt(delta * d / 4) * delta  # LAMMPS gran/hertz/history
    assert force_hertz == pytest.approx(hooke.normal_stiffness_n_per_m(BEADS) * delta)
    assert hertz.stability_stiffness_n_per_m(BEADS) > hooke.normal_stiffness_n_per_m(BEADS)


def test_contact_block_excludes_intra_fibre_pairs():
    model = Sliding().model()
    text = blocks.contact(model, ContactModel(friction=0.3), BEADS)
    assert "pair_style      gran/hooke/history" in text
    assert "neigh_modify    exclude molecule/intra all" in text


def test_tool_blocks_use_the_granular_wall_model():
    region = blocks.tool_region(ToolContact(friction=0.25), BEADS, "punch", fix_id="punch")
    assert "wall/gran/region granular hooke" in region and "region punch contacts" in region
    assert "linear_history" in region and " 0.25 " in region
    plane = blocks.tool_plane(ToolContact(), BEADS, "z", lo_m=0.0, contacts=False)
    assert "wall/gran granular hooke" in plane and "zplane 0 NULL" in plane
    commands = " ".join(logical_lines(region + plane))
    assert "hooke/history" not in commands  # the classic wall model loses friction


def test_overlap_monitor_text():
    model = Sliding().model()
    text = blocks.overlap_monitor(model, ContactModel(), BEADS, every=50, tool_fixes=("die",))
    assert "pair/local dist cutoff radius" in text
    assert "fix             guard_overlap all halt 50" in text
    assert "c_fabmd_tool_max_die" in text
    assert blocks.overlap_monitor(model, None, BEADS).startswith("#")


def test_cli_bad_contact_setting_is_one_line(tmp_path):
    out = run_cli("validate", "sliding", "--set", "stiffness_factor=0", "--out",
                  str(tmp_path / "x"))
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "contact.stiffness_factor must be > 0" in lines[0]
    assert not (tmp_path / "x").exists()  # nothing written, LAMMPS never started
    out = run_cli("validate", "capstan", "--set", "tool_stiffness_factor=-1", "--out",
                  str(tmp_path / "y"))
    assert out.returncode == 2 and "tool_contact.stiffness_factor must be > 0" in out.stderr
    assert not (tmp_path / "y").exists()
