"""Summaries state where and why a run stopped, from LAMMPS's log (issue 19)."""

import warnings

import numpy as np
import pytest

import fabmd
from fabmd.engine import Engine
from fabmd.errors import QuasiStaticWarning
from fabmd.protocols.crimp import Crimp
from fabmd.results.folder import read_print_file
from fabmd.results.run_record import read_run_end
from fabmd.scene.outputs import TrajectoryOutput
from fabmd.scene.quasi_static import QuasiStatic

from .fabrics import plain_weave_cell

#: LAMMPS logs of relaxations and how they ended: a settled halt ends one; the damped run's
#: halt does not (its undamped run follows), so one that never reached rest spent its budget
#: (it read 'halted' before, stop 47)
_LOGS = [("run 2000\n   Step          Time          KinEng\n"
          "         0   0   1.5\n      2000   0.1   0.25\n"
          "Loop time of 0.02 on 1 procs for 2000 steps with 64 atoms\n"
          "fix settled all halt 300 v_quasi_static > 0.5 error continue message yes\n"
          "   Step          Time          KinEng\n      2000   0.1   0.25\n"
          "Fix halt condition for fix-id settled met on step 2300 with value 1\n"
          "Loop time of 0.002 on 1 procs for 300 steps with 64 atoms\n",
          2300, "quasi-static", [["settled", 2300]]),
         ("   Step          Time          KinEng\n         0   0   1.5\n"
          "Fix halt condition for fix-id damped met on step 500 with value 1\n"
          "Loop time of 0.02 on 1 procs for 500 steps with 64 atoms\n"
          "   Step          Time          KinEng\n       500   0.1   0.25\n"
          "      2500   0.5   0.20\n"
          "Loop time of 0.02 on 1 procs for 2000 steps with 64 atoms\n",
          2500, "budget", [["damped", 500]])]


@pytest.mark.parametrize("log,step,stopped_by,halts", _LOGS)
def test_log_parser_reads_the_last_thermo_line_and_the_halts(tmp_path, log, step,
                                                             stopped_by, halts):
    (tmp_path / "log.lammps").write_text(log)
    end = read_run_end(tmp_path, relaxation=True)
    assert end.final_step == step and end.stopped_by == stopped_by
    assert end.halts == halts
    assert f"{step:,}" in end.sentence()
    assert read_run_end(tmp_path / "nothing") is None


@pytest.mark.lammps
def test_crimp_that_halts_between_samples_reports_the_halt_step(tmp_path):
    # few history lines (every ~ 1000 steps), a check every 100 steps: the settled halt
    # falls between two history samples
    crimp = Crimp(expansion={"warp": -0.1, "weft": -0.1}, samples=4,
                  quasi_static=QuasiStatic(check_every=100),
                  trajectory=TrajectoryOutput(frames=3))
    result = crimp.run(plain_weave_cell(), tmp_path / "run", engine=Engine(progress=False))
    s = result.summary
    history = read_print_file(result.run_dir / "history.dat")
    last_sample = int(history["step"][-1])
    assert s["quasi_static"] and s["stopped_by"] == "quasi-static"
    assert s["steps"] % 100 == 0 and s["steps"] > s["ramp_steps"]
    assert s["steps"] != last_sample  # the summary is not the last history line
    # the trajectory's final frame (written by a dump at the end) is at that step
    steps = [ts.data["step"] for ts in fabmd.load(result.run_dir).trajectory]
    assert steps[-1] == s["steps"]
    assert s["criterion"]["final_kinetic_ratio"] < s["criterion"]["kinetic_ratio"]
    assert "quasi-static" in s["stop"]


@pytest.mark.lammps
def test_crimp_that_spends_its_budget_says_so(tmp_path):
    budget = 300
    crimp = Crimp(expansion={"warp": -0.1, "weft": -0.1}, samples=4,
                  quasi_static=QuasiStatic(kinetic_ratio=1e-30, force_ratio=1e-30,
                                           check_every=100, max_steps=budget),
                  trajectory=TrajectoryOutput(frames=0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = crimp.run(plain_weave_cell(), tmp_path / "run", engine=Engine(progress=False))
    s = result.summary
    assert not s["quasi_static"] and s["stopped_by"] == "budget"
    assert s["steps"] == s["ramp_steps"] + budget  # every planned step was run
    assert any(issubclass(w.category, QuasiStaticWarning) for w in caught)
    assert np.isfinite(s["criterion"]["final_kinetic_ratio"])


@pytest.mark.lammps
def test_coupon_summary_states_where_its_relaxation_stopped(woven_coupon):
    s = woven_coupon.summary
    end = read_run_end(woven_coupon.run_dir, relaxation=True)
    assert s["steps"] == end.final_step > 0
    assert s["stop"] == end.sentence()
    assert (end.stopped_by == "quasi-static") == bool(s["settled"])
