"""A drape run converts its trajectory once (issue 15: ``Drape.run`` used to finalise again
after ``DrivenTest.run``); checked without LAMMPS: a stand-in engine and reduction."""

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
