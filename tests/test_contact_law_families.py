"""The within-family law with one table section per family: families whose virtual fibres
have different diameters (the Twintex twill: 0.497 / 0.413 mm) each follow the stated
law per unit length on their own fibre (fabmd.model.bundle_contact.law_sections)."""

import tomllib

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.bundle_contact import BundleContact
from fabmd.model.compaction import GLASS_BUNDLE
from fabmd.model.contact import WITHIN_FAMILY_TABLE, ContactModel, default_stiffness_pa
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.common import run_folder, write_run_folder
from fabmd.scene import blocks
from fabmd.scene.templates import render

# one virtual fibre of a 600 tex glass yarn of 7 (warp, the plain weave's d) and of 3 (weft)
AREA = {"warp": 600e-6 / 2540 / 7, "weft": 600e-6 / 2540 / 3}
D = {"warp": 0.333e-3, "weft": 0.533e-3}
LAWS = {f: BundleContact(GLASS_BUNDLE, AREA[f], D[f]) for f in D}
FAMILIES = tuple(LAWS.items())
#: registers of the fibre pairs (16: their mean is the force per length of two fibres)
REGISTERS = np.arange(16) / 16
#: the periodic length along the fibres [m]: a whole number of beads of either family
LENGTH = 4 * D["warp"]


def two_family_contact(**kw) -> ContactModel:
    return ContactModel(friction=0.3, within_family_law=LAWS["warp"],
                        within_family_laws=FAMILIES, **kw)


def family_beads(family: str, spacing_ratio: float = 0.5):
    fibre = VirtualFibre(GLASS, AREA[family], D[family])
    n = round(LENGTH / (spacing_ratio * D[family]))
    return bead_parameters(fibre, Discretisation(spacing_ratio), bond_length_m=LENGTH / n), n


def pairs_of_both_families(delta: float, spacing_ratio: float = 0.5):
    """16 pairs of parallel fibres per family (type 1 warp, 2 weft) along x, each pair's
    axes (1 − ``delta``)·d of its family apart along y, the second fibre of pair j at
    register j/16; pairs stacked 3 d_max apart in z. Returns the model, the beads of
    each family, and the molecule ids of each family's second fibres."""
    beads, pos, diam, mass, types, mols, bonds, btypes = {}, [], [], [], [], [], [], []
    second = {"warp": [], "weft": []}
    gap_z = 3 * max(D.values())
    fibre = 0
    for t, family in enumerate(("warp", "weft"), start=1):
        b, n = family_beads(family, spacing_ratio)
        beads[family] = b
        r = (1 - delta) * D[family]
        for j, u in enumerate(REGISTERS):
            z = gap_z * (j + len(REGISTERS) * (t - 1))
            for y, shift in ((0.0, 0.0), (r, u)):
                fibre += 1
                start = len(pos)
                pos += [[b.bond_length_m * (k + shift), y, z] for k in range(n)]
                diam += [D[family]] * n
                mass += [b.mass_kg] * n
                types += [t] * n
                mols += [fibre] * n
                bonds += [[start + k, start + (k + 1) % n] for k in range(n)]
                btypes += [t] * n
                if y > 0:
                    second[family].append(fibre)
    table = [BondType(beads[f].bond_coefficient, beads[f].bond_length_m, f,
                      beads[f].axial_stiffness_n) for f in ("warp", "weft")]
    top = gap_z * 2 * len(REGISTERS)
    model = BeadModel(positions=np.array(pos), diameters=np.array(diam), masses=np.array(mass),
                      atom_types=np.array(types), fibre_ids=np.array(mols),
                      bonds=np.array(bonds), bond_types=np.array(btypes),
                      family_names=("warp", "weft"), bond_type_table=table,
                      fibre_yarn=np.ones(fibre, np.int64), yarns=[Yarn("y", "warp")],
                      box_lo=np.array([0.0, -2 * max(D.values()), -gap_z]),
                      box_hi=np.array([LENGTH, 3 * max(D.values()), top]),
                      periodic=(True, False, False))
    return model, beads, second


def probe(tmp_path, name, model, contact, beads: list, measure: list[str]):
    """One step without an integrator (the beads stay put), with the overlap monitor; the
    values written to out.txt and the overlap monitor's pair overlap."""
    dt = 0.25 * min(b.critical_time_step_s(contact.stability_stiffness_n_per_m(beads))
                    for b in beads)
    text = "\n".join([
        blocks.setup(model, "probe", "model.data", dt), blocks.bonds(model),
        blocks.contact(model, contact, beads), *measure,
        blocks.overlap_monitor(model, contact, beads, every=1),
        "run             1   # no integrator: the beads stay where they were placed",
        render("finish", final_data="final.data")])
    run_dir = write_run_folder(tmp_path / name, "probe", model, text, {},
                               files=blocks.contact_files(contact, beads))
    run_folder(Engine(progress=False), run_dir, "probe")
    values = [float(v) for v in (run_dir / "out.txt").read_text().split()[-2:]]
    overlap = np.loadtxt(run_dir / "overlap.dat", ndmin=2)[-1, 1]
    return values, overlap


def force_on(molecules: list[int], tag: str) -> list[str]:
    """y force summed over the atoms of ``molecules`` (consecutive ids, step 2)."""
    return [f"group           {tag} molecule {molecules[0]}:{molecules[-1]}:2",
            f"compute         fy_{tag} {tag} reduce sum fy"]


def test_each_family_gets_its_own_table_section_and_linear_part():
    contact = two_family_contact()
    model, beads, _ = pairs_of_both_families(0.1)
    bl = [beads["warp"], beads["weft"]]
    text = blocks.contact(model, contact, bl)
    assert "pair_coeff      1 1 table within_family.table WITHIN_FAMILY_WARP" in text
    assert "pair_coeff      2 2 table within_family.table WITHIN_FAMILY_WEFT" in text
    table = blocks.contact_files(contact, bl)[WITHIN_FAMILY_TABLE]
    for f in ("warp", "weft"):  # each section at its own d and bead spacing
        assert f"\nWITHIN_FAMILY_{f.upper()}\nN 4000 R " in table
        assert f"{LAWS[f].table_end_text}\n" in table.split(f"WITHIN_FAMILY_{f.upper()}")[1]
        assert f"l0 = {beads[f].bond_length_m:.6g} m" in table
    k_cross = default_stiffness_pa(bl)
    coeffs = {(i, j): c for i, j, c in contact.type_pair_coefficients(bl, 2, ("warp", "weft"))}
    for t, f in ((1, "warp"), (2, "weft")):
        assert coeffs[t, t]["kn"] == pytest.approx(LAWS[f].linear_pair_stiffness_n_per_m(
            beads[f].bond_length_m, k_cross), rel=1e-12)
    assert coeffs[1, 1]["kn"] != pytest.approx(coeffs[2, 2]["kn"], rel=0.01)
    # the time step: the steepest pair of either section
    steepest = max(LAWS[f].max_pair_stiffness_n_per_m(beads[f].bond_length_m, k_cross)
                   for f in LAWS)
    assert contact.stability_stiffness_n_per_m(bl) >= steepest
    # one family's fibres at another diameter than its law's: refused before LAMMPS
    wrong = ContactModel(friction=0.3, within_family_law=LAWS["warp"],
                         within_family_laws=(("warp", LAWS["warp"]), ("weft", LAWS["warp"])))
    with pytest.raises(InputError, match="weft fibres need the law's bead diameter"):
        blocks.contact(model, wrong, bl)
    with pytest.raises(InputError, match="each entry must be"):
        ContactModel(within_family_law=LAWS["warp"], within_family_laws=(("warp", 1.0),))
    with pytest.raises(InputError, match="needs within_family_law"):
        ContactModel(within_family_laws=FAMILIES)


def test_a_fabric_of_two_fibre_diameters_renders_with_one_section_per_family():
    """The plain weave with 7 warp and 3 weft fibres per yarn (d 0.333 / 0.533 mm) and the
    law: the crimp input renders (was "needs one bead diameter")."""
    from fabmd import pipeline
    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"] = {"friction": 0.3, "within_family": {"law": "glass", "form": "law"}}
    data["yarns"]["weft"]["n_fibres"] = 3
    scene = parse_scene(data)
    laws = dict(scene.contact.within_family_laws)
    assert laws["warp"].diameter_m == pytest.approx(0.3326e-3, rel=1e-3)
    assert laws["weft"].diameter_m == pytest.approx(0.5333e-3, rel=1e-3)
    assert laws["warp"].law == laws["weft"].law == GLASS_BUNDLE
    text = pipeline.crimp_stage(scene).input_text(pipeline.periodic_cell(scene))
    assert "table within_family.table WITHIN_FAMILY_WARP" in text
    assert "table within_family.table WITHIN_FAMILY_WEFT" in text
    assert "group           fabmd_family_2 type 2" in text  # each family's own overlaps


def test_one_diameter_keeps_one_section():
    """Families with the same fibre: the one section of before (inputs byte-identical)."""
    same = ContactModel(friction=0.3, within_family_law=LAWS["warp"],
                        within_family_laws=(("warp", LAWS["warp"]), ("weft", LAWS["warp"])))
    b, _ = family_beads("warp")
    sections = same.law_sections([b])
    assert [s.keyword for s in sections] == ["WITHIN_FAMILY"]
    alone = ContactModel(friction=0.3, within_family_law=LAWS["warp"])
    assert same.table_files([b]) == alone.table_files([b])


@pytest.mark.lammps
@pytest.mark.parametrize("delta", [0.1, 0.25, 0.45])
def test_each_family_carries_the_law_per_unit_length(tmp_path, delta):
    """Two families of different fibre diameters in one model, each as 16 pairs of parallel
    fibres pressed (``delta``·d of its own; 0.45 past the law's hard core): below the core
    the mean force per unit length of each family is the law's line force on its own fibre
    within 1 %; the overlap monitor reads the larger of the two families' overlaps past the
    hard core from distances (exact: 0 before the core)."""
    contact = two_family_contact()
    model, beads, second = pairs_of_both_families(delta)
    measure = [*force_on(second["warp"], "w"), *force_on(second["weft"], "f"),
               "fix             out all ave/time 1 1 1 c_fy_w c_fy_f file out.txt "
               "format ' %.15g'"]
    (fy_warp, fy_weft), overlap = probe(tmp_path, f"pairs_{delta}", model, contact,
                                        [beads["warp"], beads["weft"]], measure)
    k_cross = default_stiffness_pa([beads["warp"], beads["weft"]])
    for family, fy in (("warp", fy_warp), ("weft", fy_weft)):
        if delta > 0.4:  # past the core its force is per pair (bumpy like a crossing)
            break
        q_law = LAWS[family].line_force_n_per_m((1 - delta) * D[family], k_cross)
        per_length = fy / LENGTH / len(REGISTERS)
        assert per_length == pytest.approx(q_law, rel=0.01), family
    past_core = [max(0.0, 1 - (1 - delta) * D[f] / LAWS[f].core_spacing_m(k_cross)) for f in D]
    # (the crossings' part, from the largest pair force, reads the law's pairs as < 1e-5)
    assert overlap == pytest.approx(max(past_core), rel=1e-6, abs=1e-5)
    assert (overlap > 0.05) == (delta > 0.4)


@pytest.mark.lammps
def test_a_two_diameter_cell_crimps_with_the_law(tmp_path):
    """The plain weave with 7 warp / 3 weft fibres per yarn (0.333 / 0.533 mm) and the law,
    crimped at −7 % (~10 s): both sections in the run folder's table, quasi-static, no
    pass-through, and no overlap warning: the law's pairs close to its hard core (0.388 d
    of raw overlap, measured) by design, and the monitor counts only what passes it."""
    import warnings

    from fabmd.errors import OverlapWarning
    from fabmd.examples_dir import example_scene
    from fabmd.pipeline import run_crimp
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    data["contact"] = {"friction": 0.3, "within_family": {"law": "glass", "form": "law"}}
    data["yarns"]["weft"]["n_fibres"] = 3
    data["crimp"] = {"expansion": {"warp": -0.07, "weft": -0.07}}
    with warnings.catch_warnings():
        warnings.simplefilter("error", OverlapWarning)
        result = run_crimp(parse_scene(data), tmp_path / "crimp",
                           Engine(progress=False, ranks=1), form="cell")
    table = (tmp_path / "crimp" / WITHIN_FAMILY_TABLE).read_text()
    assert "\nWITHIN_FAMILY_WARP\n" in table and "\nWITHIN_FAMILY_WEFT\n" in table
    s = result.summary
    assert s["quasi_static"] and s["pass_through"]["flipped_pairs"] == 0
    assert s["overlap"]["max_overlap_ratio"] < 0.1 and not s["overlap"]["warnings"]
