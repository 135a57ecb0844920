"""The stable time step derived in one place (fabmd.model.timestep) and the run plan."""

import dataclasses
import math

import pytest

from fabmd.errors import InputError
from fabmd.model.beads import TimeStep, bead_parameters
from fabmd.model.contact import ContactModel, ToolContact
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.model.timestep import critical_time_step_s, stable_time_step_s
from fabmd.scenefile import parse_scene

from .test_build import minimal

BEADS = bead_parameters(VirtualFibre.solid(GLASS, 0.1e-3))


def test_stiffest_contact_sets_the_step():
    hooke, tool = ContactModel(), ToolContact(stiffness_factor=2.0)
    k = max(hooke.stability_stiffness_n_per_m([BEADS]), tool.normal_stiffness_n_per_m([BEADS]))
    assert critical_time_step_s(BEADS, [hooke, tool]) == BEADS.critical_time_step_s(k)
    assert critical_time_step_s([BEADS], [None]) == BEADS.critical_time_step_s()
    assert stable_time_step_s(BEADS, [hooke], TimeStep(factor=0.1)) == pytest.approx(
        0.1 * critical_time_step_s(BEADS, [hooke]))
    with pytest.raises(InputError, match="time_step.value_s"):
        stable_time_step_s(BEADS, [hooke], TimeStep(value_s=1.0))


def test_hertz_counts_with_its_tangent_stiffness():
    hertz = ContactModel(normal="hertz")
    tangent = hertz.stability_stiffness_n_per_m([BEADS])
    assert tangent > 2 * hertz.normal_stiffness_n_per_m([BEADS])
    assert critical_time_step_s(BEADS, [hertz]) == BEADS.critical_time_step_s(tangent)


def test_build_reports_the_step_with_the_stability_stiffness():
    """Bug of issue 15: ``fabmd build`` used the normal (secant) stiffness, 2.1× off for
    Hertz."""
    from fabmd.cli.build import summarise
    from fabmd.model.fabric_model import bead_parameter_list

    scene = parse_scene(minimal(contact={"normal": "hertz"}))
    model = scene.model()
    beads = bead_parameter_list(model, scene.fabric, scene.discretisation)
    secant = min(b.critical_time_step_s(scene.contact.normal_stiffness_n_per_m(beads))
                 for b in beads)
    reported = summarise(model, scene)["critical_time_step_s"]
    assert reported == critical_time_step_s(beads, [scene.contact])
    assert reported < 0.99 * secant  # the bonds dominate: a few % here, more on soft fibres


def test_bond_type_carries_its_stiffness():
    from fabmd.model.bead_model import BondType

    bt = BondType(BEADS.bond_coefficient, BEADS.bond_length_m, "fibre")
    assert bt.spring_n_per_m == pytest.approx(BEADS.spring_n_per_m)
    assert bt.bond_axial_stiffness_n == pytest.approx(BEADS.axial_stiffness_n)
    assert BEADS.wave_speed_m_s == pytest.approx(GLASS.wave_speed_m_s)
    assert BEADS.mass_per_length_kg_m == pytest.approx(
        VirtualFibre.solid(GLASS, 0.1e-3).mass_per_length_kg_m)
    assert math.isfinite(dataclasses.replace(bt, rest_length_m=1.0).bond_axial_stiffness_n)


def test_a_driven_plan_is_derived_once_and_kept(tmp_path, monkeypatch):
    """Tension.input_text asked for the time step 13 times and derived the bead parameters
    28 times; now the plan is derived once per model and read back from plan.json."""
    from fabmd.protocols import driven
    from fabmd.protocols.tension import Tension
    from fabmd.scene.plan import read_plan

    from .fabrics import parallel_fibres

    calls = []
    derive = driven.DrivenTest.derive_plan
    monkeypatch.setattr(driven.DrivenTest, "derive_plan",
                        lambda self, model: calls.append(1) or derive(self, model))
    test, model = Tension(clamp_length_m=0.002), parallel_fibres()
    text = test.input_text(model)
    assert len(calls) == 1
    plan = test.plan(model)
    assert f"timestep        {plan.time_step_s:.10g}" in text
    assert plan.steps % plan.every == 0 and plan.steps * plan.time_step_s == pytest.approx(
        plan.duration_s, rel=1e-6 + plan.every / plan.steps)
    assert plan.loading.time_for(test.travel_m(model)) == pytest.approx(
        plan.steps * plan.time_step_s)
    plan.write(tmp_path)
    assert read_plan(tmp_path) == plan and test.read_plan(tmp_path, model) == plan
    assert read_plan(tmp_path / "nowhere") is None
    # another model, another plan; a replaced test derives its own
    assert test.plan(parallel_fibres(n=2)) is not plan
    slower = dataclasses.replace(test, speed_fraction=test.speed_fraction / 2)
    assert slower.plan(model).steps > plan.steps and slower == slower


def test_crimp_plan_is_derived_once(monkeypatch):
    from fabmd.protocols.crimp import Crimp

    from .fabrics import plain_weave_cell

    calls = []
    derive = Crimp.derive_plan
    monkeypatch.setattr(Crimp, "derive_plan",
                        lambda self, model: calls.append(1) or derive(self, model))
    crimp, cell = Crimp(), plain_weave_cell()
    crimp.input_text(cell)
    plan = crimp.plan(cell)
    assert len(calls) == 1
    assert plan.steps == plan.extra["ramp_steps"] + crimp.quasi_static.max_steps // 4
    assert plan.every == max(1, plan.steps // crimp.samples)


@pytest.mark.lammps
def test_a_driven_run_keeps_its_plan(tmp_path):
    """The run folder holds plan.json, and the summary reports what it says."""
    from fabmd.engine import Engine
    from fabmd.protocols.tension import Tension
    from fabmd.scene.outputs import TrajectoryOutput
    from fabmd.scene.plan import read_plan

    from .fabrics import parallel_fibres

    model = parallel_fibres(n=1, length_m=4e-3)
    test = Tension(max_elongation_pct=0.5, samples=10, trajectory=TrajectoryOutput(frames=0))
    result = test.run(model, tmp_path / "t", engine=Engine(progress=False))
    plan = read_plan(result.run_dir)
    assert plan == test.plan(model)
    assert result.summary["time_step_s"] == plan.time_step_s
    assert result.summary["steps"] == plan.steps
    assert result.summary["clamp_speed_m_s"] == plan.speed_m_s
