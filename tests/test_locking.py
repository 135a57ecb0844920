"""The shear-locking angle by a stated method that does not depend on where the test stops
(:func:`fabmd.results.curves.locking_angle`): curves with a known knee, and the same curve
cut at different angles (no LAMMPS)."""

import numpy as np
import pytest

from fabmd.results.curves import locking_angle, tangent_intersection


def knee(x, at, low_slope, high_slope, offset=0.0):
    """Two straight branches meeting at ``at``: the locking angle is ``at`` exactly."""
    return offset + low_slope * x + np.where(x > at, (high_slope - low_slope) * (x - at), 0.0)


@pytest.mark.parametrize("at,offset", [(25.0, 0.0), (40.0, 0.0), (35.0, 2.0)])
def test_a_knee_is_found_where_the_branches_meet(at, offset):
    x = np.linspace(0, 60, 241)
    rng = np.random.default_rng(1)
    y = knee(x, at, 0.05, 3.0, offset) * (1 + 0.01 * rng.standard_normal(x.size))
    lock = locking_angle(x, y)
    assert lock["found"], lock["reason"]
    assert lock["x"] == pytest.approx(at, abs=0.5)
    assert lock["departure_x"] > at  # the departure is read on the steep branch
    assert lock["final_slope"] == pytest.approx(3.0, rel=0.05)
    assert "10-20 deg" in lock["method"]


def smooth(x):
    """A picture-frame-like curve without a knee: linear, then exponential stiffening."""
    return 0.02 * x + 0.05 * np.exp((x - 30.0) / 4.0)


def test_the_same_curve_cut_at_50_55_60_gives_the_same_angle():
    x = np.linspace(0, 60, 601)
    y = smooth(x)
    new = [locking_angle(x[x <= cut], y[x <= cut])["x"] for cut in (50, 55, 60)]
    assert max(new) - min(new) < 1.0
    # the tangent over the last 15 % of the test moves with the cut (the old method)
    old = [tangent_intersection(x[x <= cut], y[x <= cut])["x"] for cut in (50, 55, 60)]
    assert max(old) - min(old) > 3.0


def test_a_test_stopped_before_locking_says_so():
    x = np.linspace(0, 60, 601)
    y = smooth(x)
    early = locking_angle(x[x <= 30], y[x <= 30])
    assert not early["found"] and "before the curve ends" in early["reason"]
    short = locking_angle(x[x <= 10], y[x <= 10])
    assert not short["found"] and "initial range" in short["reason"]
    flat = locking_angle(x, 0.5 * x)
    assert not flat["found"]


def test_the_start_up_does_not_move_the_locking_angle():
    """The initial line is fitted over 10-20 deg, past a start-up transient in the first
    degrees (the fabric brought up to the frame's speed: F at 5 deg may read low or high)."""
    x = np.linspace(0, 60, 601)
    y = knee(x, 33.0, 0.03, 3.0)
    found = []
    for bump in (-0.3, 0.0, 0.3):  # start-up transients of either sign, gone by 8 deg
        start = y + bump * np.exp(-x / 2.0)
        found.append(locking_angle(x, start)["x"])
    assert max(found) - min(found) < 0.2
    assert found[1] == pytest.approx(33.0, abs=0.5)
