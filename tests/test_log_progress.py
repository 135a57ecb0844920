"""Progress of the standalone back end: steps read from the running lmp's log, shown as
the in-process line (ranks, steps per second, time left)."""

import io
import subprocess

import pytest

from fabmd.engine.log_progress import LogSteps, planned_runs
from fabmd.engine.standalone import follow
from fabmd.progress import Progress

RUN_1 = """\
LAMMPS (22 Jul 2025 - Update 4)
run 2000
   Step          Time          KinEng
         0   0              0
      1000   1e-05          1e-9
      2000   2e-05          2e-9
Loop time of 0.5 on 2 procs for 2000 steps with 640 atoms
"""
RUN_2 = """\
reset_timestep 0
   Step          Time          KinEng
         0   0              0
WARNING: Fix halt condition for fix-id settled met on step 100 (src/fix_halt.cpp:247)
       500   5e-06          1e-9
"""


def test_steps_done_count_closed_runs_and_the_open_one(tmp_path):
    log = LogSteps(tmp_path / "log.lammps")
    assert log.read() == 0  # not written yet
    assert log.feed(RUN_1) == 2000
    assert log.feed(RUN_2 + "      15") == 2500  # a row LAMMPS is still writing waits
    assert log.feed("00   1.5e-05     1e-9\n") == 3500
    assert log.total([2000, 50_000, 9000]) == 2000 + 50_000 + 9000  # the second run is open
    assert log.feed("Loop time of 0.1 on 2 procs for 1200 steps with 640 atoms\n") == 3200
    assert log.total([2000, 50_000, 9000]) == 2000 + 1200 + 9000  # it halted at 1200


def test_every_run_command_is_planned():
    commands = ["units si", "run 50000", "run 2000 start 0 stop 9000 pre yes post no",
                "run 0 pre no post no", "variable run equal 3"]
    assert planned_runs(commands) == [50_000, 2000, 0]


def test_steps_are_read_as_the_log_grows(tmp_path):
    path = tmp_path / "log.lammps"
    log = LogSteps(path)
    path.write_text(RUN_1[:90])
    assert log.read() == 0
    path.write_text(RUN_1)
    assert log.read() == 2000 and log.read() == 2000


class FakeLmp:
    """A running lmp: writes a log row at each poll, exits after ``rows``."""

    def __init__(self, path, rows):
        self.path, self.rows, self.polls = path, rows, 0
        path.write_text("   Step          Time\n")

    def wait(self, timeout=None):
        if self.polls == len(self.rows):
            with open(self.path, "a") as f:
                f.write(f"Loop time of 3 on 2 procs for {self.rows[-1]} steps with 9 atoms\n")
            return 0
        with open(self.path, "a") as f:
            f.write(f"{self.rows[self.polls]:10d}   0.0\n")
        self.polls += 1
        raise subprocess.TimeoutExpired("lmp", timeout)

    def terminate(self):
        self.polls = len(self.rows)


def test_the_standalone_line_shows_ranks_steps_per_second_and_time_left(tmp_path,
                                                                          monkeypatch):
    clock = iter([0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    monkeypatch.setattr("fabmd.progress.time.perf_counter", lambda: next(clock))
    stream = io.StringIO()
    bar = Progress("tension", stream=stream, enabled=True, min_interval_s=0, ranks=2)
    lmp = FakeLmp(tmp_path / "log.lammps", [0, 1000, 3000, 5000])
    assert follow(lmp, LogSteps(lmp.path), [9000], bar, poll_s=0) == 0
    lines = stream.getvalue().split("\r")[1:]
    # the first logged step starts the clock: set-up time is not in the speed
    assert lines[0].startswith("tension: step 1000/9000") and "-:--:--" in lines[0]
    assert "step 3000/9000" in lines[1] and "2 ranks" in lines[1]
    assert "2,000 steps/s" in lines[1] and "left 0:00:03" in lines[1]
    assert "step 5000/9000" in lines[2] and "left 0:00:02" in lines[2]
    # the run ended at step 5000 (e.g. a fix halt): the line ends there, at 100 %
    assert "step 5000/5000  100.0 %" in lines[3] and lines[3].endswith("\n")


def test_an_interrupted_wait_stops_lmp(tmp_path):
    class Stuck(FakeLmp):
        def wait(self, timeout=None):
            if self.polls == len(self.rows):  # after terminate()
                return -15
            raise KeyboardInterrupt

    lmp = Stuck(tmp_path / "log.lammps", [0])
    with pytest.raises(KeyboardInterrupt):
        follow(lmp, LogSteps(lmp.path), [100], lambda done, total: None, poll_s=0)
    assert lmp.polls == 1  # terminated, then waited for


def test_a_stage_that_ends_at_its_first_report_shows_its_mean_speed_once(monkeypatch):
    """Seen on `fabmd test tension --fast`: the coupon's relaxation stopped inside its first
    chunk and its line said '0 steps/s' twice."""
    clock = iter([0.0, 2.0, 3.0])
    monkeypatch.setattr("fabmd.progress.time.perf_counter", lambda: next(clock))
    stream = io.StringIO()
    bar = Progress("coupon", stream=stream, enabled=True, min_interval_s=0)
    bar(1500, 1500)
    bar(1500, 1500)  # the end reported again (by the chunk, then by its run command)
    text = stream.getvalue()
    assert text.count("coupon: step 1500/1500") == 1 and text.endswith("\n")
    assert "1 rank  750 steps/s" in text and "left 0:00:00" in text


def test_a_relaxation_that_stops_in_its_first_chunk_ends_with_its_mean_speed(monkeypatch):
    clock = iter([0.0, 1.0, 2.0])
    monkeypatch.setattr("fabmd.progress.time.perf_counter", lambda: next(clock))
    stream = io.StringIO()
    bar = Progress("coupon", stream=stream, enabled=True, min_interval_s=0)
    bar(1500, 100_000)  # the first chunk: the relaxation's whole budget ahead
    bar(1500, 1500)  # it stopped there: the budget shrinks to the steps run
    last = stream.getvalue().split("\r")[-1]
    assert "coupon: step 1500/1500  100.0 %  1 rank  750 steps/s" in last


@pytest.mark.lammps
def test_a_standalone_run_draws_its_line_and_gives_the_in_process_result(tmp_path, monkeypatch,
                                                                         capsys):
    from fabmd.engine import Engine
    from fabmd.protocols.fibre_tension import FibreTension

    def tiny():
        return FibreTension(length_m=2e-3, max_strain=0.012, speed_fraction=1e-3)

    a = tiny().run(tmp_path / "a", engine=Engine(progress=False))
    monkeypatch.setenv("FABMD_TTY", "1")  # draw as on a terminal
    b = tiny().run(tmp_path / "b", engine=Engine(backend="standalone"))
    last = capsys.readouterr().err.split("\r")[-1]
    assert "fibre_tension: step" in last and "100.0 %  1 rank" in last and "steps/s" in last
    assert b.summary["measured_force_n"] == pytest.approx(a.summary["measured_force_n"],
                                                          rel=1e-6)
