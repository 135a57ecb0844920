"""Bending of cut fibres, rest shape between straight and as woven (fabmd.model.bending)."""

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


def _angles_deg(model):
    pos = model.positions
    a, b, c = model.angles.T
    u, v = pos[a] - pos[b], pos[c] - pos[b]
    return np.degrees(np.arccos(np.einsum("ij,ij->i", u, v)
                                / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)))


@pytest.mark.parametrize("kept", [0.0, 0.5])
def test_rest_shape_keeps_the_set_share_of_the_bend(kept):
    woven = cut(tile(plain_weave_cell(), 3, 3, periodic=False), 4e-3, 4e-3)
    bent = set_bending(woven, 0.01, set_fraction=kept, bin_deg=0.25)
    bend = 180.0 - _angles_deg(bent)
    rest = np.array([bent.angle_type_table[t - 1].rest_angle_deg for t in bent.angle_types])
    assert np.abs((180.0 - rest) - kept * bend).max() <= 0.125 + 1e-9
    assert bend.max() > 1.0  # there is a bend, so set 0 and set 1 differ
    if kept == 0.0:  # straight rest shape: one angle type per family, the crimp all elastic
        assert {t.rest_angle_deg for t in bent.angle_type_table} == {180.0}
        assert len(bent.angle_type_table) == len(set(bent.family_names))


def test_coupon_validates_its_bending_fields():
    from fabmd.protocols.coupon import Coupon

    with pytest.raises(InputError, match="coupon.bending_set"):
        Coupon(length_m=0.01, width_m=0.01, bending_factor=0.01, bending_set=1.5)
    with pytest.raises(InputError, match="coupon.bending_factor"):
        Coupon(length_m=0.01, width_m=0.01, bending_factor=-0.1)


def test_bending_set_is_refused_with_a_bad_factor_or_twice():
    woven = cut(tile(plain_weave_cell(), 3, 3, periodic=False), 4e-3, 4e-3)
    with pytest.raises(InputError, match="bending_factor"):
        set_bending(woven, 0.0)
    with pytest.raises(InputError, match="bending_set"):
        set_bending(woven, 0.01, set_fraction=-0.1)
    with pytest.raises(InputError, match="already has bending"):
        set_bending(set_bending(woven, 0.01), 0.01)
