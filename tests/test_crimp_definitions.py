"""Outputs name their crimp definition; the other one is beside it (issue 19)."""

import pytest

from fabmd.results.measure import CRIMP_DEFINITION, fabric_measures

from .fabrics import plain_weave_cell


def test_measures_name_the_crimp_and_give_the_centreline_crimp():
    m = fabric_measures(plain_weave_cell())
    assert m["crimp_definition"] == CRIMP_DEFINITION and "per fibre" in CRIMP_DEFINITION
    # one virtual fibre per yarn: the yarn centreline is the fibre, so both crimps agree
    assert m["centreline_crimp_pct"].keys() == m["crimp_pct"].keys()
    for fam, c in m["crimp_pct"].items():
        assert c > 0
        assert m["centreline_crimp_pct"][fam] == pytest.approx(c, rel=0.05)
