"""The yarn compaction law and the bead contact that realises it in a fibre bundle."""

import math

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.compaction import (
    CARBON_BUNDLE,
    GLASS_BUNDLE,
    CompactionLaw,
    bundle_pressure_pa,
    bundle_volume_fraction,
    compare,
    contact_for_yarn,
)
from fabmd.model.contact import ContactModel
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.common import run_folder, write_run_folder
from fabmd.scene import blocks
from fabmd.scene.templates import render

# one virtual fibre of a 600 tex glass yarn of 7 (the example's numbers)
AREA = 600e-6 / 2540 / 7
D = 0.333e-3


def test_law_and_its_inverse():
    for law in (GLASS_BUNDLE, CARBON_BUNDLE):
        assert law.pressure_pa(law.vf0) == 0.0
        for p in (1e3, 1e5, 3e5):  # below both laws' packing limits
            assert law.pressure_pa(law.volume_fraction(p)) == pytest.approx(p, rel=1e-9)
    assert GLASS_BUNDLE.volume_fraction(1e5) == pytest.approx(0.55)
    with pytest.raises(InputError, match="compaction_law.vf0"):
        CompactionLaw(1e-5, 73e9, vf0=0.95)


def test_contact_for_yarn_meets_the_law_at_the_reference_pressure():
    c = contact_for_yarn(GLASS_BUNDLE, AREA, D, "100 kPa")
    g = D * (1 - c["reference_overlap_ratio"])
    assert bundle_volume_fraction(AREA, g) == pytest.approx(GLASS_BUNDLE.volume_fraction(1e5))
    assert bundle_pressure_pa(c["normal_stiffness_pa"], D, g) == pytest.approx(1e5)
    rows = {r["pressure_pa"]: r for r in compare(GLASS_BUNDLE, c["normal_stiffness_pa"],
                                                 AREA, D)}
    assert rows[1e5]["vf_beads"] == pytest.approx(rows[1e5]["vf_law"])
    # too fat virtual fibres: they touch beyond the law's state
    with pytest.raises(InputError, match="touch at Vf"):
        contact_for_yarn(GLASS_BUNDLE, AREA, 0.25e-3, 1e5)


def hex_bundle(spacing_ratio: float, g: float, D: float):
    """Four periodic fibres along x in a hexagonal lattice of axis spacing g, periodic in
    y (2 g) and z (√3 g): every fibre has six neighbours at distance g."""
    fibre = VirtualFibre(GLASS, AREA, D)
    b = bead_parameters(fibre, Discretisation(spacing_ratio))
    length = 2 * D
    n = round(length / b.bond_length_m)
    b = bead_parameters(fibre, Discretisation(spacing_ratio), bond_length_m=length / n)
    x = b.bond_length_m * np.arange(n)
    h = math.sqrt(3) / 2 * g
    axes = [(0.0, 0.0), (g, 0.0), (0.5 * g, h), (1.5 * g, h)]
    pos = np.vstack([np.column_stack([x, np.full(n, y), np.full(n, z)]) for y, z in axes])
    ring = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
    model = BeadModel(positions=pos, diameters=D, masses=b.mass_kg, atom_types=1,
                      fibre_ids=np.repeat(np.arange(1, 5), n),
                      bonds=np.vstack([ring + k * n for k in range(4)]), bond_types=1,
                      family_names=("fibre",),
                      bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "fibre",
                                                b.axial_stiffness_n)],
                      fibre_yarn=np.ones(4, np.int64), yarns=[Yarn("y", "fibre")],
                      box_lo=np.array([0.0, -0.25 * g, -0.25 * h]),
                      box_hi=np.array([length, 1.75 * g, 1.75 * h]),
                      periodic=(True, True, True))
    return model, b


@pytest.mark.lammps
def test_a_fibre_bundle_compacts_as_the_law_it_implements(tmp_path):
    """LAMMPS virial pressure of a hexagonal bundle of bead chains (transverse, yy and zz)
    against p = √3 k'(d − g)/g: at the law's reference state (s/d 0.5) it is the law's
    pressure at the bundle's Vf; below the second-neighbour onset (3.2 % of d at s/d 0.25)
    both spacings give the same pressure."""
    d = 0.36e-3  # fibres that touch at Vf 0.30: the law's 10 kPa state is 6.7 % overlap
    c = contact_for_yarn(GLASS_BUNDLE, AREA, d, 1e4)
    contact = ContactModel(normal_stiffness_pa=c["normal_stiffness_pa"], friction=0.3)
    for s, share in ((0.5, 1.0), (0.5, 0.45), (0.25, 0.45)):
        g = d * (1 - share * c["reference_overlap_ratio"])
        model, b = hex_bundle(s, g, d)
        dt = 0.25 * b.critical_time_step_s(contact.stability_stiffness_n_per_m([b]))
        text = "\n".join([
            blocks.setup(model, "probe", "model.data", dt), blocks.bonds(model),
            blocks.contact(model, contact, [b]),
            "compute         pv all pressure NULL virial",
            "fix             out all ave/time 1 1 1 c_pv[2] c_pv[3] file p.txt "
            "format ' %.15g'",
            "run             1   # no integrator: the beads stay where they were placed",
            render("finish", final_data="final.data")])
        run_dir = write_run_folder(tmp_path / f"s{s}_{share}", "probe", model, text, {})
        run_folder(Engine(progress=False), run_dir, "probe")
        pyy, pzz = map(float, (run_dir / "p.txt").read_text().split()[-2:])
        expected = bundle_pressure_pa(c["normal_stiffness_pa"], d, g)
        assert pyy == pytest.approx(expected, rel=1e-6)
        assert pzz == pytest.approx(expected, rel=1e-6)
        if share == 1.0:  # at the reference state: the law's own pressure
            vf = bundle_volume_fraction(AREA, g)
            assert pyy == pytest.approx(GLASS_BUNDLE.pressure_pa(vf), rel=1e-6)


def test_scene_contact_table_takes_a_compaction_law():
    import tomllib

    from fabmd.examples_dir import example_scene
    from fabmd.model.fabric_model import family_beads
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"] = {"friction": 0.3,
                       "compaction": {"law": "glass", "reference_pressure_pa": "100 kPa"}}
    scene = parse_scene(data)
    fibre = family_beads(scene.fabric, scene.discretisation)["warp"].fibre
    expected = contact_for_yarn(GLASS_BUNDLE, fibre.area_m2, fibre.diameter_m, 1e5)
    assert scene.contact.normal_stiffness_pa == pytest.approx(expected["normal_stiffness_pa"])
    data["contact"]["normal_stiffness_pa"] = 1e9
    with pytest.raises(InputError, match="not both"):
        parse_scene(data)
    data["contact"] = {"compaction": {"law": "custom", "coefficient": 1e-5,
                                      "modulus_pa": "73 GPa", "vf0": 0.3,
                                      "reference_pressure_pa": "1 kPa"}}
    with pytest.raises(InputError, match=r"\[contact.compaction\].*touch at Vf"):
        parse_scene(data)


def test_the_law_stops_at_the_hexagonal_packing_limit():
    """van Wyk's form has no bound; a bundle of circular fibres cannot pack denser than
    π/(2√3): pressures beyond the law's value there are refused, below they invert."""
    import math

    from fabmd.errors import InputError
    from fabmd.model.compaction import GLASS_BUNDLE, PACKING_LIMIT

    assert PACKING_LIMIT == pytest.approx(0.9069, abs=1e-4)
    top = GLASS_BUNDLE.max_pressure_pa()
    assert GLASS_BUNDLE.volume_fraction(0.999 * top) == pytest.approx(
        (0.999 * top / (GLASS_BUNDLE.coefficient * GLASS_BUNDLE.modulus_pa)
         + GLASS_BUNDLE.vf0**3) ** (1 / 3), rel=1e-12)
    assert GLASS_BUNDLE.volume_fraction(top) == pytest.approx(PACKING_LIMIT, rel=1e-9)
    with pytest.raises(InputError, match="packing limit"):
        GLASS_BUNDLE.volume_fraction(1.01 * top)
    assert not math.isnan(top)
