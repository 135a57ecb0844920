"""run.sh finds the mpirun and lmp of the install that wrote it (issue 19)."""

import shutil
import subprocess

import pytest

from fabmd.engine.run_script import run_sh_text

CLEAN = {"PATH": "/usr/bin:/bin", "HOME": "/tmp"}  # no virtual environment on PATH


def _folder(tmp_path):
    (tmp_path / "in.probe").write_text('print "fabmd probe ran"\n')
    (tmp_path / "run.sh").write_text(run_sh_text("in.probe"))
    return tmp_path


@pytest.mark.lammps
@pytest.mark.mpi
def test_run_sh_runs_outside_the_virtual_environment(tmp_path, mpirun):
    folder = _folder(tmp_path)
    proc = subprocess.run(["sh", str(folder / "run.sh")], env=CLEAN, capture_output=True,
                          text=True, timeout=120, cwd="/")
    assert proc.returncode == 0, proc.stderr
    assert "fabmd probe ran" in (folder / "log.lammps").read_text()
    assert "1 MPI rank(s)" in proc.stderr  # what it says is what it ran
    assert "-np 1" in proc.stderr


def test_run_sh_says_which_binary_to_put_on_path(tmp_path):
    if shutil.which("mpirun", path=CLEAN["PATH"]):
        pytest.skip("a system mpirun is on the clean PATH")
    folder = _folder(tmp_path)
    proc = subprocess.run(["sh", str(folder / "run.sh")], capture_output=True, text=True,
                          env=dict(CLEAN, MPIRUN="/nonexistent/mpirun"), timeout=60)
    assert proc.returncode == 127
    assert "put an MPI's mpirun on PATH or set MPIRUN" in proc.stderr
