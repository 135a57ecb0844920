"""Compaction between rigid platens: a tiny periodic plain-weave cell (seconds)."""

import warnings

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.beads import model_bead_parameters
from fabmd.model.contact import ContactModel, ToolContact
from fabmd.protocols.compaction import Compaction, monotone_loading, thickness_at
from fabmd.results.folder import read_csv
from fabmd.scene.plan import RunPlan

from .fabrics import plain_weave_cell


def test_thickness_at_interpolates_the_first_crossing():
    p = np.array([0.0, 500.0, 1500.0, 20000.0])
    h = np.array([2.0, 1.8, 1.6, 1.0])
    got = thickness_at(p, h, (1e3, 1e4, 1e6))
    assert got["1000"] == pytest.approx(1.7)
    assert thickness_at(p[2:], h[2:], (1e3,))["1000"] is None  # starts above 1 kPa
    assert got["10000"] == pytest.approx(1.6 - 0.6 * (1e4 - 1500) / 18500)
    assert got["1e+06"] is None


def test_a_fabric_that_gives_way_is_not_monotone():
    """Judged in the order of travel from half the lowest reported pressure: the 7-fibre
    plain weave's flattening (26.6 → 24.1 kPa as it thins) fails; noise under 1 % and a
    rattle below the floor do not."""
    rising = np.geomspace(100.0, 2e5, 5000)  # 0.15 % a sample
    assert monotone_loading(rising, 500.0)
    gives_way = np.concatenate([np.linspace(1e3, 26.6e3, 50), np.linspace(26.6e3, 24.1e3, 20),
                                np.linspace(24.1e3, 2e5, 50)])
    assert not monotone_loading(gives_way, 500.0)
    noisy = rising * (1 + 0.004 * np.sin(np.arange(rising.size)))
    assert np.diff(noisy).min() < 0 and monotone_loading(noisy, 500.0)
    rattle = np.concatenate([[70.0, 100.0, 59.0, 200.0], rising[rising > 300]])
    assert monotone_loading(rattle, 500.0) and not monotone_loading(rattle, 50.0)
    assert monotone_loading(np.array([10.0, 20.0]), 500.0)  # never reached: nothing to judge


def test_bad_settings_fail_before_lammps():
    with pytest.raises(InputError, match="compaction.max_pressure_pa must be > 0"):
        Compaction(max_pressure_pa=0)
    with pytest.raises(InputError, match="compaction.max_travel_fraction"):
        Compaction(max_travel_fraction=1.0)
    assert Compaction(max_pressure_pa="50 kPa").max_pressure_pa == 5e4
    with pytest.raises(InputError, match="periodic in x and y"):
        Compaction().input_text(plain_weave_cell(periodic=False))


@pytest.mark.lammps
def test_thickness_falls_monotonically_with_pressure(tmp_path):
    cell = plain_weave_cell()
    # soft contact (per unit length): the crossings and platen contacts give way visibly
    soft = {"normal_stiffness_pa": "10 MPa"}
    test = Compaction(max_pressure_pa="20 kPa", datasheet_pressure_pa="5 kPa",
                      speed_fraction=1e-4, samples=100, contact=ContactModel(**soft),
                      tool=ToolContact(friction=0.2, **soft))
    s = test.run(cell, tmp_path / "c", engine=Engine(progress=False)).summary
    assert s["pressure_reached"]
    assert s["thickness_monotone"]
    assert s["quasi_static"]["ok"], s["quasi_static"]["problems"]
    h = s["thickness_at_pressure_m"]
    assert h["5000"] > h["10000"]
    # the curve starts where both platens carry the load; below that nothing is reported
    assert (h["1000"] is None) == (s["contact_pressure_pa"] > 1e3)
    assert h["100000"] is None  # the platen turned back at 20 kPa
    # the platens start on the outermost bead surfaces of the fabric after its free settle
    # (platens.txt), which moved them little from the as-woven cell's
    lo, hi = (float(v) for v in (tmp_path / "c" / "platens.txt").read_text().split())
    assert s["starting_gap_m"] == pytest.approx(hi - lo, rel=1e-12)
    z, r = cell.positions[:, 2], 0.25e-3
    assert s["starting_gap_m"] == pytest.approx(z.max() - z.min() + 2 * r, rel=0.02)
    assert s["settle_shift_m"] == pytest.approx([lo - (z.min() - r), hi - (z.max() + r)],
                                                abs=1e-15)
    # two stacked single-fibre yarns cannot get thinner than two diameters (less overlap)
    assert s["min_thickness_m"] > 2 * 0.5e-3 * (1 - 2 * s["max_overlap_ratio"])
    curve = read_csv(tmp_path / "c" / "curve.csv")
    assert set(curve) >= {"pressure_pa", "thickness_m", "phase"}
    assert (curve["phase"] < 0).any()  # it unloaded
    # no law: the platen's speed is constant, down and up; the unloading ends at the lowest
    # reported pressure (1 kPa) or back at the start
    np.testing.assert_allclose(curve["platen_speed_m_s"], test.speed_m_s(cell), rtol=1e-9)
    back = curve["phase"] < 0
    assert (curve["pressure_pa"][back][-1] <= 1e3
            or curve["thickness_m"][back][-1] >= s["starting_gap_m"] * (1 - 1e-9))
    assert (tmp_path / "c" / "curve.png").exists()


def test_scene_table_and_contact_reach_the_protocol():
    from fabmd.pipeline import build_protocol

    c = build_protocol("compaction", {"max_pressure_pa": "150 kPa",
                                      "datasheet_pressure_pa": "100 kPa",
                                      "tool": {"friction": 0.1}},
                       contact=ContactModel(normal_stiffness_pa="1 GPa"))
    assert c.max_pressure_pa == 1.5e5 and c.datasheet_pressure_pa == 1e5
    assert c.contact.normal_stiffness_pa == 1e9 and c.tool.friction == 0.1


def _synthetic_run(run_dir, top, bottom, kinetic, settle=10, every=10):
    """A compaction run folder without LAMMPS: ``means.dat`` of the given loading samples
    (pressures [Pa], kinetic energy [J]; the platen comes down 1 µm per interval), one
    settling sample before them, ``plan.json`` and ``turn.txt`` (the pressure reached)."""
    n = len(top)
    rows = [(settle, 0.0, 0.0, 1e-3, 0.0, 1)] + [
        (settle + every * (i + 1), top[i], bottom[i], 1e-3 - 1e-6 * i, kinetic[i], 1)
        for i in range(n)]
    run_dir.mkdir()
    (run_dir / "means.dat").write_text(
        "# Time-averaged data for fix means\n"
        "# step pressure_pa bottom_pressure_pa thickness_m kinetic_j phase\n"
        + "".join(" ".join(f"{v:.12g}" for v in r) + "\n" for r in rows))
    RunPlan(time_step_s=1e-8, steps=every * (n + 5), every=every, duration_s=1e-6,
            speed_m_s=0.1, extra={"settle_steps": settle}).write(run_dir)
    (run_dir / "turn.txt").write_text(f"{every * n}\n")
    return run_dir


def _reduce_quietly(run_dir):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Compaction(unload=False).reduce(run_dir, plain_weave_cell()).summary


def test_quasi_static_measures_start_at_first_contact(tmp_path):
    # the top platen strikes one bead at the start (the bottom carries nothing, no work
    # done yet), the bead rattles free, then the load goes through the fabric smoothly
    top = [3000.0, 0.0, 0.0, 1000.0, 2000.0, 4000.0, 6000.0, 8000.0, 10000.0]
    bottom = [0.0, 0.0, 0.0, 990.0, 1990.0, 3980.0, 5970.0, 7960.0, 9950.0]
    kinetic = [1e-12] * 3 + [1e-15] * 6
    s = _reduce_quietly(_synthetic_run(tmp_path / "c", top, bottom, kinetic))
    assert s["contact_pressure_pa"] == 1000.0
    # old code: the strike counted (mismatch 1.0, KE over a work floored at 1e-300)
    assert s["max_platen_pressure_mismatch"] == pytest.approx(0.005, rel=1e-6)
    assert s["max_kinetic_to_work"] < 1e-3
    assert s["quasi_static"]["ok"], s["quasi_static"]["problems"]


def test_kinetic_to_work_without_work_is_not_measured(tmp_path):
    # both platens carry the load from the first sample, where the platen has done no work
    top = [5000.0, 10000.0]
    s = _reduce_quietly(_synthetic_run(tmp_path / "c", top, top, [1e-12, 1e-16]))
    # old code: 1e-12 / 1e-300 = 1e288 at the first sample; now only the second is a ratio
    work = 0.5 * (5000.0 + 10000.0) * 1e-6 * Compaction().area_m2(plain_weave_cell())
    assert s["max_kinetic_to_work"] == pytest.approx(1e-16 / work)
    s = _reduce_quietly(_synthetic_run(tmp_path / "one", [5000.0], [5000.0], [1e-12]))
    assert s["max_kinetic_to_work"] is None  # no sample with work: not measured
    assert s["max_platen_pressure_mismatch"] == 0.0
    assert s["quasi_static"]["ok"] and s["quasi_static"]["not_measured"] == [
        "max_kinetic_to_work"]


def test_each_reported_thickness_says_whether_the_load_had_crossed_the_fabric(tmp_path):
    # low pressures: the top platen leads the bottom one (the load still crossing the
    # fabric); from 4 kPa on they agree
    top = [800.0, 2000.0, 4000.0, 8000.0, 12000.0, 20000.0]
    bottom = [500.0, 1500.0, 3900.0, 7950.0, 11950.0, 19950.0]
    run = _synthetic_run(tmp_path / "c", top, bottom, [1e-15] * 6)
    with pytest.warns(UserWarning, match=r"1000 Pa \(platens differ by 38%\).*speed_fraction"):
        s = Compaction(unload=False).reduce(run, plain_weave_cell()).summary
    at = s["quasi_static_at_pressure"]
    assert at["1000"]["platen_pressure_mismatch"] == pytest.approx(0.375)
    assert not at["1000"]["ok"]
    # the mismatch falls about as the speed: the speed that would bring it to the limit
    run_fraction = 0.1 / min(b.wave_speed_m_s for b in model_bead_parameters(plain_weave_cell()))
    assert at["1000"]["speed_fraction_below"] == pytest.approx(run_fraction * 0.1 / 0.375)
    assert at["10000"] == {"platen_pressure_mismatch": pytest.approx(50 / 8000), "ok": True}
    assert "100000" not in at  # never reached
