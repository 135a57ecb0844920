"""A drape run converts its trajectory once (issue 15: ``Drape.run`` used to finalise again
after ``DrivenTest.run``) and keeps its run plan; checked without LAMMPS: a stand-in engine
and reduction."""

from __future__ import annotations

import sys
from types import SimpleNamespace

import numpy as np
import pytest

from fabmd.errors import SimulationFailed
from fabmd.protocols import driven
from fabmd.protocols.drape import Drape
from fabmd.scene.outputs import TrajectoryOutput

from .fabrics import plain_weave_cell
from .test_drape import SMALL


class StandInEngine:
    """Runs nothing: returns what ``Engine.run`` returns, or fails like a blown-up run."""

    def __init__(self, fail: bool = False):
        self.fail = fail

    def run(self, run_dir, input_name, **kwargs):
        if self.fail:
            raise SimulationFailed("stand-in failure", run_dir=run_dir)
        return SimpleNamespace(wall_s=0.0, ranks=1, backend="stand-in")


@pytest.fixture
def conversions(monkeypatch):
    """Count the calls of the trajectory conversion (finalise, salvage) from any protocol
    module that imported them."""
    from fabmd.results import trajectory

    calls = []
    for name, module in list(sys.modules.items()):
        if not name.startswith("fabmd.protocols"):
            continue
        for func in ("finalise", "salvage"):
            if getattr(module, func, None) is getattr(trajectory, func):
                monkeypatch.setattr(module, func,
                                    lambda run_dir, _f=func, **kw: calls.append(_f))
    return calls


@pytest.fixture
def blank():
    from fabmd.model.transform import cut, tile

    return cut(tile(plain_weave_cell(), 7, 7, periodic=False), 26e-3, 26e-3)


def stand_in_reduce(self, run_dir, model, monitor=None):
    curve = {"depth_m": np.zeros(3), "punch_force_n": np.zeros(3)}
    return driven.DrivenResult(run_dir, curve, {"protocol": "drape"}, [])


def test_a_drape_converts_its_trajectory_once(blank, conversions, monkeypatch, tmp_path):
    monkeypatch.setattr(Drape, "reduce", stand_in_reduce)
    drape = Drape(**SMALL, trajectory=TrajectoryOutput(frames=2, paraview=False))
    result = drape.run(blank, tmp_path / "drape", engine=StandInEngine())
    assert conversions == ["finalise"]
    assert (result.run_dir / "summary.json").exists()


def test_a_failed_drape_salvages_its_frames_once(blank, conversions, tmp_path):
    drape = Drape(**SMALL, trajectory=TrajectoryOutput(frames=2, paraview=False))
    with pytest.raises(SimulationFailed):
        drape.run(blank, tmp_path / "drape", engine=StandInEngine(fail=True))
    assert conversions == ["salvage"]


def test_a_drape_plans_once_with_its_tools(blank, monkeypatch, tmp_path):
    """The drape's time step, output interval and damping come from the one plan (issue 15:
    it overrode them): bounded by the stiffer of fibre and tool contact, the interval a
    multiple of the means' sampling interval, τ the whole draw; the run folder keeps it."""
    from fabmd.model.timestep import stable_time_step_s
    from fabmd.protocols.drape.input import SAMPLE_EVERY
    from fabmd.scene.plan import read_plan

    calls = []
    derive = driven.DrivenTest.derive_plan
    monkeypatch.setattr(driven.DrivenTest, "derive_plan",
                        lambda self, model: calls.append(1) or derive(self, model))
    monkeypatch.setattr(Drape, "reduce", stand_in_reduce)
    drape = Drape(**SMALL, trajectory=TrajectoryOutput(frames=2, paraview=False))
    model = drape.prepare(blank)
    text = drape.input_text(model)
    plan = drape.plan(model)
    assert len(calls) == 1
    assert plan.time_step_s == stable_time_step_s(model, (drape.contact, drape.tool),
                                                  drape.time_step)
    assert plan.time_step_s <= stable_time_step_s(model, (drape.contact,), drape.time_step)
    assert f"timestep        {plan.time_step_s:.10g}" in text
    assert plan.every % SAMPLE_EVERY == 0 and plan.steps % plan.every == 0
    assert plan.every == SAMPLE_EVERY * max(
        1, int(np.ceil(plan.duration_s / plan.time_step_s)) // drape.samples // SAMPLE_EVERY)
    assert plan.damping_time_s == plan.duration_s == drape.duration_s(model)
    assert plan.gamma_kg_s == pytest.approx(float(np.median(model.masses)) / plan.duration_s)
    assert Drape(**SMALL, damping_time_s=1.0).plan(model).damping_time_s == 1.0
    result = drape.run(blank, tmp_path / "drape", engine=StandInEngine())
    assert read_plan(result.run_dir) == plan
