"""benchmarks/frame_kinetic.py: the work alone against the work less the kinetic energy."""

import numpy as np
import pytest

from .test_benchmarks import load_benchmark


def load():
    return load_benchmark("frame_kinetic")


def synthetic(force_n, ke_per_m2):
    """A frame pulled at a shear resistance ``force_n`` whose fabric's kinetic energy grows
    as ke_per_m2·d²: the work is F·d + KE."""
    d = np.linspace(0.0, 0.01, 401)
    return {"shear_angle_deg": np.degrees(d / 0.01), "displacement_m": d,
            "kinetic_energy_j": ke_per_m2 * d**2,
            "external_work_j": force_n * d + ke_per_m2 * d**2}


def test_taking_the_kinetic_energy_off_recovers_the_resistance():
    bench = load()
    edges = np.arange(5.0, 55.0, 5.0)
    out = bench.interval_forces(synthetic(2.0, 3.0e3), edges)
    assert out["net"] == pytest.approx(np.full(len(edges) - 1, 2.0), rel=1e-9)
    assert np.all(out["work"] > 2.0) and out["share"].max() > 0.05
    # a twice-as-fast frame (four times the kinetic energy) reads the same net force
    rows = bench.compare(synthetic(2.0, 1.2e4), synthetic(2.0, 3.0e3))
    assert rows and all(r[2] in ("+0.0 %", "-0.0 %") for r in rows)
    assert all(float(r[1].split()[0]) > 1.0 for r in rows)
    # motion of the fabric's own (relative to the frame) is not the carriage's: not taken off
    own = synthetic(2.0, 3.0e3)
    own["kinetic_relative_j"] = 0.5 * own["kinetic_energy_j"]
    out = bench.interval_forces(own, edges)
    assert np.all(out["net"] > 2.0) and np.all(out["net"] < out["work"])
