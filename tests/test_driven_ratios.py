"""Kinetic-energy ratios of a driven curve: samples with nothing to divide by are not
measured (a 1e-300 floor used to turn them into 1e+288)."""

import numpy as np

from fabmd.protocols.driven_outputs import Outputs, kinetic_ratio, kinetic_to_work_ratio


def _outputs(kinetic, strain, work):
    n = len(kinetic)
    cols = {"kinetic_j": np.asarray(kinetic, float), "strain_energy_j": np.asarray(strain, float)}
    return Outputs(cols, {}, np.asarray(work, float), np.zeros(n), None)


def test_zero_denominators_are_skipped_not_floored():
    out = _outputs([1e-9, 2e-3, 1e-3], [0.0, 1e-2, 2e-2], [0.0, -4e-2, 5e-2])
    started = np.ones(3, bool)
    assert kinetic_ratio(out, started) == 2e-3 / 1e-2
    assert kinetic_to_work_ratio(out, started) == 2e-3 / 4e-2


def test_nothing_to_divide_by_is_none():
    out = _outputs([1e-9, 1e-9], [0.0, 0.0], [0.0, 0.0])
    started = np.ones(2, bool)
    assert kinetic_ratio(out, started) is None
    assert kinetic_to_work_ratio(out, started) is None
    assert kinetic_ratio(out, np.zeros(2, bool)) is None
