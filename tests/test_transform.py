"""Coupons: subset, cut and tile keep whole bonds and whole fibres (no LAMMPS)."""

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.transform import continuous_images, cut, subset, tile

L0 = 1e-4  # bond length


def grid(nw=4, nf=4, beads=20, periodic=True) -> BeadModel:
    """Straight warp (x) and weft (y) single-fibre yarns in one periodic cell."""
    period_x, period_y = beads * L0, beads * L0
    pos, types, fib, bonds = [], [], [], []
    k = 0
    for w in range(nw):  # warp along x at z = 0
        y = (w + 0.5) * period_y / nw
        for i in range(beads):
            pos.append((i * L0 + 0.3 * L0, y, 0.0))
            types.append(1)
            fib.append(w + 1)
        bonds += [(k + i, k + i + 1) for i in range(beads - 1)]
        if periodic:
            bonds.append((k + beads - 1, k))
        k += beads
    for f in range(nf):  # weft along y at z = d
        x = (f + 0.5) * period_x / nf
        for i in range(beads):
            pos.append((x, i * L0 + 0.3 * L0, 1.2 * L0))
            types.append(2)
            fib.append(nw + f + 1)
        bonds += [(k + i, k + i + 1) for i in range(beads - 1)]
        if periodic:
            bonds.append((k + beads - 1, k))
        k += beads
    bond_types = [1 if types[a] == 1 else 2 for a, _ in bonds]
    return BeadModel(
        positions=pos, diameters=L0, masses=1e-9, atom_types=types, fibre_ids=fib, bonds=bonds,
        bond_types=bond_types, family_names=("warp", "weft"),
        bond_type_table=[BondType(1.0, L0, "warp"), BondType(1.0, L0, "weft")],
        fibre_yarn=np.arange(1, nw + nf + 1),
        yarns=[Yarn(f"warp-{i}", "warp") for i in range(nw)]
        + [Yarn(f"weft-{i}", "weft") for i in range(nf)],
        box_lo=[0, 0, -5 * L0], box_hi=[period_x, period_y, 5 * L0],
        periodic=(periodic, periodic, False))


def assert_fibres_whole(m: BeadModel, periodic: bool):
    """Every bond joins neighbours along a fibre at rest length (minimum image)."""
    np.testing.assert_allclose(m.bond_lengths(), L0, rtol=1e-9)
    assert (m.fibre_ids[m.bonds[:, 0]] == m.fibre_ids[m.bonds[:, 1]]).all()
    assert (np.diff(m.fibre_ids) >= 0).all()
    per_fibre = np.bincount(m.fibre_ids)[1:]
    assert per_fibre.min() >= 2
    if not periodic:
        # open chains: n - 1 bonds per fibre
        assert m.n_bonds == m.n_beads - m.n_fibres


def test_tile_joins_periodic_fibres_across_cells():
    m = grid()
    t = tile(m, 3, 2)
    assert t.n_beads == 6 * m.n_beads and t.n_bonds == 6 * m.n_bonds
    assert_fibres_whole(t, periodic=True)
    # warp fibres run through 3 cells in x, weft through 2 in y: 4*2 + 4*3 fibres
    assert t.n_fibres == 4 * 2 + 4 * 3
    lengths = np.bincount(t.fibre_ids)[1:]
    assert sorted(set(lengths.tolist())) == [40, 60]
    # unwrapped fibres are continuous (no jump of a box length)
    u = t.unwrapped_positions
    steps = np.linalg.norm(u[t.bonds[:, 1]] - u[t.bonds[:, 0]], axis=1)
    closing = np.abs(t.bonds[:, 1] - t.bonds[:, 0]) > 1
    np.testing.assert_allclose(steps[~closing], L0, rtol=1e-9)
    assert t.yarns[0].name.startswith("warp-0@")


def test_open_tile_cuts_fibres_at_the_outer_faces():
    t = tile(grid(), 2, 2, periodic=False)
    assert t.periodic == (False, False, False)
    assert_fibres_whole(t, periodic=False)
    assert t.n_fibres == 4 * 2 + 4 * 2


def test_cut_keeps_whole_bonds_and_no_single_beads():
    big = tile(grid(), 3, 3, periodic=False)
    coupon = cut(big, length_m=30 * L0, width_m=20 * L0, edge_zone_m=5 * L0)
    assert_fibres_whole(coupon, periodic=False)
    ext = coupon.positions.max(axis=0) - coupon.positions.min(axis=0)
    assert ext[0] <= 30 * L0 + 1e-12 and ext[1] <= 20 * L0 + 1e-12
    assert coupon.info["coupon"]["length_m"] == pytest.approx(30 * L0)


def test_bias_coupon_is_rotated_so_its_length_is_along_x():
    big = tile(grid(), 3, 3, periodic=False)
    coupon = cut(big, length_m=24 * L0, width_m=12 * L0, angle_deg=45)
    assert_fibres_whole(coupon, periodic=False)
    # warp fibres (along fabric x) now run at -45 deg to the coupon axis
    warp = coupon.beads_of_family("warp")
    first, last = coupon.fibre_ends()[coupon.fibre_ids[warp[0]] - 1]
    d = coupon.positions[last] - coupon.positions[first]
    assert abs(np.degrees(np.arctan2(d[1], d[0]))) == pytest.approx(45, abs=1e-6)


def test_cut_outside_the_fabric_is_refused():
    with pytest.raises(InputError, match="does not fit"):
        cut(tile(grid(), 2, 2, periodic=False), length_m=1.0, width_m=0.1)


def test_subset_splits_fibres_and_drops_fragments():
    m = subset(grid(periodic=False), np.ones(160, bool))
    keep = np.ones(m.n_beads, bool)
    keep[5] = False   # fibre 1 splits into 5 + 14 beads
    keep[21] = False  # fibre 2 leaves a single bead (index 20): dropped
    s = subset(m, keep)
    assert_fibres_whole(s, periodic=False)
    assert s.n_fibres == m.n_fibres + 1
    assert s.n_beads == m.n_beads - 3


def test_continuous_images_of_a_periodic_cell():
    m = grid()
    images = continuous_images(m)
    u = m.positions + images * (m.box_hi - m.box_lo)
    inner = np.abs(m.bonds[:, 1] - m.bonds[:, 0]) == 1
    np.testing.assert_allclose(np.linalg.norm(u[m.bonds[inner, 1]] - u[m.bonds[inner, 0]],
                                              axis=1), L0)
