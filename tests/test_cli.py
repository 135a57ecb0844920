"""The fabmd command: help, one-line errors, traceback on request."""

import pytest

from .conftest import run_cli


def test_help_lists_commands():
    out = run_cli("--help", check=True)
    assert "validate" in out.stdout and "demo" in out.stdout


@pytest.mark.parametrize("setting,words", [
    ("modulus_pa=-70e9", "material.modulus_pa must be > 0"),
    ("spacing_ratio=1.5", "spacing_ratio must be in (0, 1]"),
    ("time_step.value_s=1e-3", "above the stable time step"),
    ("time_step_s=1e-3", "--set time_step_s is now --set time_step.value_s"),
    ("diameter_m=0", "diameter_m must be > 0"),
])
def test_bad_input_is_one_line_before_lammps(tmp_path, setting, words):
    out = run_cli("validate", "fibre-tension", "--set", setting, "--out", str(tmp_path / "x"))
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fabmd: error:") and words in lines[0]
    assert not (tmp_path / "x").exists()  # nothing written, LAMMPS never started


def test_traceback_on_request(tmp_path):
    out = run_cli("--traceback", "validate", "fibre-tension", "--set", "modulus_pa=-1")
    assert "Traceback" in out.stderr and "InputError" in out.stderr
