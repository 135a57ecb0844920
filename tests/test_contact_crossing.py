"""Crossing per crossing: pairs of different families get k_n = 2k'·l0²/d, so that a crossing of
two chains, averaged over their registers, carries 2π·k'·δ²·(1 − δ/d)/sin θ at any bead spacing
(ContactModel docstring, "Crossing per crossing"); the default (per unit length) is unchanged."""

import math
import tomllib

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.contact import (
    ContactModel,
    crossing_force_n,
    crossing_law_force_n,
    default_stiffness_pa,
)

from .test_contact_law import FIBRE, LAW, D, probe

K_LINE = 2e9  # k' [Pa] of the Python sums (any value: the forces scale with it)


def grid_mean(ratio: float, overlap: float, angle: float, crossing: str, n: int = 32) -> float:
    """Mean force [N] of two chains crossing at ``angle`` over an n × n grid of registers."""
    l0 = ratio * D
    shifts = (np.arange(n) + 0.5) / n * l0
    return float(np.mean([crossing_force_n(K_LINE, l0, D, overlap * D, angle, u, v, crossing)
                          for u in shifts for v in shifts]))


def test_per_crossing_is_opt_in_and_needs_type_pair_coefficients():
    assert ContactModel().crossing == "per_length"
    with pytest.raises(InputError, match="contact.crossing = 'per_crossing' needs"):
        ContactModel(crossing="per_crossing")
    with pytest.raises(InputError, match="contact.crossing must be one of"):
        ContactModel(crossing="per_pair", within_family_stiffness_pa=1e6)
    ContactModel(crossing="per_crossing", within_family_stiffness_pa=1e6)
    ContactModel(crossing="per_crossing", within_family_law=LAW)


def test_the_scene_file_takes_the_crossing_form_and_refuses_it_without_a_split():
    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("twintex_plain.toml").read_text())
    assert parse_scene(data).contact.crossing == "per_length"
    data["contact"]["crossing"] = "per_crossing"
    assert parse_scene(data).contact.crossing == "per_crossing"
    del data["contact"]["within_family"]
    with pytest.raises(InputError, match="per_crossing' needs per-type-pair"):
        parse_scene(data)


@pytest.mark.parametrize("ratio", [1.0, 0.5, 0.25])
def test_the_crossing_pair_stiffness_follows_the_spacing_squared(ratio):
    """k_n = 2k'·l0²/d on pairs of different families only; equal to the per-length k'·l0 at
    s/d 0.5; the time step follows it where it is the stiffest pair."""
    b = bead_parameters(FIBRE, Discretisation(ratio))
    per_length = ContactModel(within_family_stiffness_pa=1e6)
    per_crossing = ContactModel(within_family_stiffness_pa=1e6, crossing="per_crossing")
    k_line = default_stiffness_pa([b])
    assert per_length.normal_stiffness_n_per_m([b]) == pytest.approx(k_line * ratio * D)
    assert per_crossing.normal_stiffness_n_per_m([b]) == pytest.approx(
        2 * k_line * (ratio * D) ** 2 / D)
    assert per_crossing.normal_stiffness_n_per_m([b]) == pytest.approx(
        2 * ratio * per_length.normal_stiffness_n_per_m([b]))
    assert per_crossing.within_family_stiffness_n_per_m([b]) == pytest.approx(
        per_length.within_family_stiffness_n_per_m([b]))
    pairs = {(i, j): c["kn"] for i, j, c in per_crossing.type_pair_coefficients([b], 2)}
    assert pairs[1, 2] == pytest.approx(per_crossing.normal_stiffness_n_per_m([b]))
    assert pairs[1, 1] == pairs[2, 2] == pytest.approx(1e6 * ratio * D)
    assert per_crossing.stability_stiffness_n_per_m([b]) == pytest.approx(
        per_crossing.normal_stiffness_n_per_m([b]))
    # with the law, the hard core (k'·l0 per pair, parallel chains) is unchanged
    law_cross = ContactModel(within_family_law=LAW, crossing="per_crossing")
    law_length = ContactModel(within_family_law=LAW)
    assert law_cross.within_family_stiffness_n_per_m([b]) == pytest.approx(
        law_length.within_family_stiffness_n_per_m([b]))


@pytest.mark.parametrize("angle", [90.0, 50.0])
@pytest.mark.parametrize("overlap", [0.05, 0.1, 0.2])
def test_a_crossing_averaged_over_registers_is_a_law_of_the_crossing(angle, overlap):
    """Python sums over a 32 × 32 grid of registers: per crossing, the closed form within 2 %
    at s/d 0.5 and 0.25 (the two within 2 % of each other); per length, the force grows as
    1/l0 (×2 from s/d 0.5 to 0.25: the dependence the new form removes)."""
    law = crossing_law_force_n(K_LINE, D, overlap * D, angle)
    coarse = grid_mean(0.5, overlap, angle, "per_crossing")
    fine = grid_mean(0.25, overlap, angle, "per_crossing")
    assert coarse == pytest.approx(law, rel=0.02)
    assert fine == pytest.approx(law, rel=0.02)
    assert fine == pytest.approx(coarse, rel=0.02)
    ratio = grid_mean(0.25, overlap, angle, "per_length") / grid_mean(
        0.5, overlap, angle, "per_length")
    assert ratio == pytest.approx(2 * fine / coarse, rel=1e-9)  # k_n: ×1/2 vs ×1/4
    assert ratio == pytest.approx(2.0, rel=0.02)


def test_the_crossing_law_in_numbers():
    """2π·k'·δ²·(1 − δ/d)/sin θ; refused outside 0 ≤ δ < d and 0 < θ < 180°."""
    assert crossing_law_force_n(1e9, 1e-3, 1e-4) == pytest.approx(
        2 * math.pi * 1e9 * 1e-8 * 0.9)
    assert crossing_law_force_n(1e9, 1e-3, 1e-4, 30.0) == pytest.approx(
        2 * crossing_law_force_n(1e9, 1e-3, 1e-4))
    with pytest.raises(InputError, match="overlap_m"):
        crossing_law_force_n(1e9, 1e-3, 1e-3)
    with pytest.raises(InputError, match="angle_deg"):
        crossing_law_force_n(1e9, 1e-3, 1e-4, 0.0)


#: registers of the crossings in one probe: an n × n grid of (u, v), fractions of l0
PROBE_GRID = 8
#: the probe's chains reach this far from their crossing point [× d]
CHAIN_REACH = 3.0


def crossings(ratio: float, overlap: float, angle: float):
    """PROBE_GRID² crossings stacked 3 d apart in z: chain A (type 1) along x at z_j, chain B
    (type 2) along (cos θ, sin θ) at z_j + d − δ; crossing j's beads sit at (k + u_j)·l0 and
    (k + v_j)·l0 from the crossing point. Open chains, no periodicity."""
    b = bead_parameters(FIBRE, Discretisation(ratio))
    l0 = b.bond_length_m
    gap = (1 - overlap) * D
    ks = np.arange(-math.ceil(CHAIN_REACH * D / l0), math.ceil(CHAIN_REACH * D / l0) + 1)
    n = len(ks)
    grid = (np.arange(PROBE_GRID) + 0.5) / PROBE_GRID
    registers = [(u, v) for u in grid for v in grid]
    e2 = np.array([math.cos(math.radians(angle)), math.sin(math.radians(angle)), 0.0])
    pos = []
    for j, (u, v) in enumerate(registers):
        z = 3 * D * j
        pos.append(np.column_stack([(ks + u) * l0, np.zeros(n), np.full(n, z)]))
        pos.append(((ks + v) * l0)[:, None] * e2 + np.array([0.0, 0.0, z + gap]))
    chains = 2 * len(registers)
    line = np.column_stack([np.arange(n - 1), np.arange(1, n)])
    reach = (CHAIN_REACH + 2) * D
    model = BeadModel(
        positions=np.vstack(pos), diameters=D, masses=b.mass_kg,
        atom_types=np.tile(np.repeat([1, 2], n), len(registers)),
        fibre_ids=np.repeat(np.arange(1, chains + 1), n),
        bonds=np.vstack([line + i * n for i in range(chains)]), bond_types=1,
        family_names=("warp", "weft"),
        bond_type_table=[BondType(b.bond_coefficient, l0, "fibre", b.axial_stiffness_n)],
        fibre_yarn=np.tile([1, 2], len(registers)), yarns=[Yarn("a", "warp"), Yarn("b", "weft")],
        box_lo=np.array([-reach, -reach, -2 * D]),
        box_hi=np.array([reach, reach, 3 * D * len(registers) + 2 * D]),
        periodic=(False, False, False))
    return model, b, registers


# z force on the upper chains (type 2) and the pair energy
FORCE_Z = ["group           upper type 2",
           "compute         fz upper reduce sum fz",
           "compute         epair all pe pair",
           "fix             out all ave/time 1 1 1 c_fz c_epair file out.txt format ' %.15g'"]


@pytest.mark.lammps
def test_lammps_crossings_carry_the_same_force_at_either_spacing(tmp_path):
    """One step, no integrator: 64 crossings (8 × 8 registers) of two open chains, of two
    families, with the glass within-family law (the Twintex example's contact). Per crossing:
    LAMMPS sums what Python sums for the same registers (1e-6), the mean is the closed form
    and s/d 0.25 carries what s/d 0.5 carries (≤ 2 %), at 90° and 50°. Default (per length):
    unchanged, k_n = k'·l0, so the mean force doubles from s/d 0.5 to 0.25."""
    overlap = 0.1
    mean = {}
    for crossing in ("per_crossing", "per_length"):
        contact = ContactModel(friction=0.3, within_family_law=LAW, crossing=crossing)
        for angle in (90.0, 50.0) if crossing == "per_crossing" else (90.0,):
            for ratio in (0.5, 0.25):
                model, b, registers = crossings(ratio, overlap, angle)
                k_line = contact.crossing_stiffness_pa([b])
                fz, _ = probe(tmp_path, f"{crossing}_{angle:g}_{ratio}", model, contact, b,
                              FORCE_Z)
                python = sum(crossing_force_n(
                    k_line, b.bond_length_m, D, overlap * D, angle, u * b.bond_length_m,
                    v * b.bond_length_m, crossing) for u, v in registers)
                assert fz == pytest.approx(python, rel=1e-6), (crossing, angle, ratio)
                mean[crossing, angle, ratio] = fz / len(registers)
                if crossing == "per_crossing":
                    assert mean[crossing, angle, ratio] == pytest.approx(
                        crossing_law_force_n(k_line, D, overlap * D, angle), rel=0.02)
    for angle in (90.0, 50.0):
        assert mean["per_crossing", angle, 0.25] == pytest.approx(
            mean["per_crossing", angle, 0.5], rel=0.02)
    assert mean["per_crossing", 90.0, 0.5] == pytest.approx(
        mean["per_length", 90.0, 0.5], rel=1e-9)  # the two forms agree at s/d 0.5
    assert mean["per_length", 90.0, 0.25] / mean["per_length", 90.0, 0.5] == pytest.approx(
        2.0, rel=0.02)


def test_crossing_friction_sets_mu_of_the_crossings_only():
    """``crossing_friction``: μ of pairs of different families; ``friction`` stays within a
    family; refused without per-type-pair coefficients or below 0."""
    b = bead_parameters(FIBRE, Discretisation(0.5))
    contact = ContactModel(friction=0.3, crossing_friction=0.0, within_family_law=LAW)
    mus = {(i, j): c["friction"] for i, j, c in contact.type_pair_coefficients([b], 2)}
    assert mus == {(1, 1): 0.3, (1, 2): 0.0, (2, 2): 0.3}
    default = ContactModel(friction=0.3, within_family_law=LAW)
    assert {c["friction"] for _, _, c in default.type_pair_coefficients([b], 2)} == {0.3}
    with pytest.raises(InputError, match="contact.crossing_friction needs per-type-pair"):
        ContactModel(crossing_friction=0.1)
    with pytest.raises(InputError, match="contact.crossing_friction"):
        ContactModel(crossing_friction=-0.1, within_family_law=LAW)


def test_the_scene_file_takes_the_crossing_friction_into_the_pair_coefficients():
    from fabmd.examples_dir import example_scene
    from fabmd.model.beads import model_bead_parameters
    from fabmd.scene.blocks import contact
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("twintex_plain.toml").read_text())
    data["contact"]["crossing_friction"] = 0.1
    scene = parse_scene(data)
    assert scene.contact.crossing_friction == 0.1
    model = scene.model(check=False)
    text = contact(model, scene.contact, model_bead_parameters(model))
    lines = [ln.split() for ln in text.splitlines() if ln.startswith("pair_coeff")
             and "granular" in ln]
    mu = {(ln[1], ln[2]): float(ln[ln.index("linear_history") + 3]) for ln in lines}
    assert mu == {("1", "1"): 0.3, ("1", "2"): 0.1, ("2", "2"): 0.3}
