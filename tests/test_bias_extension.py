"""Bias extension: closed-form kinematics, the fibre-angle measure, and a small braced
trellis net (seconds).

The tiny single-fibre plain weaves of ``tests/fabrics.py`` cannot carry a bias-extension
test: their yarns have no bending stiffness and no normal force at the crossings once
cut free, so the clamped fibres slide out and the centre does not shear. The LAMMPS
check therefore uses a net whose crossings are pinned and braced (a small shear
stiffness) and whose fibres resist bending: the textbook trellis.
"""

import dataclasses
import math

import numpy as np
import pytest

import fabmd
from fabmd.analysis import FabricFrame, zone_shear_angle_deg
from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.bead_model import AngleType, BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.material import VirtualFibre
from fabmd.protocols.bias_extension import (
    BiasExtension,
    bias_displacement_m,
    bias_shear_angle_deg,
)

from .fabrics import SOFT_GLASS, parallel_fibres


def braced_bias_net(length_m=14e-3, width_m=5e-3, spacing_m=1e-3, diameter_m=0.5e-3,
                    beads_per_spacing=4, brace=0.02, bending=0.02, layer_gap=0.7):
    """Straight warp at +45° over straight weft at −45° (layers ``layer_gap``·d apart),
    pinned at every crossing by a bond, braced by four short bonds from the crossing's
    neighbouring warp beads to its neighbouring weft beads, with bending terms along
    every fibre; cut to length × width with the length along x."""
    fibre = VirtualFibre.solid(SOFT_GLASS, diameter_m)
    l0 = spacing_m / beads_per_spacing
    b = bead_parameters(fibre, Discretisation(), bond_length_m=l0)
    h = layer_gap * diameter_m
    u = np.array([1.0, 1.0]) / math.sqrt(2)
    v = np.array([-1.0, 1.0]) / math.sqrt(2)
    reach = int(math.ceil((length_m + width_m) / spacing_m)) + 2
    pos, types, fib, bonds, btypes, yarns, key, angles = [], [], [], [], [], [], {}, []
    for fam, a, c, z in (("warp", u, v, h / 2), ("weft", v, u, -h / 2)):
        for j in range(-reach, reach + 1):
            chain = [(n, n * l0 * a + j * spacing_m * c)
                     for n in range(-reach * beads_per_spacing, reach * beads_per_spacing + 1)]
            chain = [(n, xy) for n, xy in chain
                     if abs(xy[0]) <= length_m / 2 and abs(xy[1]) <= width_m / 2]
            if len(chain) < 2:
                continue
            ids = list(range(len(pos), len(pos) + len(chain)))
            for (n, xy), i in zip(chain, ids, strict=True):
                key[(fam, j, n)] = i
                pos.append([xy[0], xy[1], z])
            types += [1 if fam == "warp" else 2] * len(ids)
            fib += [len(yarns) + 1] * len(ids)
            bonds += list(zip(ids[:-1], ids[1:], strict=True))
            btypes += [1 if fam == "warp" else 2] * (len(ids) - 1)
            angles += [ids[k:k + 3] for k in range(len(ids) - 2)]
            yarns.append(Yarn(f"{fam}-{j}", fam))
    bps = beads_per_spacing
    for (fam, j, n), i in list(key.items()):
        partner = key.get(("weft", n // bps, j * bps)) if fam == "warp" and n % bps == 0 \
            else None
        if partner is None:
            continue
        bonds.append((i, partner))
        btypes.append(3)
        for sw in (-1, 1):
            for sf in (-1, 1):
                w, f = key.get(("warp", j, n + sw)), key.get(("weft", n // bps, j * bps + sf))
                if w is not None and f is not None:
                    bonds.append((w, f))
                    btypes.append(4)
    brace_len = math.sqrt(2 * l0**2 + h**2)
    ea = b.axial_stiffness_n
    table = [BondType(b.bond_coefficient, l0, "warp", ea),
             BondType(b.bond_coefficient, l0, "weft", ea),
             BondType(ea / (2 * h), h, "warp", ea),
             BondType(brace * ea / (2 * brace_len), brace_len, "weft", brace * ea)]
    ei = bending * SOFT_GLASS.modulus_pa * math.pi * diameter_m**4 / 64
    pos = np.asarray(pos)
    types = np.asarray(types)
    return BeadModel(
        positions=pos, diameters=diameter_m, masses=b.mass_kg, atom_types=types,
        fibre_ids=fib, bonds=bonds, bond_types=btypes, family_names=("warp", "weft"),
        bond_type_table=table, fibre_yarn=np.arange(1, len(yarns) + 1), yarns=yarns,
        angles=angles, angle_types=types[[a[1] for a in angles]],
        angle_type_table=[AngleType(ei / l0, "warp"), AngleType(ei / l0, "weft")],
        box_lo=pos.min(axis=0) - 2 * diameter_m, box_hi=pos.max(axis=0) + 2 * diameter_m)


# -- closed form (no LAMMPS) ---------------------------------------------------------------
@pytest.mark.parametrize("gamma", [0.0, 10.0, 30.0, 55.0])
def test_central_zone_kinematics(gamma):
    """Zone A is a rhombus of inextensible fibres whose x diagonal is L0 at the start."""
    free, width = 0.2, 0.08
    l0 = free - width
    side = l0 / math.sqrt(2)
    theta = math.radians(45 - gamma / 2)  # fibre angle to the load axis
    d = 2 * side * math.cos(theta) - l0  # x diagonal grows by d
    assert bias_shear_angle_deg(d, free, width) == pytest.approx(gamma, abs=1e-9)
    assert bias_displacement_m(gamma, free, width) == pytest.approx(d, abs=1e-12)


def test_fibre_angle_measure_reads_an_affine_trellis():
    net = braced_bias_net(bending=0.0)
    gamma = math.radians(24.0)
    # trellis of fibres at ±45° stretched along x: x' = F x with F = R(45°) S R(−45°)
    phi = gamma / 2
    f = np.array([[math.cos(phi) + math.sin(phi), 0], [0, math.cos(phi) - math.sin(phi)]])
    moved = net.positions.copy()
    moved[:, :2] = net.positions[:, :2] @ f.T
    start = FabricFrame.from_model(net)
    sheared = dataclasses.replace(start, positions=moved)
    assert zone_shear_angle_deg(start, reference_deg=0.0) == pytest.approx(0, abs=1e-9)
    assert zone_shear_angle_deg(sheared, reference_deg=0.0) == pytest.approx(24.0, abs=1e-6)
    # and a picture frame's shear seen from its pulled diagonal
    assert zone_shear_angle_deg(sheared, reference_deg=90.0) == pytest.approx(-24.0, abs=1e-6)
    # a zone: only segments with both beads in it count; an empty zone has no angle
    nowhere = np.zeros(net.n_beads, bool)
    assert zone_shear_angle_deg(sheared, nowhere, reference_deg=0.0) is None


def test_short_or_unbiased_coupons_are_refused():
    net = braced_bias_net(length_m=9e-3)
    with pytest.raises(InputError, match="at least twice the width"):
        BiasExtension().prepare(net)
    with pytest.raises(InputError, match="angle_deg=45"):
        BiasExtension(clamp_length_m=1e-3).prepare(parallel_fibres(length_m=20e-3))
    with pytest.raises(InputError, match="central_zone_fraction"):
        BiasExtension(central_zone_fraction=0.8)


def test_clamps_that_leave_no_gauge_name_the_bias_extension():
    # the message names this test's table, not the tension whose clamping it shares
    with pytest.raises(InputError, match=r"^bias_extension\.clamp_length_m = 0\.01 m leaves no "
                                         r"gauge length"):
        BiasExtension(clamp_length_m=0.01).prepare(braced_bias_net())
    with pytest.raises(InputError, match=r"^bias_extension\.clamp_length_m must be > 0"):
        BiasExtension(clamp_length_m=-1e-3)


# -- LAMMPS --------------------------------------------------------------------------------
@pytest.mark.lammps
def test_braced_net_shears_in_the_centre_and_balances_energy(tmp_path):
    net = braced_bias_net()
    result = BiasExtension(max_shear_angle_deg=20, speed_fraction=5e-4).run(
        net, tmp_path / "be", engine=Engine(progress=False))
    s = result.summary
    fibre = s["fibre_shear_angle"]
    kin, meas = np.asarray(fibre["kinematic_deg"]), np.asarray(fibre["fibres_deg"])
    assert len(kin) >= 10 and kin[-1] == pytest.approx(20, abs=0.5)
    assert np.all(np.diff(meas) > -0.2)  # the centre shears steadily ...
    assert meas[-1] > 0.5 * kin[-1]
    # ... and follows the closed form within a few degrees at moderate angle
    assert np.max(np.abs(meas - kin)[kin <= 10]) < 4.0
    assert s["max_kinetic_to_strain_energy"] < 0.05
    assert s["energy_balance"]["relative_error"] < 0.05
    assert s["max_force_n"] > 0
    files = {p.name for p in result.run_dir.iterdir()}
    assert {"curve.csv", "curve.png", "shear_angle.png", "summary.json",
            "trajectory.h5", "trajectory.pvd", "in.bias_extension"} <= files
    # the fibre angles were measured on every frame of trajectory.h5, the last one the end
    u = fabmd.load(result.run_dir)
    assert u.trajectory.n_frames == len(fibre["steps"])
    assert fibre["steps"][-1] == s["steps"] == u.trajectory[-1].data["step"]
