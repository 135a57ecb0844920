"""Uniaxial tension: closed form on straight fibres, and a woven coupon's curve shape."""

import json

import numpy as np
import pytest

import fabmd
from fabmd.engine import Engine
from fabmd.errors import InputError, UnstableRun
from fabmd.protocols.coupon import load_coupon
from fabmd.protocols.tension import Tension
from fabmd.results.universe import data_file_bond_count
from fabmd.scene.outputs import TrajectoryOutput

from .fabrics import SOFT_GLASS, parallel_fibres

pytestmark = pytest.mark.lammps


def test_parallel_straight_fibres_give_n_ea_epsilon(tmp_path):
    n = 4
    coupon = parallel_fibres(n=n)
    test = Tension(max_elongation_pct=1.2, trajectory=TrajectoryOutput(frames=7))
    result = test.run(coupon, tmp_path / "t", engine=Engine(progress=False))
    s = result.summary
    ea = SOFT_GLASS.modulus_pa * 3.14159265 * 0.5e-3**2 / 4
    for strain in (0.5, 1.0):
        measured = s["force_at_elongation_n"][f"{strain:g}"]
        assert measured == pytest.approx(n * ea * strain / 100, rel=0.02)
        # the optical gauge sees the same even strain: F = n E A eps against it too
        gauged = s["optical_gauge"]["force_at_strain_n"][f"{strain:g}"]
        assert gauged == pytest.approx(n * ea * strain / 100, rel=0.02)
    assert s["optical_gauge"]["strain_ratio_to_clamp"] == pytest.approx(1.0, abs=0.02)
    # the marks: centroids of bands a bead diameter wide, within a bond of the nominal marks
    assert s["optical_gauge"]["length_m"] == pytest.approx(0.5 * s["gauge_length_m"], rel=0.1)
    assert s["energy_balance"]["relative_error"] < 0.05
    assert s["max_kinetic_to_strain_energy"] < 0.05
    _assert_outputs_and_trajectory(result, test, coupon)


def _data_steps(path) -> np.ndarray:
    rows = [line.split() for line in path.read_text().splitlines()
            if line.strip() and not line.startswith("#")]
    return np.array([int(r[0]) for r in rows])


def _assert_outputs_and_trajectory(result, test, coupon):
    """The trajectory's final zero-step run adds no line to means.dat / curve.dat; the
    frames fall on output steps, the last is the last step; fabmd.load opens them."""
    run_dir, steps, every = result.run_dir, test.steps(coupon), test.every(coupon)
    for name in ("curve.dat", "means.dat"):
        written = _data_steps(run_dir / name)
        assert np.all(np.diff(written) > 0), f"{name}: a step written twice"
        assert written[-1] == steps
    assert len(_data_steps(run_dir / "curve.dat")) == steps // every + 1
    assert result.summary["trajectory"] == "trajectory.h5"
    u = fabmd.load(run_dir)
    frames = np.array([ts.data["step"] for ts in u.trajectory])
    assert frames[0] == 0 and frames[-1] == steps and np.all(np.diff(frames) > 0)
    assert np.all(frames % every == 0)  # on curve samples
    assert 7 <= len(frames) <= 9
    assert len(u.bonds) == data_file_bond_count(run_dir / "model.data")


def test_coupon_is_relaxed_and_reusable(woven_coupon):
    again = load_coupon(woven_coupon.run_dir)
    assert again.n_beads == woven_coupon.model.n_beads
    tension = woven_coupon.summary["relaxed_state"]["tension"]["warp"]["max_fibre_tension_n"]
    crimped = json.loads((woven_coupon.run_dir.parent / "crimp" / "summary.json").read_text())
    woven = crimped["crimped"]["tension"]["warp"]["mean_fibre_tension_n"]
    # the cut coupon sprang back to (almost) no tension: its relaxation stops when quasi-
    # static, judged every 500 steps (measured 2026-12-06: 1.7e-3 N stopped at step 2,000,
    # 4.6e-4 N at 2,500 on a rounding-different path, of 10 N per fibre crimped)
    assert tension < 5e-4 * woven


def test_woven_coupon_is_soft_first_then_stiffens(woven_coupon, tmp_path):
    result = Tension(max_elongation_pct=3.0).run(woven_coupon.model, tmp_path / "t",
                                                 engine=Engine(progress=False))
    s = result.summary
    assert s["final_stiffness_n"] > 1.3 * s["initial_stiffness_n"]
    assert 0.2 < s["transition_elongation_pct"] < 2.8
    assert s["max_kinetic_to_strain_energy"] < 0.05
    assert s["energy_balance"]["relative_error"] < 0.05
    assert (result.run_dir / "curve.png").exists() and (result.run_dir / "curve.csv").exists()


def test_clamps_that_leave_no_gauge_are_refused():
    with pytest.raises(InputError, match=r"^tension\.clamp_length_m = 0\.02 m leaves no gauge"):
        Tension(clamp_length_m=0.02).input_text(parallel_fibres())


def test_a_blow_up_keeps_the_frames_up_to_it(tmp_path, monkeypatch):
    """A driven test that fails still converts its trajectory (salvage), for a look."""
    coupon = parallel_fibres(n=2)
    test = Tension(max_elongation_pct=1.2, trajectory=TrajectoryOutput(every_steps=1))
    runaway = coupon.bond_type_table[0].rest_length_m / test.time_step_s(coupon)  # m/s
    original = Tension.input_text
    # a kick far beyond the speed guard, for the test only (after the relaxation)
    monkeypatch.setattr(Tension, "input_text", lambda self, model, extra="": original(
        self, model, extra=f"velocity        free set NULL NULL {runaway:.6g} sum yes"))
    with pytest.raises(UnstableRun):
        test.run(coupon, tmp_path / "boom", engine=Engine(progress=False))
    u = fabmd.load(tmp_path / "boom")
    assert u.trajectory.n_frames >= 2 and u.trajectory[0].data["step"] == 0



def _plain_weave_one_fibre(cells: int, relieve: bool = True, clamp: str | None = None):
    """The plain-weave example with one virtual fibre per yarn, its tension coupon
    ``cells`` × 2 cells, pulled to 8.5 % (past its relieved crimp, about 5.2 %)."""
    import tomllib

    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    for yarn in data["yarns"].values():
        yarn["n_fibres"] = 1
    for key in ("target_crimp_pct", "crimp_by", "crimp_tolerance_pct"):
        # one-fibre yarns cannot reach the example's stated crimp (as --fast): the drawn
        # section at the weaving tension
        del data["crimp"][key]
    data["tension"]["max_elongation_pct"] = 8.5
    data["tension"]["coupon"] = {"cells": [cells, 2], "relieve_tension": relieve}
    if clamp is not None:
        data["tension"]["clamp_length_m"] = clamp
    return parse_scene(data, source=f"plain_weave.toml, 1 fibre, {cells} cells")


#: issue #16's convergence criterion. Measured (2026-12-02, the crimp then stopped before
#: it was at rest): 3 cells 2.6 % / 2.0 % below 6 cells at 6.5 / 7 %, transitions 4.83 /
#: 4.78 %. With the crimp at rest (2026-12-06) the transitions are 5.14 / 5.19 % and 3
#: cells read a constant 5.2 kN/m (0.085 % of strain) above 6 cells past them: +6.5 /
#: +4.8 / +3.7 / +3.0 % at 6.5 / 7 / 7.5 / 8 %. The coupon relaxed as cut, with the
#: crimp's tension in its fibres and 10 % clamps, gave 0.52 / 0.56 × and 2.57 / 1.90 %;
#: relieved but with 10 % clamps (1.5 / 3 mm), 0.84 / 0.88 ×: both parts fail this test.
LENGTH_TOLERANCE = 0.05


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::fabmd.errors.QuasiStaticWarning")  # the slack toe
def test_force_per_width_at_a_strain_does_not_depend_on_the_coupon_length(tmp_path):
    """Tension coupons of the plain weave 3 and 6 cells long (1 fibre per yarn): the same
    transition and force per width past it. Cut and relaxed with the crimp's tension in
    their fibres, the coupons' crimp varied along them and with their length (about 60 s)."""
    from fabmd.pipeline import run_crimp, run_test

    engine = Engine(progress=False)
    run_crimp(_plain_weave_one_fibre(3), tmp_path / "crimp", engine=engine, form="cell")
    curves, summaries = {}, {}
    for cells in (3, 6):
        summary = run_test(_plain_weave_one_fibre(cells), "tension", tmp_path / f"t{cells}",
                           engine=engine, crimped=tmp_path / "crimp")
        s = summaries[cells] = summary["test_summary"]
        curve = np.genfromtxt(tmp_path / f"t{cells}" / "tension" / "curve.csv", delimiter=",",
                              names=True)
        curves[cells] = (curve["elongation_pct"], curve["force_per_width_n_m"])
        # clamps of one cell (5 mm) each: the free length is the rest
        assert s["gauge_length_m"] == pytest.approx(cells * 5e-3 - 10e-3, abs=1e-3)
    t3, t6 = (summaries[c]["transition_elongation_pct"] for c in (3, 6))
    assert abs(t3 - t6) < 0.3  # the toe ends at the same strain
    for past in (2.5, 3.0):  # % of strain past the toe (its end moves with the crimp)
        strain = t6 + past
        f3, f6 = (float(np.interp(strain, *curves[c])) for c in (3, 6))
        assert f3 == pytest.approx(f6, rel=LENGTH_TOLERANCE), strain


@pytest.mark.parametrize("length_mm, clamp_mm", [(30, 5), (80, 8)])
def test_clamps_hold_at_least_one_weave_repeat(length_mm, clamp_mm):
    """Default clamps: 10 % of the coupon, but at least the unit cell along the load."""
    import dataclasses

    coupon = parallel_fibres(length_m=length_mm * 1e-3)
    coupon = dataclasses.replace(coupon, info={**coupon.info, "unit_cell_m": [5e-3, 5e-3]})
    left, right, gauge = Tension().clamps(coupon)
    x = coupon.positions[:, 0]
    held = (x < left).sum() / 4 * (x[1] - x[0])  # clamped length per fibre
    assert held == pytest.approx(clamp_mm * 1e-3, abs=0.3e-3)
    # without a unit cell (a hand-built piece): 10 % as before
    assert Tension().clamps(parallel_fibres(length_m=length_mm * 1e-3))[0] < left + 1e-12


def test_the_optical_gauge_follows_two_cross_sections_between_the_clamps():
    coupon = parallel_fibres(length_m=20e-3)
    text = Tension().input_text(coupon)
    assert "group           gauge_left region gauge_left" in text
    assert "${gauge_distance}" in text and "gauge_distance_m" in text
    a, b, band = Tension().gauge_marks(coupon)
    left, right, _ = Tension().clamps(coupon)
    assert b - a == pytest.approx(0.5 * (right - left))
    assert left < a - band and b + band < right
    plain = Tension(gauge_fraction=None).input_text(coupon)
    assert "gauge" not in plain.replace("gauge length", "")
    with pytest.raises(InputError, match="tension.gauge_fraction"):
        Tension(gauge_fraction=1.0)


@pytest.mark.filterwarnings("ignore::fabmd.errors.QuasiStaticWarning")
def test_fibres_started_with_the_clamps_stretch_from_the_first_step(tmp_path):
    """``start = "affine"`` (asked for): straight fibres start with the clamps' uniform
    stretch, v = 2 v0 (x − x0)/(x_right − x_left), so their kinetic energy at the first
    sample is that field's, the first interval takes no inertia the smooth start's does,
    and the force is still n·E·A·ε."""
    n = 4
    coupon = parallel_fibres(n=n)
    runs = {start: Tension(max_elongation_pct=1.2, start=start, speed_fraction=4e-4,
                           trajectory=TrajectoryOutput(frames=0)).run(
        coupon, tmp_path / start, engine=Engine(progress=False))
        for start in ("smooth", "affine")}
    affine = runs["affine"]
    left, right, _ = Tension().clamps(coupon)
    free = (coupon.positions[:, 0] > left) & (coupon.positions[:, 0] < right)
    rate = 2 * affine.summary["clamp_speed_m_s"] / (right - left)
    x = coupon.positions[free, 0] - 0.5 * (left + right)
    field = 0.5 * np.sum(coupon.masses[free] * (rate * x) ** 2)
    assert affine.curve["kinetic_energy_j"][0] == pytest.approx(field, rel=0.02)
    assert [r.summary["start"] for r in runs.values()] == ["smooth", "affine"]
    ea = SOFT_GLASS.modulus_pa * 3.14159265 * 0.5e-3**2 / 4
    for strain in (0.5, 1.0):
        assert affine.summary["force_at_elongation_n"][f"{strain:g}"] == pytest.approx(
            n * ea * strain / 100, rel=0.02)
    first = [r.summary["quasi_static_intervals"]["intervals"][0]["inertia_share"]
             for r in runs.values()]
    assert first[1] < 0.2 * first[0], first


def test_an_initial_stiffness_fitted_over_a_flagged_toe_is_marked():
    """The initial stiffness is the toe's slope; where the verdict flags part of the toe,
    its force is drag (the example's released toe falls 5-7x per halving of the speed), so
    the summary says it is not the fabric's, and names the flagged part."""
    import types

    test = Tension()
    flagged = types.SimpleNamespace(curve={}, summary={
        "transition_elongation_pct": 1.58, "quasi_static": {"flagged": [[0.0, 1.75]]}})
    test.after_verdict(flagged)
    assert flagged.summary["initial_stiffness_trusted"] is False
    assert "0-1.58 %" in flagged.summary["initial_stiffness_note"]
    past_toe = types.SimpleNamespace(curve={}, summary={
        "transition_elongation_pct": 1.58, "quasi_static": {"flagged": [[4.0, 4.5]]}})
    test.after_verdict(past_toe)
    assert past_toe.summary["initial_stiffness_trusted"] is True
    assert "initial_stiffness_note" not in past_toe.summary
    # the optical gauge's toe ends at its own transition (gauge strain 1.2 %), which the
    # gauge reaches at 1.6 % clamp elongation here (the clamps' ends strain more): the
    # flagged 0-1.5 % covers part of it
    elongation = np.linspace(0.0, 4.0, 41)
    gauge = types.SimpleNamespace(
        curve={"elongation_pct": elongation, "gauge_strain_pct": 0.75 * elongation},
        summary={"transition_elongation_pct": 1.0, "quasi_static": {"flagged": [[0.0, 1.5]]},
                 "optical_gauge": {"transition_strain_pct": 1.2}})
    test.after_verdict(gauge)
    optical = gauge.summary["optical_gauge"]
    assert optical["initial_stiffness_trusted"] is False
    assert "gauge strain 0-1.2 %: clamp elongation 0-1.6 %" in optical["initial_stiffness_note"]
    assert "over 0-1.5 %" in optical["initial_stiffness_note"]
    gauge.summary["quasi_static"]["flagged"] = [[1.75, 2.0]]
    test.after_verdict(gauge)  # past the gauge's toe: trusted
    assert gauge.summary["optical_gauge"]["initial_stiffness_trusted"] is True
    # the bias extension fits against the displacement, 0 to its transition (4 mm here,
    # 20 deg on this curve); its intervals are in shear angle
    from fabmd.protocols.bias_extension import BiasExtension

    bias = types.SimpleNamespace(
        curve={"displacement_m": np.linspace(0, 0.01, 11),
               "shear_angle_deg": np.linspace(0, 50, 11)},
        summary={"transition_displacement_m": 0.004,
                 "quasi_static": {"flagged": [[0.0, 5.0], [15.0, 20.0], [30.0, 35.0]]}})
    BiasExtension().after_verdict(bias)
    assert bias.summary["initial_stiffness_trusted"] is False
    assert ("displacement 0-4 mm: shear angle 0-20 deg) is not quasi-static over 0-5 deg, "
            "15-20 deg") in bias.summary["initial_stiffness_note"]
    # the periodic tension fits over 10-40 % of its range: 0.2-0.8 % of a 2 % test
    from fabmd.protocols.periodic import PeriodicTension

    cell = types.SimpleNamespace(summary={"quasi_static": {"flagged": [[0.0, 0.25]]}})
    PeriodicTension(max_strain_pct=2.0).after_verdict(cell)
    assert cell.summary["initial_stiffness_trusted"] is False
    assert "over 0.2-0.25 %" in cell.summary["initial_stiffness_note"]
