"""Bending with the as-woven shape as rest shape (fabmd.model.bending)."""

from __future__ import annotations

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.bending import chain_triples, set_bending
from fabmd.model.transform import cut, tile
from fabmd.scene import blocks
from fabmd.scene.templates import fmt

from .fabrics import parallel_fibres, plain_weave_cell


def test_every_inner_bead_of_a_chain_gets_one_angle():
    model = parallel_fibres(n=3)
    triples = chain_triples(model)
    per_fibre = np.bincount(model.fibre_ids)[1:]
    assert len(triples) == int((per_fibre - 2).sum())
    # a, b, c are neighbours along one fibre, b in the middle
    assert (model.fibre_ids[triples[:, 0]] == model.fibre_ids[triples[:, 1]]).all()
    assert (model.fibre_ids[triples[:, 2]] == model.fibre_ids[triples[:, 1]]).all()
    assert set(triples[:, 1]).isdisjoint(set(model.fibre_ends().ravel().tolist()))


def test_rest_angles_are_the_crimped_angles_and_nothing_is_prestressed():
    woven = cut(tile(plain_weave_cell(), 3, 3, periodic=False), 4e-3, 4e-3)
    bent = set_bending(woven, 0.01, bin_deg=0.25)
    pos = bent.positions
    a, b, c = bent.angles.T
    u, v = pos[a] - pos[b], pos[c] - pos[b]
    theta = np.degrees(np.arccos(np.einsum("ij,ij->i", u, v)
                                 / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)))
    rest = np.array([bent.angle_type_table[t - 1].rest_angle_deg for t in bent.angle_types])
    assert np.abs(theta - rest).max() <= 0.125 + 1e-9  # half a bin
    assert theta.min() < 179.0  # the crimp is there to keep
    # stiffness: the factor times E·I/l0 of the solid fibre, E·I = E·A·d²/16
    bt = bent.bond_type_table[0]
    d = bent.diameters.max()
    expected = 0.01 * 2 * bt.coefficient * bt.rest_length_m * d * d / 16 / bt.rest_length_m
    assert bent.angle_type_table[0].coefficient == pytest.approx(expected)
    text = blocks.bonds(bent)
    assert "angle_style     harmonic" in text  # K/2 matches the cosine form's stiffness
    first = bent.angle_type_table[0]
    assert f"angle_coeff     1 {fmt(first.coefficient / 2)} {fmt(first.rest_angle_deg)}" in text


def test_bending_set_is_refused_with_a_bad_factor_or_twice():
    woven = cut(tile(plain_weave_cell(), 3, 3, periodic=False), 4e-3, 4e-3)
    with pytest.raises(InputError, match="bending_set_factor"):
        set_bending(woven, 0.0)
    with pytest.raises(InputError, match="already has bending"):
        set_bending(set_bending(woven, 0.01), 0.01)
