"""The trajectory-cost benchmark runs (tiny) and edits inputs as it says."""

import importlib.util
import json
from pathlib import Path

import pytest

from fabmd.scene.outputs import TrajectoryOutput

ROOT = Path(__file__).resolve().parents[1]


def load_benchmark():
    spec = importlib.util.spec_from_file_location("trajectory_cost",
                                                  ROOT / "benchmarks" / "trajectory_cost.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_trajectory_block_is_taken_out_and_put_in():
    bench = load_benchmark()
    out = TrajectoryOutput(frames=4)
    text = "units si\n" + out.commands(100) + "\nrun 100\n" + out.final_commands() + "\nx\n"
    plain = bench.without_trajectory(text)
    assert "dump" not in plain and "run 0" not in plain and "run 100" in plain
    again = bench.with_trajectory(plain, out)
    assert again.index("fabmd_trajectory all custom 25") < again.index("run 100")
    assert again.index("run 100") < again.index("run             0 pre no post no")
    assert bench.with_trajectory(text, out) == text  # a block already there is kept


@pytest.mark.lammps
def test_benchmark_runs_on_a_tiny_sheet(tmp_path):
    bench = load_benchmark()
    report = tmp_path / "cost.json"
    assert bench.main(["--yarns", "2", "--fibres", "2x1", "--steps", "100", "--frames", "2",
                       "--json", str(report)]) == 0
    result = json.loads(report.read_text())
    assert result["frames"] == 3 and result["beads"] == 640
    assert result["trajectory_h5_mb"] > 0 and result["run_without_cpu_s"] > 0


def load_accuracy():
    import sys

    spec = importlib.util.spec_from_file_location("accuracy", ROOT / "benchmarks" / "accuracy.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["accuracy"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_accuracy_configuration_keeps_the_fabric_and_the_physical_speed():
    bench = load_accuracy()
    from fabmd.scenefile import load_scene

    base = load_scene(ROOT / "examples" / "plain_weave.toml")
    scene = bench.Config(n_fibres=19, spacing_ratio=0.25, mass_scaling=100.0,
                         speed=0.5).scene(base)
    assert scene.fabric.warp.n_fibres == 19 and scene.fabric.weft.n_fibres == 19
    assert scene.fabric.warp.spacing_m == base.fabric.warp.spacing_m
    assert scene.discretisation.spacing_ratio == 0.25
    assert scene.discretisation.mass_scaling == 100.0
    # mass scaling lowers the wave speed by sqrt(m): the fraction grows by sqrt(m)
    assert scene.protocols["tension"]["speed_fraction"] == pytest.approx(1e-4 * 0.5 * 10)
    assert scene.protocols["picture_frame"]["speed_fraction"] == pytest.approx(2e-3 * 0.5 * 10)
    assert scene.protocols["tension"]["coupon"] == {"cells": list(bench.TENSION_CELLS)}
    assert base.protocols["tension"].get("speed_fraction") is None  # base untouched


def test_accuracy_errors_and_pareto_front():
    bench = load_accuracy()
    curve = {"x": [0.0, 1.0, 2.0, 3.0], "y": [0.0, 1.0, 2.0, 3.0]}
    ref = {"tension": {"values": {"stiffness": 10.0, "F1%": 1.0, "F2%": 2.0, "F3%": 3.0},
                       "curve": curve},
           "picture_frame": {"values": {"F20°": 4.0, "F40°": 8.0, "locking": 40.0},
                             "curve": curve}}
    run = {"tension": {"values": {"stiffness": 11.0, "F1%": 1.0, "F2%": 2.0, "F3%": 3.0},
                       "curve": curve},
           "picture_frame": {"values": {"F20°": 3.0, "F40°": 8.0, "locking": None},
                             "curve": {"x": curve["x"], "y": [0.0, 1.0, 2.0, 6.0]}}}
    e = bench.relative_errors(run, ref)
    assert e["tension"]["values"]["stiffness"] == pytest.approx(0.1)
    assert e["picture_frame"]["values"]["F20°"] == pytest.approx(-0.25)
    assert e["picture_frame"]["values"]["curve"] == pytest.approx(1.0)  # 3 off at 3, of 3
    assert e["picture_frame"]["combined"] == 1.0  # no locking angle found counts as 100 %
    assert e["combined"] == 1.0
    points = [("a", 1.0, 0.5), ("b", 2.0, 0.6), ("c", 3.0, 0.1), ("d", 0.5, 0.9)]
    assert bench.pareto_front(points) == ["d", "a", "c"]
