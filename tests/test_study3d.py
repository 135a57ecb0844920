"""examples/interlock_3d_study/: its scene is the through-thickness example at the study's
discretisation, it builds and passes every check, and the study runs end to end on its
quick setting."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
STUDY = ROOT / "examples" / "interlock_3d_study"
SCENE = STUDY / "interlock_3d_study.toml"
EXAMPLE = ROOT / "examples" / "through_thickness_3d.toml"
#: 2 ranks sum forces in another order; measured: 6e-7 of the peak on the quick coupon
MPI_TOLERANCE = 1e-4


def study_module():
    spec = importlib.util.spec_from_file_location("run_study", STUDY / "run_study.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_study_scene_is_the_example_but_for_its_discretisation_and_tests():
    study, example = (tomllib.loads(p.read_text()) for p in (SCENE, EXAMPLE))
    for table in ("fabric", "materials", "contact", "crimp"):
        assert study[table] == example[table], table
    assert study["yarns"].keys() == example["yarns"].keys()
    for family, spec in study["yarns"].items():
        assert spec["n_fibres"] == 1
        assert {k: v for k, v in spec.items() if k != "n_fibres"} == \
            {k: v for k, v in example["yarns"][family].items() if k != "n_fibres"}
    assert study["discretisation"] == {**example["discretisation"], "spacing_ratio": 1.0}
    assert study["tension"]["coupon"] == {"length_m": "120 mm", "width_m": "50 mm"}
    assert study["picture_frame"]["coupon"] == {"length_m": "40 mm", "width_m": "40 mm"}


@pytest.mark.parametrize("periodic", [False, True])
def test_the_study_scene_builds_without_overlap_and_passes_the_checks(periodic):
    from fabmd.model.fabric_model import render_fabric
    from fabmd.preflight import check_scene, check_test, plan_test
    from fabmd.scenefile import load_scene

    scene = load_scene(SCENE)
    check_scene(scene)
    for test in ("tension", "picture-frame"):
        check_test(scene, test, plan_test(scene, test))
    fabric = dataclasses.replace(scene.fabric, periodic=periodic)
    m = render_fabric(fabric, scene.discretisation)  # raises on any overlap
    assert not m.info.get("auto_clearance_gap_short", False)
    assert m.info["clearance_m"] > 0
    assert m.n_beads == 2360  # the README's figure


def test_the_quick_setting_replaces_only_the_test_tables():
    study = study_module()
    full, quick = study.study_scene(), study.study_scene(quick=True)
    assert quick.fabric == full.fabric and quick.discretisation == full.discretisation
    assert quick.protocols["crimp"] == full.protocols["crimp"]
    assert quick.protocols["tension"]["coupon"] == {"length_m": "48 mm", "width_m": "20 mm"}
    assert full.protocols["tension"]["coupon"] == {"length_m": "120 mm", "width_m": "50 mm"}


def test_the_midplane_of_a_flat_and_a_wavy_sheet(tmp_path):
    """The wrinkling measure: zero for a flat sheet, the amplitude for a wavy one."""
    study = study_module()
    xs = np.arange(0, 0.04, 0.0005)
    sheets = {}
    for name, amp in (("flat", 0.0), ("wavy", 0.002)):
        x, y = np.meshgrid(xs, xs)
        z = amp * np.sin(2 * np.pi * x / 0.04)
        sheets[name] = np.concatenate([np.c_[x.ravel(), y.ravel(), z.ravel() + dz]
                                       for dz in (0.0, 0.003)])
    for name, points in sheets.items():
        out = study.midplane_of(points, 0.001)
        if name == "flat":
            assert out["max_deviation_m"] < 1e-12
            assert out["mean_thickness_m"] == pytest.approx(0.004)
        else:
            assert out["max_deviation_m"] == pytest.approx(0.002, rel=0.1)


@pytest.fixture(scope="module")
def quick_study(tmp_path_factory):
    """The quick setting's cell and tension stages (about 30 s on one loaded core)."""
    study = study_module()
    out = tmp_path_factory.mktemp("study") / "q"
    t0 = time.perf_counter()
    results = study.run(out, stages=("cell", "tension"), quick=True)
    return study, out, results, time.perf_counter() - t0


@pytest.mark.lammps
@pytest.mark.slow
def test_the_quick_study_runs_end_to_end(quick_study):
    study, out, results, wall = quick_study
    saved = json.loads((out / "study.json").read_text())
    assert saved["quick"] is True and saved["tension"]["beads"] == results["tension"]["beads"]
    cell = saved["cell"]
    assert cell["beads"] == 2360 and cell["steps"] > 0
    assert cell["pass_through"]["flipped_pairs"] == 0
    assert cell["thickness_m"]["crimped"] < cell["thickness_m"]["loose"]
    assert set(cell["crimp_pct"]) == {"warp", "weft", "binder"}
    assert cell["crimp_pct"]["binder"] > 1
    assert cell["yarn_tension_cn_per_tex"]["binder"] > 0
    t = saved["tension"]
    assert t["rises"] and t["max_force_n"] > 0 and t["steps"] > 0 and t["ranks"] == [1]
    assert t["force_at_elongation_n"]["2"] > t["force_at_elongation_n"]["0.5"]
    assert {"ok", "intervals", "failed_intervals"} <= t["quasi_static"].keys()
    assert t["midplane"]["last"]["mean_thickness_m"] > 0
    assert (out / "tension" / "tension" / "run.sh").exists()
    assert all(Path(f).exists() for f in saved["figures"])
    assert "| (c) tension 48 mm × 20 mm |" in study.table(saved)
    assert wall < 90, wall  # the quick setting stays quick (about 30 s here, loaded)


@pytest.mark.lammps
@pytest.mark.slow
@pytest.mark.mpi
def test_the_quick_tension_folder_runs_under_mpirun_with_the_same_curve(quick_study, mpirun):
    study, out, _, _ = quick_study
    r = study.stage_mpirun(study.study_scene(quick=True), out, ranks=2)
    assert r["lammps_ranks"] == [2] and r["run_sh"]
    assert r["max_force_difference_over_peak"] < MPI_TOLERANCE
