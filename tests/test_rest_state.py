"""Fibres at rest in their present shape (the crimp's locked-in tension relieved)."""

import dataclasses

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.rest_state import RELIEF_BIN, relieve_fibre_tension
from fabmd.protocols.coupon import Coupon

from .fabrics import plain_weave_cell


def _tensioned_cell(shrink=0.95):
    """The loose cell with its fibres' rest lengths shrunk: every fibre in tension, as a
    crimped cell holds it."""
    cell = plain_weave_cell(cells=(2, 1))
    table = [dataclasses.replace(bt, rest_length_m=shrink * bt.rest_length_m)
             for bt in cell.bond_type_table]
    return dataclasses.replace(cell, bond_type_table=table)


def _bond_forces(model):
    rest = np.array([model.bond_type_table[t - 1].rest_length_m for t in model.bond_types])
    k = np.array([model.bond_type_table[t - 1].spring_n_per_m for t in model.bond_types])
    return k * (model.bond_lengths() - rest), k * rest


def test_relieved_fibres_carry_no_tension_and_keep_their_shape():
    cell = _tensioned_cell()
    before, ea0 = _bond_forces(cell)
    assert before.mean() > 0.04 * ea0.mean()  # the starting fibres are in tension
    relieved = relieve_fibre_tension(cell)
    after, ea = _bond_forces(relieved)
    # the binning misfit: at most half a bin of strain, of either sign, mean ~0
    assert np.all(np.abs(after) <= 0.5 * RELIEF_BIN * ea * 1.001)
    assert abs(after.mean()) < 0.05 * RELIEF_BIN * ea.mean()
    np.testing.assert_array_equal(relieved.positions, cell.positions)
    np.testing.assert_array_equal(relieved.bonds, cell.bonds)
    # springs kept; a family's types stay contiguous
    assert {bt.coefficient for bt in relieved.bond_type_table} == \
        {bt.coefficient for bt in cell.bond_type_table}
    fams = [bt.family for bt in relieved.bond_type_table]
    assert fams == sorted(fams, key=["warp", "weft"].index)
    assert relieved.info["fibre_tension_relieved"]["bond_types"] == len(fams)


def test_a_coupon_relieved_as_cut_has_no_fibre_tension():
    cell = _tensioned_cell()
    kept = Coupon(length_m=6e-3, width_m=3e-3).geometry(cell)
    relieved = Coupon(length_m=6e-3, width_m=3e-3, relieve_tension=True).geometry(cell)
    assert _bond_forces(kept)[0].mean() > 0.04 * _bond_forces(kept)[1].mean()  # 5 % shrink
    force, ea = _bond_forces(relieved)
    assert np.abs(force).max() <= 0.5 * RELIEF_BIN * ea.max() * 1.001
    with pytest.raises(InputError, match="coupon.relieve_tension"):
        Coupon(length_m=6e-3, width_m=3e-3, relieve_tension="yes")


def test_the_tension_test_relieves_its_coupon_by_default():
    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import load_scene
    from fabmd.stages import coupon_stage

    scene = load_scene(example_scene("plain_weave.toml"))
    assert coupon_stage(scene, "tension")[0].relieve_tension is True
    assert coupon_stage(scene, "bias-extension")[0].relieve_tension is False
