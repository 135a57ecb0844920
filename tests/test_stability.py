"""Deliberately unstable runs are caught at once, named, and leave no curve behind."""

import json

import pytest

from fabmd.engine import Engine
from fabmd.errors import UnstableRun
from fabmd.model.beads import TimeStep, model_bead_parameters
from fabmd.model.contact import ContactModel
from fabmd.protocols.crimp import Crimp
from fabmd.protocols.fibre_tension import FibreTension
from fabmd.protocols.tension import Tension

from .fabrics import plain_weave_cell

pytestmark = pytest.mark.lammps

CAUSES = {"speed", "bond_stretch", "nan", "lost_atoms", "overlap", "runaway_atom"}


def assert_caught_without_curve(err, run_dir):
    assert err.value.cause in CAUSES
    assert "Likely cause and fix" in str(err.value)
    assert not (run_dir / "curve.csv").exists()
    assert not (run_dir / "summary.json").exists()
    failure = json.loads((run_dir / "failure.json").read_text())
    assert failure["cause"] == err.value.cause


@pytest.mark.parametrize("factor", [1.5, 3.0])
def test_time_step_above_critical_is_caught(tmp_path, factor):
    test = FibreTension(length_m=3e-3, time_step=TimeStep(factor=factor, check=False),
                        speed_fraction=1e-3)
    with pytest.raises(UnstableRun) as err:
        test.run(tmp_path / "run", engine=Engine(progress=False))
    assert_caught_without_curve(err, tmp_path / "run")
    assert err.value.step is None or err.value.step < test.steps


def test_contact_stiffer_than_the_time_step_allows_is_caught(tmp_path):
    """Stiffness contrast: a contact 500x the bond spring with a bond-only time step."""
    loose = plain_weave_cell()
    bond_only = min(b.critical_time_step_s() for b in model_bead_parameters(loose))
    crimp = Crimp(expansion={"warp": -0.1, "weft": -0.1},
                  contact=ContactModel(stiffness_factor=500.0),
                  time_step=TimeStep(value_s=0.25 * bond_only, check=False))
    with pytest.raises(UnstableRun) as err:
        crimp.run(loose, tmp_path / "run", engine=Engine(progress=False))
    assert err.value.cause in CAUSES
    # the same contact with fabmd's own time step (which sees the contact) is stable
    fine = Crimp(expansion={"warp": -0.1, "weft": -0.1},
                 contact=ContactModel(stiffness_factor=500.0))
    assert fine.run(loose, tmp_path / "ok", engine=Engine(progress=False)).summary["steps"] > 0


def test_unstable_tension_writes_no_curve(tmp_path, woven_coupon):
    test = Tension(time_step=TimeStep(factor=4.0, check=False), max_elongation_pct=1.0)
    with pytest.raises(UnstableRun) as err:
        test.run(woven_coupon.model, tmp_path / "run", engine=Engine(progress=False))
    assert_caught_without_curve(err, tmp_path / "run")


def test_quasi_static_verdict_names_what_is_too_large():
    from fabmd.protocols.driven import QUASI_STATIC_LIMITS, quasi_static_verdict

    calm = {"max_kinetic_to_strain_energy": 0.02, "max_kinetic_to_external_work": None,
            "energy_balance": {"external_work_j": 1.0, "damping_dissipation_j": 0.1}}
    assert quasi_static_verdict(calm)["ok"]
    assert quasi_static_verdict(calm)["values"]["damping_share"] == pytest.approx(0.1)
    dragged = {**calm, "energy_balance": {"external_work_j": 1.0, "damping_dissipation_j": 0.9}}
    verdict = quasi_static_verdict(dragged)
    assert not verdict["ok"] and verdict["problems"] == ["damping_share = 0.9 > 0.5"]
    shaking = {**calm, "max_kinetic_to_strain_energy": 2.0}
    assert "max_kinetic_to_strain_energy = 2 > 0.1" in quasi_static_verdict(shaking)["problems"]
    assert quasi_static_verdict(shaking, {"damping_share": 0.5})["ok"]  # a test's own limits
    leaking = {**calm, "energy_balance": {"external_work_j": -1e-4,
                                          "damping_dissipation_j": 0.04, "relative_error": 5.2}}
    verdict = quasi_static_verdict(leaking)  # a specimen springing apart: work < 0
    assert verdict["problems"] == ["energy_balance_error = 5.2 > 0.05"]
    moving = {**calm, "start_settled": False}  # loaded before its relaxation settled
    assert "still moving" in quasi_static_verdict(moving)["problems"][0]
    assert quasi_static_verdict({**calm, "start_settled": True})["ok"]
    assert set(QUASI_STATIC_LIMITS) >= {"max_kinetic_to_strain_energy", "damping_share"}


@pytest.mark.lammps
def test_a_tension_pulled_too_fast_is_flagged_not_quasi_static(tmp_path, woven_coupon):
    """Default speed: quasi-static; 200 x faster: the summary and a warning say it is not."""
    from fabmd.engine import Engine
    from fabmd.errors import QuasiStaticWarning
    from fabmd.protocols.tension import Tension
    from fabmd.scene.outputs import TrajectoryOutput

    quiet = TrajectoryOutput(frames=0)
    with pytest.warns(QuasiStaticWarning, match=r"trust only 0\.(25|5)-3"):
        slow = Tension(trajectory=quiet).run(woven_coupon.model, tmp_path / "slow",
                                             engine=Engine(progress=False))
    verdict = slow.summary["quasi_static"]
    # the whole run passes; judged per 0.25 % only the start is flagged (the fabric still
    # catching up with the clamps while it carries almost no force: drag and inertia): the
    # first 0.25 %, or 0.5 % where the coupon's relaxation stopped a check earlier (measured
    # 2026-12-06: drag share 0.11 over 0.25-0.5 %, its limit 0.1)
    assert verdict["partly"] and verdict["flagged"] in ([[0.0, 0.25]], [[0.0, 0.5]]), verdict
    assert all(p.startswith(("elongation_pct 0-0.25", "elongation_pct 0.25-0.5"))
               for p in verdict["problems"])
    assert slow.summary["start_settled"] is True
    with pytest.warns(QuasiStaticWarning, match="not quasi-static"):
        fast = Tension(speed_fraction=2e-2, trajectory=quiet).run(
            woven_coupon.model, tmp_path / "fast", engine=Engine(progress=False))
    assert not fast.summary["quasi_static"]["ok"]
    saved = json.loads((fast.run_dir / "summary.json").read_text())
    assert saved["quasi_static"]["problems"]
    assert all(spec["title"].startswith("NOT QUASI-STATIC") for spec in fast.plots)


@pytest.mark.lammps
def test_a_test_started_before_its_relaxation_settled_is_flagged(tmp_path, woven_coupon):
    """A relaxation cut short (100 steps, judged every 500) never settles: the coupon stage
    and the test both say so instead of passing a moving specimen on as a result."""
    from fabmd.engine import Engine
    from fabmd.errors import QuasiStaticWarning
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.tension import Tension
    from fabmd.scene.outputs import TrajectoryOutput
    from fabmd.scene.quasi_static import QuasiStatic

    short = QuasiStatic(max_steps=100, check_every=500)
    with pytest.warns(QuasiStaticWarning, match="did not settle"):
        coupon = Coupon(length_m=8e-3, width_m=4e-3, relax=short).run(
            woven_coupon.model, tmp_path / "coupon", engine=Engine(progress=False))
    assert coupon.summary["settled"] is False
    assert woven_coupon.summary["settled"] is True  # the default relaxation does settle
    with pytest.warns(QuasiStaticWarning, match="still moving"):
        test = Tension(relax=short, max_elongation_pct=0.5,
                       trajectory=TrajectoryOutput(frames=0)).run(
            coupon.model, tmp_path / "tension", engine=Engine(progress=False))
    assert test.summary["start_settled"] is False
    assert not test.summary["quasi_static"]["ok"]
