"""The LAMMPS engine: loading, capabilities, errors, both back ends."""

import json
import subprocess
import sys

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import OutputExists, SimulationFailed, UnstableRun
from fabmd.protocols.common import write_run_folder
from fabmd.protocols.fibre_tension import FibreTension

from .conftest import clean_env, run_cli

pytestmark = pytest.mark.lammps


def test_lammps_loads_without_ld_library_path():
    code = ("import fabmd, lammps; l = lammps.lammps(cmdargs=['-log','none','-screen','none']);"
            "print(l.version()); l.close()")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=clean_env(), check=True)
    assert int(out.stdout.strip()) >= 20250722


def test_engine_has_what_fabmd_needs():
    from fabmd.engine.library import check_engine

    assert check_engine()


def tiny_test() -> FibreTension:
    return FibreTension(length_m=2e-3, max_strain=0.012, speed_fraction=1e-3)


def test_lammps_error_names_run_folder_and_line(tmp_path):
    test = tiny_test()
    model = test.model()
    bad = test.input_text(model).replace("bond_style      harmonic", "bond_style      nonsense")
    run_dir = write_run_folder(tmp_path / "bad", "fibre_tension", model, bad, {})
    with pytest.raises(SimulationFailed) as err:
        Engine(progress=False).run(run_dir, "in.fibre_tension")
    assert str(run_dir) in str(err.value)
    assert err.value.lammps_error.startswith("ERROR:")
    assert "nonsense" in err.value.lammps_error


@pytest.mark.parametrize("backend", ["inprocess", "standalone"])
def test_unstable_run_is_stopped_with_cause(tmp_path, backend):
    """A time step 3x the critical one blows up and is caught, with a remedy."""
    test = tiny_test()
    model = test.model()
    dt = test.time_step_s
    text = test.input_text(model).replace(f"timestep        {dt:.10g}",
                                          f"timestep        {12 * dt:.10g}")
    run_dir = write_run_folder(tmp_path / backend, "fibre_tension", model, text, {})
    with pytest.raises(UnstableRun) as err:
        Engine(backend=backend, progress=False).run(run_dir, "in.fibre_tension")
    assert err.value.cause in {"speed", "bond_stretch", "nan", "lost_atoms"}
    assert "time step" in str(err.value) or "time_step" in str(err.value)


def test_results_folder_is_never_overwritten(tmp_path):
    out = tmp_path / "run"
    tiny_test().run(out, engine=Engine(progress=False))
    before = (out / "summary.json").read_text()
    with pytest.raises(OutputExists, match="--overwrite"):
        tiny_test().run(out, engine=Engine(progress=False))
    assert (out / "summary.json").read_text() == before
    # a folder that is not fabmd's is never deleted, even with overwrite
    other = tmp_path / "precious"
    other.mkdir()
    (other / "thesis.tex").write_text("x")
    with pytest.raises(OutputExists, match="not a fabmd results folder"):
        tiny_test().run(other, engine=Engine(progress=False), overwrite=True)
    assert (other / "thesis.tex").exists()


def test_fibre_tension_matches_closed_form_and_writes_results(tmp_path):
    result = FibreTension().run(tmp_path / "ft", engine=Engine(progress=False))
    s = result.summary
    assert s["rel_error"] <= 0.01
    assert s["max_kinetic_to_strain_energy"] < 0.05
    for name in ("scene.json", "in.fibre_tension", "log.lammps", "curve.csv", "summary.json",
                 "curve.png", "model.data", "run.sh"):
        assert (tmp_path / "ft" / name).exists(), name
    summary = json.loads((tmp_path / "ft" / "summary.json").read_text())
    assert "measured_force_n" in summary and "check_strain_pct" in summary
    # the force-strain curve is linear with slope EA over the whole run
    c = result.curve
    loaded = c["strain_pct"] > 0.2
    slope = np.polyfit(c["strain_pct"][loaded] / 100, c["force_n"][loaded], 1)[0]
    assert slope == pytest.approx(s["axial_stiffness_n"], rel=0.01)


def test_standalone_run_folder_reproduces_inprocess_force(tmp_path):
    a = tiny_test().run(tmp_path / "a", engine=Engine(progress=False))
    b = tiny_test().run(tmp_path / "b", engine=Engine(backend="standalone"))
    assert b.summary["measured_force_n"] == pytest.approx(a.summary["measured_force_n"],
                                                          rel=1e-6)


def test_cli_validate_fibre_tension_json(tmp_path):
    out = run_cli("validate", "fibre-tension", "--json", "--out", str(tmp_path / "v"))
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert {"expected_force_n", "measured_force_n", "rel_error"} <= result.keys()
    assert result["rel_error"] <= 0.01


@pytest.mark.mpi
def test_two_mpi_ranks_give_the_one_rank_force(tmp_path, mpirun):
    one = run_cli("validate", "fibre-tension", "--json", "--out", str(tmp_path / "one"))
    two = run_cli("validate", "fibre-tension", "--json", "--out", str(tmp_path / "two"),
                  mpi_ranks=2)
    assert one.returncode == 0 and two.returncode == 0, two.stderr
    r1, r2 = json.loads(one.stdout), json.loads(two.stdout)  # exactly one JSON object
    assert r2["ranks"] == 2
    assert r2["measured_force_n"] == pytest.approx(r1["measured_force_n"], rel=1e-6)
