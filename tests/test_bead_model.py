"""Bead model and LAMMPS data files (no LAMMPS)."""

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn


def two_fibres(periodic=False) -> BeadModel:
    x = np.arange(5) * 0.5e-4
    pos = np.vstack([np.column_stack([x, np.zeros(5), np.zeros(5)]),
                     np.column_stack([x, np.full(5, 1.2e-4), np.zeros(5)])])
    bonds = [(i, i + 1) for i in range(4)] + [(i, i + 1) for i in range(5, 9)]
    return BeadModel(positions=pos, diameters=1e-4, masses=1e-9, atom_types=[1] * 5 + [2] * 5,
                     fibre_ids=[1] * 5 + [2] * 5, bonds=bonds, bond_types=[1] * 4 + [2] * 4,
                     family_names=("warp", "weft"),
                     bond_type_table=[BondType(1e6, 0.5e-4, "warp"),
                                      BondType(2e6, 0.5e-4, "weft")],
                     fibre_yarn=[1, 2], yarns=[Yarn("warp-1", "warp"), Yarn("weft-1", "weft")],
                     box_lo=[-1e-3] * 3, box_hi=[1e-3] * 3,
                     periodic=(periodic, False, False))


def test_data_file_round_trip(tmp_path):
    m = two_fibres()
    data, meta = m.save(tmp_path)
    back = BeadModel.load(data)
    assert back.n_beads == 10 and back.n_bonds == 8
    np.testing.assert_allclose(back.positions, m.positions, rtol=1e-11, atol=1e-15)
    np.testing.assert_allclose(back.masses, m.masses, rtol=1e-8)
    np.testing.assert_array_equal(back.bonds, m.bonds)
    np.testing.assert_array_equal(back.yarn_ids, [1] * 5 + [2] * 5)
    assert list(back.families[:1]) == ["warp"]
    assert back.bond_type_table[1].coefficient == 2e6


def test_inconsistent_models_are_refused():
    m = two_fibres()
    with pytest.raises(InputError, match="bond refers"):
        BeadModel(**{**m.__dict__, "bonds": [(0, 99)], "bond_types": [1]})
    with pytest.raises(InputError, match="atom types"):
        BeadModel(**{**m.__dict__, "atom_types": 3})


def test_periodic_bond_lengths_use_minimum_image():
    m = two_fibres(periodic=True)
    m.positions[4, 0] = m.box_hi[0] - 1e-5
    m.positions[3, 0] = m.box_lo[0] + 2e-5
    lengths = m.bond_lengths()
    assert lengths[3] == pytest.approx(3e-5)
