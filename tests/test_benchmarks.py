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
