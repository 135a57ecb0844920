"""The suite's mpirun tests take turns across pytest-xdist workers (conftest's lock)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest


def test_tests_marked_mpi_never_overlap_under_two_workers(tmp_path):
    # two tiny tests marked mpi, each recording when it held the lock; run under -n 2
    pytest.importorskip("xdist")
    suite = tmp_path / "suite"
    suite.mkdir()
    conftest = (Path(__file__).parent / "conftest.py").read_text()
    lock_fixture = conftest[conftest.index("@pytest.fixture(autouse=True)\ndef one_mpirun"):
                            conftest.index("def pytest_runtest_setup")]
    (suite / "conftest.py").write_text("import fcntl\nimport pytest\n\n\n" + lock_fixture)
    (suite / "pytest.ini").write_text("[pytest]\nmarkers =\n    mpi: starts mpirun\n")
    log = tmp_path / "spans.txt"
    (suite / "test_pair.py").write_text(textwrap.dedent(f"""
        import time
        import pytest

        @pytest.mark.mpi
        @pytest.mark.parametrize("name", ["a", "b"])
        def test_hold(name):
            start = time.monotonic()
            time.sleep(1.0)
            with open({str(log)!r}, "a") as f:
                f.write(f"{{start}} {{time.monotonic()}}\\n")
    """))
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "2",
                           "-p", "no:cacheprovider", str(suite)],
                          capture_output=True, text=True, cwd=suite, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    (a0, a1), (b0, b1) = sorted(tuple(map(float, line.split()))
                                for line in log.read_text().splitlines())
    assert b0 >= a1 - 1e-3, f"the two mpi tests overlapped: [{a0}, {a1}] and [{b0}, {b1}]"
