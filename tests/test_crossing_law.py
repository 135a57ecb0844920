"""Crossings that compact by the yarn's law (``contact.crossing = "law"``): the crossing force of
two sub-bundles pressed through a d × d/sin θ patch, F = p_s(Vf_t/(1 − δ/2d))·d²/sin θ, carried by
bead pairs whose register average does not see the bead spacing (fabmd.model.crossing_law)."""

import math
import tomllib

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.bundle_contact import BundleContact
from fabmd.model.contact import ContactModel
from fabmd.model.crossing_law import CROSSING_KEYWORD, CrossingLaw
from fabmd.scene.blocks import contact, contact_files

from .test_contact_crossing import FORCE_Z, PROBE_GRID, crossings
from .test_contact_law import AREA, FIBRE, LAW, D, probe

K_CROSS = 8.9e9  # k' of the hard core [Pa] (the example's default order)


def law() -> CrossingLaw:
    return CrossingLaw(LAW, K_CROSS)


def test_the_crossing_force_is_the_compaction_law_through_the_patch():
    """F(δ) = p_s·d²/sin θ with p_s the law at Vf_t/(1 − δ/(2d)) less the law at Vf_t, computed
    here from the law's own formula; 0 untouched, rising, and 1/sin θ at other angles."""
    x = law()
    g = LAW.law
    vf_t = AREA / (math.sqrt(3) / 2 * D**2)
    for ratio in (0.05, 0.15, 0.3):
        vf = vf_t / (1 - ratio / 2)
        p = g.coefficient * g.modulus_pa * (vf**3 - vf_t**3)
        assert x.force_n(ratio * D) == pytest.approx(p * D**2, rel=1e-9)
        assert x.force_n(ratio * D, 50.0) == pytest.approx(p * D**2 / math.sin(
            math.radians(50)), rel=1e-9)
    assert x.force_n(0.0) == 0.0
    forces = x.force_n(np.linspace(0, 0.3, 31) * D)
    assert np.all(np.diff(forces) > 0)


@pytest.mark.parametrize("angle", [90.0, 50.0])
@pytest.mark.parametrize("overlap", [0.1, 0.25])
def test_bead_pairs_carry_the_crossing_law_at_any_spacing(angle, overlap):
    """Two straight chains, averaged over 16 × 16 registers: the law within 2 % at s/d 0.5 and
    0.25, and the two spacings within 2 % of each other."""
    x = law()
    means = {r: x.mean_force_n(overlap * D, r * D, angle, grid=16) for r in (0.5, 0.25)}
    for r, m in means.items():
        assert m == pytest.approx(x.force_n(overlap * D, angle), rel=0.02), r
    assert means[0.25] == pytest.approx(means[0.5], rel=0.02)


def test_the_linear_part_lies_under_the_pair_force_and_friction_says_its_share():
    x = law()
    l0 = 0.5 * D
    r = np.linspace(x.core_spacing_m, D, 500)[:-1]
    k = x.linear_pair_stiffness_n_per_m(l0)
    assert np.all(k * (D - r) <= x.pair_force_n(r, l0) * (1 + 1e-9))
    shares = [x.friction_share(o * D, l0) for o in (0.05, 0.15, 0.3)]
    assert all(0 < s <= 1 for s in shares) and shares == sorted(shares)


def test_the_crossing_law_needs_the_within_family_law_and_one_fibre_kind():
    with pytest.raises(InputError, match="crossing = 'law' needs"):
        ContactModel(crossing="law")
    with pytest.raises(InputError, match="crossing = 'law' needs"):
        ContactModel(crossing="law", within_family_stiffness_pa=1e6)
    other = BundleContact(LAW.law, AREA, 1.1 * D)
    with pytest.raises(InputError, match="one fibre kind"):
        ContactModel(crossing="law", within_family_law=LAW,
                     within_family_laws=(("warp", LAW), ("weft", other)))
    with pytest.raises(InputError, match="no crossing law"):
        ContactModel(within_family_law=LAW).crossing_law([bead_parameters(
            FIBRE, Discretisation(0.5))])


def test_the_scene_writes_the_crossing_section_and_its_pair_coefficients(tmp_path):
    """A plain weave with ``crossing = "law"``: the table file has a CROSSING section, the
    input puts it on the warp–weft pair, whose granular part is the law's linear part."""
    from fabmd.examples_dir import example_scene
    from fabmd.model.beads import model_bead_parameters
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"]["crossing"] = "law"
    scene = parse_scene(data)
    model = scene.model()
    beads = model_bead_parameters(model)
    files = contact_files(scene.contact, beads)
    text = next(iter(files.values()))
    assert f"\n{CROSSING_KEYWORD}\n" in text
    lammps = contact(model, scene.contact, beads)
    assert f"pair_coeff      1 2 table within_family.table {CROSSING_KEYWORD}" in lammps
    k_lin = scene.contact.crossing_law(beads).linear_pair_stiffness_n_per_m(
        max(b.bond_length_m for b in beads))
    assert f"pair_coeff      1 2 granular hooke {k_lin:.10g}"[:38] in lammps


@pytest.mark.lammps
def test_lammps_crossings_follow_the_law_at_either_spacing(tmp_path):
    """One step, no integrator: 64 crossings (8 × 8 registers) of two open chains of two
    families with ``crossing = "law"``: LAMMPS's mean force per crossing is what Python sums
    over the same registers (table and granular linear part together, 0.2 %: the table's
    interpolation), and the law within 3 % (8 × 8 registers; 16 × 16 give 2 %, above), at s/d
    0.5 and 0.25, at 90° and 50°."""
    overlap = 0.15
    contact_model = ContactModel(friction=0.3, within_family_law=LAW, crossing="law",
                                 normal_stiffness_pa=K_CROSS)
    for angle in (90.0, 50.0):
        for ratio in (0.5, 0.25):
            model, b, registers = crossings(ratio, overlap, angle)
            fz, _ = probe(tmp_path, f"law_{angle:g}_{ratio}", model, contact_model, b, FORCE_Z)
            python = law().mean_force_n(overlap * D, b.bond_length_m, angle, grid=PROBE_GRID)
            assert fz / len(registers) == pytest.approx(python, rel=2e-3), (angle, ratio)
            assert fz / len(registers) == pytest.approx(
                law().force_n(overlap * D, angle), rel=0.03), (angle, ratio)
