"""Bending of cut fibres with a straight rest shape (fabmd.model.bending)."""

from __future__ import annotations

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.bending import add_bending, chain_triples
from fabmd.model.transform import cut, tile
from fabmd.scene import blocks
from fabmd.scene.templates import fmt

from .fabrics import parallel_fibres, plain_weave_cell


def _woven():
    return cut(tile(plain_weave_cell(), 3, 3, periodic=False), 4e-3, 4e-3)


def test_every_inner_bead_of_a_chain_gets_one_angle():
    model = parallel_fibres(n=3)
    triples = chain_triples(model)
    per_fibre = np.bincount(model.fibre_ids)[1:]
    assert len(triples) == int((per_fibre - 2).sum())
    # a, b, c are neighbours along one fibre, b in the middle
    assert (model.fibre_ids[triples[:, 0]] == model.fibre_ids[triples[:, 1]]).all()
    assert (model.fibre_ids[triples[:, 2]] == model.fibre_ids[triples[:, 1]]).all()
    assert set(triples[:, 1]).isdisjoint(set(model.fibre_ends().ravel().tolist()))


def test_bending_is_the_factor_times_the_solid_fibre_and_straight_at_rest():
    woven = _woven()
    bent = add_bending(woven, 0.01)
    assert len(bent.angles) == len(chain_triples(woven))
    assert len(bent.angle_type_table) == len(set(bent.family_names))  # one type per family
    # K = factor · E·I/l0 of the solid fibre, E·I = E·A·d²/16
    bt = bent.bond_type_table[0]
    d = bent.diameters.max()
    expected = 0.01 * 2 * bt.coefficient * bt.rest_length_m * d * d / 16 / bt.rest_length_m
    assert bent.angle_type_table[0].coefficient == pytest.approx(expected)
    text = blocks.bonds(bent)  # cosine: E = K(1 + cos θ), least when straight
    assert "angle_style     cosine" in text
    assert f"angle_coeff     1 {fmt(bent.angle_type_table[0].coefficient)}" in text


def test_the_bending_term_counts_in_the_time_step():
    from fabmd.model.beads import model_critical_time_step_s

    woven = _woven()
    assert model_critical_time_step_s(add_bending(woven, 1.0)) < \
        model_critical_time_step_s(woven)


def test_a_saved_model_with_a_bent_rest_shape_is_refused(tmp_path):
    import json

    from fabmd.model.bead_model import BeadModel

    bent = add_bending(_woven(), 0.01)
    bent.save(tmp_path, stem="m")
    assert len(BeadModel.load(tmp_path / "m.data", tmp_path / "m.json").angles) == len(bent.angles)
    meta = json.loads((tmp_path / "m.json").read_text())
    meta["angle_types"][0]["rest_angle_deg"] = 176.5  # written by an older fabmd
    (tmp_path / "m.json").write_text(json.dumps(meta))
    with pytest.raises(InputError, match="bent rest shape"):
        BeadModel.load(tmp_path / "m.data", tmp_path / "m.json")


def test_coupon_validates_its_bending_factor():
    from fabmd.protocols.coupon import Coupon

    with pytest.raises(InputError, match="coupon.bending_factor"):
        Coupon(length_m=0.01, width_m=0.01, bending_factor=-0.1)
    with pytest.raises(InputError, match="coupon.bending_factor"):
        Coupon(length_m=0.01, width_m=0.01, bending_factor=2.0)


def test_bending_is_refused_with_a_bad_factor_or_twice():
    woven = _woven()
    with pytest.raises(InputError, match="bending_factor"):
        add_bending(woven, 0.0)
    with pytest.raises(InputError, match="already has bending"):
        add_bending(add_bending(woven, 0.01), 0.01)
