"""The contacts' elastic energy U_c (fabmd.scene.energy.ContactEnergy) and its place in the
quasi-static verdict: KE/U with U = bonds + contacts (issue 16, stop 20)."""

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.contact import ContactModel, default_stiffness_pa
from fabmd.protocols.common import run_folder, write_run_folder
from fabmd.protocols.driven import DrivenResult
from fabmd.protocols.driven_outputs import Outputs, kinetic_ratio, kinetic_to_work_ratio
from fabmd.protocols.verdict import add_interval_verdict
from fabmd.scene import blocks
from fabmd.scene.energy import ContactEnergy, ContactPower, balance
from fabmd.scene.templates import render

from .test_contact_law import (
    FIBRE,
    LAW,
    PAIR_REGISTERS,
    D,
    beads_for,
    law_contact,
    pairs_in_registers,
)


def sample_energy(tmp_path, name, model, contact, b) -> float:
    """U_c [J] of ``model`` as placed (one step without an integrator), sampled by the
    driven runs' monitor."""
    dt = 0.25 * b.critical_time_step_s(contact.stability_stiffness_n_per_m([b]))
    monitor = ContactPower(contact.pair_style(),
                           ContactEnergy.for_contact(contact, [b], model.family_names))
    text = "\n".join([
        blocks.setup(model, "probe", "model.data", dt), blocks.bonds(model),
        blocks.contact(model, contact, [b]), ContactPower.commands(contact.pair_style()),
        ContactEnergy.commands(),
        "run             1   # no integrator: the beads stay where they were placed",
        render("finish", final_data="final.data")])
    run_dir = write_run_folder(tmp_path / name, "probe", model, text, {},
                               files=blocks.contact_files(contact, [b]))
    run_folder(Engine(progress=False), run_dir, "probe", monitor=monitor, monitor_every=1)
    assert monitor.steps == [1]
    return monitor.energy_j[0]


def law_energy_per_length(r: float, k_cross: float) -> float:
    """Closed form: ∫ q dδ of the law's line force from touching (h = d) to h = r [J/m]."""
    h = np.linspace(r, D, 4001)
    q = LAW.line_force_n_per_m(h, k_cross)
    return float(np.sum(0.5 * (q[1:] + q[:-1]) * np.diff(h)))


@pytest.mark.lammps
def test_two_parallel_fibres_hold_the_laws_energy_per_unit_length(tmp_path):
    """Pressed δ together, averaged over 16 registers: U_c (the granular linear part's
    ½k_nδ² plus the table's energy) is the law's ∫q dδ per unit length × length (≤ 2 %),
    at s/d 0.5 and 0.25."""
    k_cross = default_stiffness_pa([beads_for(0.5, 2 * D)[0]])
    for delta in (0.2, 0.33):
        r = (1 - delta) * D
        expected = law_energy_per_length(r, k_cross) * 2 * D * len(PAIR_REGISTERS)
        for ratio in (0.5, 0.25):
            model, b = pairs_in_registers(r, ratio)
            u = sample_energy(tmp_path, f"pairs_{delta}_{ratio}", model, law_contact(), b)
            assert u == pytest.approx(expected, rel=0.02), (delta, ratio)  # measured: ≤ 1e-4


def crossing(delta: float, types=(1, 2)):
    """Two straight fibres crossing at 90°, one along x, one along y above it, their axes
    (1 − δ)·d apart (not periodic)."""
    b = bead_parameters(FIBRE, Discretisation(0.5))
    n = 9
    s = b.bond_length_m * (np.arange(n) - (n - 1) / 2 + 0.3)  # off register: many overlaps
    gap = (1 - delta) * D
    pos = np.vstack([np.column_stack([s, np.zeros(n), np.zeros(n)]),
                     np.column_stack([np.zeros(n), s + 0.1 * b.bond_length_m,
                                      np.full(n, gap)])])
    chain = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    half = n * b.bond_length_m
    model = BeadModel(positions=pos, diameters=D, masses=b.mass_kg,
                      atom_types=np.repeat(np.asarray(types), n),
                      fibre_ids=np.repeat([1, 2], n), bonds=np.vstack([chain, chain + n]),
                      bond_types=1, family_names=("warp", "weft")[:max(types)],
                      bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "fibre",
                                                b.axial_stiffness_n)],
                      fibre_yarn=np.array([1, 2]) if max(types) == 2 else np.ones(2, int),
                      yarns=[Yarn("a", "warp"), Yarn("b", "weft")] if max(types) == 2
                      else [Yarn("a", "warp")],
                      box_lo=np.array([-half, -half, -2 * D]),
                      box_hi=np.array([half, half, 3 * D]), periodic=(False, False, False))
    return model, b, pos, n


def hand_sum(pos, n, kn) -> float:
    """Σ ½·k_n·(d − r)² over the bead pairs of the two fibres closer than d."""
    r = np.linalg.norm(pos[:n, None, :] - pos[None, n:, :], axis=2)
    pen = np.clip(D - r, 0.0, None)
    assert np.count_nonzero(pen) >= 4  # several bead pairs overlap
    return float(np.sum(0.5 * kn * pen**2))


@pytest.mark.lammps
def test_a_crossing_holds_half_kn_delta_squared_per_pair(tmp_path):
    """A crossing of two families (the law's crossing stiffness, no table energy), the
    same crossing with the plain Hooke contact (gran/hooke/history) and with the split
    contact (granular, per type pair): U_c = Σ ½k_nδ² with the pair's own k_n."""
    model, b, pos, n = crossing(0.15)
    contact = law_contact()
    kn = contact.normal_stiffness_n_per_m([b])
    u = sample_energy(tmp_path, "law", model, contact, b)
    assert u == pytest.approx(hand_sum(pos, n, kn), rel=1e-9)
    plain = ContactModel(friction=0.3)
    model1, b1, pos1, _ = crossing(0.15, types=(1, 1))
    u1 = sample_energy(tmp_path, "hooke", model1, plain, b1)
    assert plain.pair_style() == "gran/hooke/history"
    assert u1 == pytest.approx(hand_sum(pos1, n, plain.normal_stiffness_n_per_m([b1])),
                               rel=1e-9)
    # the split contact (pair_style granular, per type pair): crossing and same-family k_n
    split = ContactModel(friction=0.3, within_family_stiffness_pa=1e6)
    assert split.pair_style() == "granular"
    u2 = sample_energy(tmp_path, "split_cross", model, split, b)
    assert u2 == pytest.approx(hand_sum(pos, n, split.normal_stiffness_n_per_m([b])), rel=1e-9)
    u3 = sample_energy(tmp_path, "split_same", model1, split, b1)
    assert u3 == pytest.approx(hand_sum(pos1, n, split.within_family_stiffness_n_per_m([b1])),
                               rel=1e-9)


def test_hertz_energy_is_the_integral_of_its_force():
    k = np.array([[0.0, 0.0], [0.0, 7.0]])
    e = ContactEnergy(k, hertz=True)
    delta = np.linspace(0, 1e-5, 2001)
    r = 1e-4
    force = k[1, 1] * delta * np.sqrt(delta * r * r / (2 * r))  # LAMMPS's hertz force
    work = np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(delta))
    assert e.pair_energy_j(delta[-1], r, r, 1, 1) == pytest.approx(work, rel=1e-6)


def test_the_contact_model_sets_kn_per_type_pair():
    b = beads_for(0.5, 2 * D)[0]
    c = law_contact()
    e = ContactEnergy.for_contact(c, [b], ("warp", "weft"))
    assert e.stiffness[1, 2] == e.stiffness[2, 1] == pytest.approx(
        c.normal_stiffness_n_per_m([b]))
    assert e.stiffness[1, 1] == pytest.approx(c.within_family_stiffness_n_per_m([b]))
    assert ContactEnergy.for_contact(ContactModel(), [b], ("warp",)).stiffness[1, 1] == \
        pytest.approx(ContactModel().normal_stiffness_n_per_m([b]))


# -- the verdict: KE/U with U = bonds + contacts ------------------------------------------
def curve(contact: bool) -> dict:
    """A curve whose fabric holds 9/10 of its elastic energy in the contacts: KE/U is 0.5
    against the bonds alone and 0.05 against bonds + contacts."""
    x = np.linspace(0, 20, 41)
    u_bonds = 1e-3 * (1 + x)
    c = {"x": x, "external_work_j": 1.0 * x, "damping_dissipation_j": 1e-3 * x,
         "kinetic_energy_j": 0.5 * u_bonds, "strain_energy_j": u_bonds}
    if contact:
        c["contact_energy_j"] = 9 * u_bonds
    return c


def test_the_interval_verdict_counts_the_contact_energy(tmp_path):
    result = DrivenResult(tmp_path, curve(contact=True), {})
    verdict = add_interval_verdict(result, "x", 5.0)
    assert [i["kinetic_to_strain_energy"] for i in verdict["intervals"]] == \
        pytest.approx([0.05] * 4)
    assert verdict["flagged"] == [] and verdict["trusted"] == [[0.0, 20.0]]
    bonds_only = add_interval_verdict(DrivenResult(tmp_path, curve(contact=False), {}),
                                      "x", 5.0)
    assert bonds_only["flagged"] == [[0.0, 20.0]]  # a standalone run: bonds only


def test_the_whole_run_ratio_and_the_balance_count_the_contact_energy():
    c = curve(contact=True)
    out = Outputs({"kinetic_j": c["kinetic_energy_j"], "strain_energy_j": c["strain_energy_j"]},
                  {}, c["external_work_j"], c["damping_dissipation_j"], None,
                  c["contact_energy_j"])
    assert kinetic_ratio(out, np.ones(41, bool)) == pytest.approx(0.05)
    one = np.array([0.0, 1.0])
    terms = balance(one, 0.2 * one, 0.1 * one, 0.1 * one, 0.6 * one, 0.5 * one)
    assert terms["contact_energy_change_j"] == pytest.approx(0.5)
    assert terms["contact_dissipation_j"] == pytest.approx(0.1)
    assert terms["relative_error"] == pytest.approx(0.0)  # the split changes no closing


# -- KE relative to the tools' affine field ---------------------------------------------
def test_ke_over_u_takes_the_kinetic_energy_relative_to_the_affine_field(tmp_path):
    """A fabric carried along by the frame: its absolute KE is the carriage (KE/U 0.5 with
    contacts), its KE relative to the frame's field 1 % of that; KE/U reads the relative
    one, the inertia share keeps the absolute one (what the tools pay for)."""
    c = curve(contact=True)
    c["kinetic_relative_j"] = 0.01 * c["kinetic_energy_j"]
    c["kinetic_energy_j"] = 10 * c["kinetic_energy_j"]
    verdict = add_interval_verdict(DrivenResult(tmp_path, c, {}), "x", 5.0)
    assert [i["kinetic_to_strain_energy"] for i in verdict["intervals"]] == \
        pytest.approx([0.0005] * 4)
    dke = np.interp([0, 5], c["x"], c["kinetic_energy_j"])
    assert verdict["intervals"][0]["inertia_share"] == pytest.approx(np.diff(dke)[0] / 5)
    out = Outputs({"kinetic_j": c["kinetic_energy_j"], "strain_energy_j": c["strain_energy_j"],
                   "kinetic_relative_j": c["kinetic_relative_j"]}, {}, c["external_work_j"],
                  c["damping_dissipation_j"], None, c["contact_energy_j"])
    assert kinetic_ratio(out, np.ones(41, bool)) == pytest.approx(0.0005)
    started = c["x"] > 0
    ratio = c["kinetic_relative_j"][started] / c["external_work_j"][started]
    assert kinetic_to_work_ratio(out, started) == pytest.approx(ratio.max())


@pytest.mark.lammps
def test_the_picture_frame_prints_the_relative_kinetic_energy(tmp_path):
    """A 4 mm picture frame of the test plain weave: the curve carries
    ``kinetic_relative_j`` and the summary's KE/U comes from it and from U_c; the fabric
    follows the frame, so its KE relative to the frame's field is a small part of its KE."""
    import warnings

    from fabmd.errors import QuasiStaticWarning
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.picture_frame import PictureFrame

    from .fabrics import plain_weave_cell

    engine = Engine(progress=False)
    coupon = Coupon(length_m=4e-3, width_m=4e-3, relax=None).run(
        plain_weave_cell(spacing_m=1e-3, gap=1.0), tmp_path / "coupon", engine=engine).model
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", QuasiStaticWarning)
        r = PictureFrame(max_shear_angle_deg=30, samples=40).run(coupon, tmp_path / "pf",
                                                                 engine=engine)
    c = r.curve
    assert "variable        ke_rel_atom atom" in (r.run_dir / "in.picture_frame").read_text()
    mid = (c["shear_angle_deg"] > 10) & (c["shear_angle_deg"] < 25)
    assert np.all(c["kinetic_relative_j"][mid] < 0.2 * c["kinetic_energy_j"][mid])
    # sampled at every output step (a loose fabric may start without an overlap)
    assert np.all(c["contact_energy_j"] >= 0) and c["contact_energy_j"][-1] > 0
    assert "contacts' elastic energy" in r.summary["elastic_energy"]
    assert "affine" in r.summary["kinetic_energy"]
    u_all = c["strain_energy_j"] + c["contact_energy_j"]
    for iv in r.summary["quasi_static_intervals"]["intervals"]:
        u = max(np.interp(iv["to"], c["shear_angle_deg"], u_all), 0.01 * u_all.max())
        ke = np.interp(iv["to"], c["shear_angle_deg"], c["kinetic_relative_j"])
        assert iv["kinetic_to_strain_energy"] >= ke / u * (1 - 1e-9)
