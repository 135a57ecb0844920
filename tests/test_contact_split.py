"""Split contact: fibres of one family touch with the yarn's compaction stiffness, fibres of
different families (crossings) with the stiff crossing contact (ContactModel docstring)."""

import math

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.compaction import (
    GLASS_BUNDLE,
    bundle_pressure_pa,
    bundle_volume_fraction,
    contact_for_yarn,
)
from fabmd.model.contact import ContactModel, crossing_force_n, default_stiffness_pa
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.common import run_folder, write_run_folder
from fabmd.scene import blocks
from fabmd.scene.templates import render

# one virtual fibre of a 600 tex glass yarn of 7 (the example's numbers)
AREA = 600e-6 / 2540 / 7
D = 0.36e-3  # touches at Vf 0.30 in a hexagonal bundle
FIBRE = VirtualFibre(GLASS, AREA, D)
BEADS = bead_parameters(FIBRE, Discretisation(0.5))
LAW_K = contact_for_yarn(GLASS_BUNDLE, AREA, D, 1e4)  # the law's 10 kPa state


def split_contact(**kw) -> ContactModel:
    return ContactModel(friction=0.3, within_family_stiffness_pa=LAW_K["normal_stiffness_pa"],
                        **kw)


def test_default_contact_is_not_split():
    c = ContactModel()
    assert not c.split
    assert c.pair_style() == "gran/hooke/history"
    assert c.within_family_stiffness_n_per_m([BEADS]) == c.normal_stiffness_n_per_m([BEADS])


def test_split_coefficients_per_type_pair():
    c = split_contact()
    assert c.split and c.pair_style() == "granular"
    l0 = BEADS.bond_length_m
    kw = LAW_K["normal_stiffness_pa"] * l0
    kc = default_stiffness_pa([BEADS]) * l0
    assert c.within_family_stiffness_n_per_m([BEADS]) == pytest.approx(kw)
    assert c.normal_stiffness_n_per_m([BEADS]) == pytest.approx(kc)
    # the time step follows the stiffer of the two (here the crossing)
    assert c.stability_stiffness_n_per_m([BEADS]) == pytest.approx(max(kw, kc))
    soft_cross = ContactModel(normal_stiffness_pa=1e3, within_family_stiffness_pa=1e6)
    assert soft_cross.stability_stiffness_n_per_m([BEADS]) == pytest.approx(1e6 * l0)
    assert c.softest_normal_stiffness_n_per_m([BEADS]) == pytest.approx(kw)
    table = c.type_pair_coefficients([BEADS], 3)
    assert [(i, j) for i, j, _ in table] == [(1, 1), (1, 2), (1, 3), (2, 2), (2, 3), (3, 3)]
    m_eff = 0.5 * BEADS.mass_kg
    for i, j, coeff in table:
        k = kw if i == j else kc
        assert coeff["kn"] == pytest.approx(k)
        assert coeff["kt"] == pytest.approx(c.tangential_ratio * k)
        # damping: the same fraction of critical for each pair's own stiffness
        assert coeff["gamman"] == pytest.approx(c.damping_ratio * 2 * math.sqrt(k / m_eff))
        assert coeff["friction"] == 0.3


def test_split_contact_inputs_are_checked():
    c = ContactModel(within_family_stiffness_pa="230 kPa")
    assert c.within_family_stiffness_pa == pytest.approx(2.3e5)
    with pytest.raises(InputError, match="contact.within_family_stiffness_pa"):
        ContactModel(within_family_stiffness_pa=-1.0)
    with pytest.raises(InputError, match="hooke"):
        ContactModel(normal="hertz", within_family_stiffness_pa=1e5)
    with pytest.raises(InputError, match="stiffness_factor"):
        ContactModel(stiffness_factor=0.1, within_family_stiffness_pa=1e5)


def test_split_contact_renders_one_pair_coeff_per_type_pair():
    model, b = hex_bundle(0.5, D, D, types=(1, 2, 1, 2))
    text = blocks.contact(model, split_contact(), [b])
    assert "pair_style      granular" in text
    lines = [ln for ln in text.splitlines() if ln.startswith("pair_coeff")]
    assert [ln.split()[1:3] for ln in lines] == [["1", "1"], ["1", "2"], ["2", "2"]]
    assert all(ln.endswith("damping mass_velocity") and " tangential linear_history " in ln
               for ln in lines)
    assert "neigh_modify    exclude molecule/intra all" in text
    # not split: the global gran/hooke/history line as before
    plain = blocks.contact(model, ContactModel(friction=0.3), [b])
    assert "pair_style      gran/hooke/history" in plain and "pair_coeff      * *" in plain


def test_scene_contact_takes_a_within_family_law():
    import tomllib

    from fabmd.examples_dir import example_scene
    from fabmd.model.fabric_model import family_beads
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"] = {"friction": 0.3,
                       "within_family": {"law": "glass", "reference_pressure_pa": "100 kPa"}}
    scene = parse_scene(data)
    fibre = family_beads(scene.fabric, scene.discretisation)["warp"].fibre
    expected = contact_for_yarn(GLASS_BUNDLE, fibre.area_m2, fibre.diameter_m, 1e5)
    assert scene.contact.within_family_stiffness_pa == pytest.approx(
        expected["normal_stiffness_pa"])
    assert scene.contact.normal_stiffness_pa is None  # crossings keep the default
    data["contact"]["within_family_stiffness_pa"] = 1e5
    with pytest.raises(InputError, match="not both"):
        parse_scene(data)
    data["contact"] = {"within_family": {"law": "steel"}}
    with pytest.raises(InputError, match=r"\[contact.within_family\] law"):
        parse_scene(data)


def test_a_crossing_holds_at_the_pressure_the_law_gives_the_yarn():
    """At the law's reference pressure (100 kPa) one crossing of two virtual fibres carries
    p·g² (g: fibre spacing the law gives there). With the crossing contact (default k') the
    overlap stays far below the warning (0.1 d); with the law's soft k' on the crossing too
    it would be > 0.2 d — the pass-through the split avoids."""
    d = 0.333e-3
    law = contact_for_yarn(GLASS_BUNDLE, AREA, d, 1e5)
    g = d * (1 - law["reference_overlap_ratio"])
    force = 1e5 * g * g
    fibre = VirtualFibre(GLASS, AREA, d)
    b = bead_parameters(fibre, Discretisation(0.5))
    c = ContactModel(within_family_stiffness_pa=law["normal_stiffness_pa"])

    def overlap(k_line):  # bisection on the closed-form crossing force (monotone < 0.5 d)
        lo, hi = 0.0, 0.5 * d
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if crossing_force_n(k_line, b.bond_length_m, d, mid) < force:
                lo = mid
            else:
                hi = mid
        return hi / d

    crossing = overlap(default_stiffness_pa([b]))
    assert crossing < 1e-3 < c.overlap_warning
    assert overlap(law["normal_stiffness_pa"]) > 0.2


def hex_bundle(spacing_ratio: float, g: float, d: float, types=(1, 1, 1, 1)):
    """Four periodic fibres along x in a hexagonal lattice of axis spacing g, periodic in
    y (2 g) and z (√3 g): every fibre has six neighbours at distance g; ``types`` gives
    each fibre's atom type (family)."""
    fibre = VirtualFibre(GLASS, AREA, d)
    b = bead_parameters(fibre, Discretisation(spacing_ratio))
    length = 2 * d
    n = round(length / b.bond_length_m)
    b = bead_parameters(fibre, Discretisation(spacing_ratio), bond_length_m=length / n)
    x = b.bond_length_m * np.arange(n)
    h = math.sqrt(3) / 2 * g
    axes = [(0.0, 0.0), (g, 0.0), (0.5 * g, h), (1.5 * g, h)]
    pos = np.vstack([np.column_stack([x, np.full(n, y), np.full(n, z)]) for y, z in axes])
    ring = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    names = ("warp", "weft")[:max(types)]
    model = BeadModel(positions=pos, diameters=d, masses=b.mass_kg,
                      atom_types=np.repeat(np.asarray(types), n),
                      fibre_ids=np.repeat(np.arange(1, 5), n),
                      bonds=np.vstack([ring + k * n for k in range(4)]), bond_types=1,
                      family_names=names,
                      bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "fibre",
                                                b.axial_stiffness_n)],
                      fibre_yarn=np.ones(4, np.int64), yarns=[Yarn("y", "warp")],
                      box_lo=np.array([0.0, -0.25 * g, -0.25 * h]),
                      box_hi=np.array([length, 1.75 * g, 1.75 * h]),
                      periodic=(True, True, True))
    return model, b


def virial_pressure(tmp_path, name, model, contact, b):
    dt = 0.25 * b.critical_time_step_s(contact.stability_stiffness_n_per_m([b]))
    text = "\n".join([
        blocks.setup(model, "probe", "model.data", dt), blocks.bonds(model),
        blocks.contact(model, contact, [b]),
        "compute         pv all pressure NULL virial",
        "fix             out all ave/time 1 1 1 c_pv[2] c_pv[3] file p.txt format ' %.15g'",
        "run             1   # no integrator: the beads stay where they were placed",
        render("finish", final_data="final.data")])
    run_dir = write_run_folder(tmp_path / name, "probe", model, text, {})
    run_folder(Engine(progress=False), run_dir, "probe")
    return tuple(map(float, (run_dir / "p.txt").read_text().split()[-2:]))


@pytest.mark.lammps
def test_a_yarn_of_one_family_compacts_as_its_law_and_crossings_stay_stiff(tmp_path):
    """LAMMPS virial pressure of a periodic hexagonal bundle (every fibre six neighbours):
    all of one family, at the law's reference state, it is the law's pressure (1e-6) with the
    split contact although the crossing contact is 10⁴× stiffer; with alternate rows of
    the other family the pairs between families (4 of 6 neighbours) carry the crossing k'."""
    contact = split_contact()
    g = D * (1 - LAW_K["reference_overlap_ratio"])
    model, b = hex_bundle(0.5, g, D)
    k_cross = contact.normal_stiffness_n_per_m([b]) / b.bond_length_m
    assert k_cross > 1e4 * LAW_K["normal_stiffness_pa"]
    pyy, pzz = virial_pressure(tmp_path, "one_family", model, contact, b)
    law = GLASS_BUNDLE.pressure_pa(bundle_volume_fraction(AREA, g))
    assert pyy == pytest.approx(law, rel=1e-6)
    assert pzz == pytest.approx(law, rel=1e-6)
    # one row (along y) per family: each fibre has 2 same-family neighbours (along y)
    # and 4 of the other family (the diagonals at ±60°: n_y² = 1/4, n_z² = 3/4)
    model2, b2 = hex_bundle(0.5, g, D, types=(1, 1, 2, 2))
    pyy2, pzz2 = virial_pressure(tmp_path, "two_families", model2, contact, b2)
    p_w = bundle_pressure_pa(LAW_K["normal_stiffness_pa"], D, g)  # all-pairs pressure
    p_c = bundle_pressure_pa(k_cross, D, g)
    # in a hexagonal bundle the y virial is 2/3 from the y-neighbours, 1/3 from diagonals
    assert pyy2 == pytest.approx(2 / 3 * p_w + 1 / 3 * p_c, rel=1e-6)
    assert pzz2 == pytest.approx(p_c, rel=1e-6)
