"""Every core by default: how many ranks a command chooses, and the re-launch under mpirun
that gives them (exit status, signals, one JSON object, the same numbers)."""

import argparse
import io
import json
import os
import signal
import subprocess
import time

import pytest

from fabmd.engine import interrupt, ranks, relaunch
from fabmd.engine.ranks import MIN_BEADS_PER_RANK, choose_ranks
from fabmd.errors import InputError
from fabmd.progress import Progress

from .conftest import clean_env, fabmd_command, run_cli


@pytest.fixture
def no_env(monkeypatch):
    monkeypatch.delenv(ranks.ENV_VARIABLE, raising=False)
    return monkeypatch


def test_large_models_get_every_usable_core_small_ones_one(no_env):
    big = choose_ranks(10 * MIN_BEADS_PER_RANK, cores=2, load=0)
    assert big.ranks == 2 and "2 usable cores" in big.reason
    assert f"{10 * MIN_BEADS_PER_RANK:,} beads" in big.line()
    small = choose_ranks(MIN_BEADS_PER_RANK - 1, cores=2, load=0)
    assert small.ranks == 1 and f"{MIN_BEADS_PER_RANK:,} beads per rank" in small.reason
    # more cores than the model can use: as many ranks as it has MIN_BEADS_PER_RANK
    assert choose_ranks(3 * MIN_BEADS_PER_RANK, cores=16, load=0).ranks == 3
    assert choose_ranks(None, cores=8, load=0).ranks == 1  # size unknown: serial, and says why
    assert "--np" in choose_ranks(None, cores=8, load=0).reason
    # the line is printed for what was measured (and for every re-launch), not when told
    assert big.measured and small.measured and not choose_ranks(None, cores=8, load=0).measured


def test_np_beats_the_environment_which_beats_the_machine(no_env):
    asked = []

    def beads():
        asked.append(1)
        return 10**6

    no_env.setenv(ranks.ENV_VARIABLE, "1")
    assert choose_ranks(beads, cores=2, load=0) == ranks.RankChoice(1, "FABMD_NP=1")
    assert choose_ranks(beads, requested=2, cores=2, load=0).ranks == 2
    assert not asked  # the model is not even estimated when told
    no_env.setenv(ranks.ENV_VARIABLE, "auto")
    assert choose_ranks(beads, cores=2, load=0).ranks == 2 and asked


@pytest.mark.parametrize("value", ["0", "-2", "two"])
def test_a_bad_rank_count_is_one_line(no_env, value):
    no_env.setenv(ranks.ENV_VARIABLE, value)
    with pytest.raises(InputError, match=f"FABMD_NP must be a whole number >= 1 or 'auto', "
                                         f"got '{value}'"):
        choose_ranks(100, cores=2, load=0)
    with pytest.raises(InputError, match="--np must be a whole number >= 1, got 0"):
        choose_ranks(100, requested=0)


def test_cores_other_jobs_keep_busy_are_not_used(no_env, monkeypatch):
    """MPI ranks poll while they wait: on a loaded machine one rank beats two."""
    monkeypatch.setattr(ranks.os, "cpu_count", lambda: 2)
    busy = choose_ranks(10 * MIN_BEADS_PER_RANK, cores=2, load=1.2)
    assert busy.ranks == 1 and "1 kept busy by other jobs" in busy.reason
    assert ranks.free_cores(2, load=11.5) == 1  # never fewer than one
    monkeypatch.setattr(ranks.os, "cpu_count", lambda: 64)  # 4 of 64 cores granted:
    assert ranks.free_cores(4, load=60.0) == 4  # the others' load is on the other 60


def test_usable_cores_are_the_affinity_not_the_machine(monkeypatch):
    monkeypatch.setattr(ranks.os, "sched_getaffinity", lambda pid: {3}, raising=False)
    assert ranks.usable_cores() == 1


def test_the_demo_size_is_estimated_from_the_scene():
    """The fast demo's largest stage is its picture frame: 972 beads (as it runs)."""
    from fabmd.cli.ranks import model_beads

    fast = model_beads(argparse.Namespace(command="demo", scene=None, preset="fast"))
    assert fast == 972
    full = model_beads(argparse.Namespace(command="demo", scene=None, preset="default"))
    assert full > 2 * MIN_BEADS_PER_RANK  # the full demo runs on 2 cores here
    assert model_beads(argparse.Namespace(command="validate")) is None


def test_relaunch_command_and_environment(monkeypatch):
    monkeypatch.setattr(relaunch, "mpirun_executable", lambda: "/x/mpirun")
    cmd = relaunch.command_line(["demo", "--out", "d"], 2)
    assert cmd[:3] == ["/x/mpirun", "-np", "2"] and cmd[-5:] == ["-m", "fabmd", "demo",
                                                                   "--out", "d"]
    env = relaunch.relaunch_environment(2)
    assert env["FABMD_NP"] == "2" and env[relaunch.RELAUNCHED_VARIABLE] == "1"


def test_relaunched_ranks_take_sigusr1_for_the_sigterm_it_was(monkeypatch):
    monkeypatch.setenv(relaunch.RELAUNCHED_VARIABLE, "1")
    with interrupt.catching():
        signal.raise_signal(interrupt.FORWARDED_SIGTERM)
        assert interrupt.received() == "SIGTERM" and interrupt.stop_requested()
    monkeypatch.delenv(relaunch.RELAUNCHED_VARIABLE)
    with interrupt.catching():  # a plain command leaves SIGUSR1 alone
        assert signal.getsignal(interrupt.FORWARDED_SIGTERM) is not interrupt._handler


def test_progress_line_shows_ranks_speed_and_time_left(monkeypatch):
    clock = iter([0.0, 1.0, 3.0])
    monkeypatch.setattr("fabmd.progress.time.perf_counter", lambda: next(clock))
    stream = io.StringIO()
    bar = Progress("tension", stream=stream, enabled=True, min_interval_s=0, ranks=2)
    bar(1000, 9000)  # the start of a resumed run: speed from here
    bar(5000, 9000)
    line = stream.getvalue().split("\r")[-1]
    assert "tension: step 5000/9000" in line and "2 ranks" in line
    assert "2,000 steps/s" in line and "left 0:00:02" in line


def test_progress_is_drawn_for_a_relaunched_command(monkeypatch):
    monkeypatch.setenv(relaunch.TTY_VARIABLE, "1")
    assert Progress("x", stream=io.StringIO()).enabled
    monkeypatch.delenv(relaunch.TTY_VARIABLE)
    assert not Progress("x", stream=io.StringIO()).enabled


# -- the re-launch, for real (mpirun, LAMMPS) ------------------------------------------------

TINY = ["--set", "spacing_ratio=0.5"]


@pytest.mark.lammps
@pytest.mark.mpi
def test_np_2_relaunches_under_mpirun_with_the_one_rank_numbers(tmp_path, mpirun):
    one = run_cli("validate", "fibre-tension", "--json", "--np", "1", "--out",
                  str(tmp_path / "one"))
    two = run_cli("validate", "fibre-tension", "--json", "--np", "2", "--out",
                  str(tmp_path / "two"))
    assert one.returncode == 0, one.stderr
    assert two.returncode == 0, two.stderr
    assert "fabmd: 2 MPI ranks (--np)" in two.stderr
    r1, r2 = json.loads(one.stdout), json.loads(two.stdout)  # exactly one JSON object
    assert r1["ranks"] == 1 and r2["ranks"] == 2
    # the MPI tolerance of tests/test_engine.py
    assert r2["measured_force_n"] == pytest.approx(r1["measured_force_n"], rel=1e-6)


@pytest.mark.lammps
@pytest.mark.mpi
def test_relaunched_errors_pass_their_exit_status_and_print_once(tmp_path, mpirun):
    out = run_cli("validate", "fibre-tension", "--np", "2", "--set", "spacing_ratio=-1",
                  "--out", str(tmp_path / "bad"))
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("fabmd: error:") == 1


@pytest.mark.lammps
@pytest.mark.mpi
@pytest.mark.slow
def test_sigterm_to_a_relaunched_command_stops_every_rank_and_resume_finishes(tmp_path,
                                                                             mpirun):
    from .test_interrupt import tiny

    path, _ = tiny(tmp_path)
    out = tmp_path / "run"
    args = ["test", "tension", str(path), "--out", str(out), "--quiet", "--np", "2"]
    proc = subprocess.Popen(fabmd_command() + args, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=clean_env())
    deadline = time.time() + 120
    while not (out / "crimp" / "log.lammps").exists() and time.time() < deadline:
        time.sleep(0.02)  # every rank catches signals once LAMMPS (collective) has started
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 5, err
    assert "SIGTERM" in err and "--resume" in err and err.count("fabmd: error:") == 1
    resumed = run_cli("test", "tension", str(path), "--out", str(out), "--resume",
                      "--quiet", "--np", "2")
    assert resumed.returncode == 0, resumed.stderr
    assert (out / "tension" / "summary.json").exists()


def test_without_mpirun_the_default_runs_serially_and_says_so(monkeypatch, capsys):
    import fabmd.engine.library as library
    from fabmd.cli import ranks as cli_ranks
    from fabmd.errors import EngineUnavailable

    def missing():
        raise EngineUnavailable("no mpirun")

    monkeypatch.delenv(ranks.ENV_VARIABLE, raising=False)
    monkeypatch.setattr(library, "mpirun_executable", missing)
    monkeypatch.setattr(ranks, "free_cores", lambda cores, load=None: cores)
    monkeypatch.setattr(ranks, "usable_cores", lambda: 2)
    monkeypatch.setattr(cli_ranks, "_estimate", lambda args: 10**6)
    monkeypatch.setattr(relaunch, "under_mpirun", lambda: False)
    args = argparse.Namespace(command="demo", ranks=None, backend="inprocess", threads=1)
    assert cli_ranks.relaunch_if_worth_it(args, ["demo"]) is None
    assert "no mpirun" in capsys.readouterr().err


# -- busy cores now, not a minute ago ---------------------------------------------------------

def _stat(user, nice, system, idle, iowait=0):
    return (f"cpu  {user} {nice} {system} {idle} {iowait} 0 0 0 0 0\n"
            f"cpu0 {user} {nice} {system} {idle} {iowait} 0 0 0 0 0\nintr 1 2 3\n")


def test_busy_cores_come_from_two_samples_of_proc_stat(monkeypatch):
    """One other job on a 2-core machine over the window: one busy core, whatever the
    load average says (it still counts a run that ended a minute ago)."""
    monkeypatch.setattr(ranks.os, "cpu_count", lambda: 2)
    samples = iter([_stat(1000, 50, 100, 5000, 10), _stat(1040, 50, 100, 5040, 10)])
    slept = []
    busy = ranks.busy_cores(0.4, read=lambda: next(samples), sleep=slept.append)
    assert busy == pytest.approx(1.0) and slept == [0.4]
    # niced jobs count as busy, iowait as idle
    samples = iter([_stat(0, 0, 0, 0, 0), _stat(0, 20, 0, 40, 20)])
    assert ranks.busy_cores(read=lambda: next(samples), sleep=lambda s: None) == \
        pytest.approx(0.5)
    # a quiet machine now: every core free even with a high 1-minute load average
    monkeypatch.setattr(ranks.os, "getloadavg", lambda: (1.9, 1.0, 0.5))
    monkeypatch.setattr(ranks, "busy_cores", lambda: 0.1)
    assert ranks.free_cores(2) == 2
    monkeypatch.setattr(ranks, "busy_cores", lambda: 0.8)
    assert ranks.free_cores(2) == 1


@pytest.mark.skipif(not os.path.exists("/proc/stat"), reason="no /proc/stat (not Linux)")
def test_busy_cores_reads_this_machine():
    busy = ranks.busy_cores(0.05)
    assert busy is not None and 0.0 <= busy <= (os.cpu_count() or 1) + 1e-9


def test_without_proc_stat_the_load_average_decides(monkeypatch):
    monkeypatch.setattr(ranks.os, "cpu_count", lambda: 2)

    def missing():
        raise OSError("no /proc/stat")

    assert ranks.busy_cores(read=missing, sleep=lambda s: None) is None
    assert ranks.busy_cores(read=lambda: "intr 1\n", sleep=lambda s: None) is None
    monkeypatch.setattr(ranks, "busy_cores", lambda: None)
    monkeypatch.setattr(ranks.os, "getloadavg", lambda: (1.2, 0.0, 0.0))
    assert ranks.free_cores(2) == 1
    monkeypatch.setattr(ranks.os, "getloadavg", lambda: (0.2, 0.0, 0.0))
    assert ranks.free_cores(2) == 2
