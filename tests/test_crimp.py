"""Crimp stage, measures and calibration on a tiny plain weave (seconds)."""

import json

import meshio
import numpy as np
import pytest

import fabmd
from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.protocols.calibrate import CrimpTargets, calibrate
from fabmd.protocols.coupon import Coupon
from fabmd.protocols.crimp import Crimp, load_crimped
from fabmd.results.measure import family_crimp, passed_through, thickness_m
from fabmd.results.trajectory import read_model
from fabmd.results.universe import data_file_bond_count
from fabmd.scene.outputs import TrajectoryOutput

from .fabrics import plain_weave_cell

pytestmark = pytest.mark.lammps


@pytest.fixture(scope="module")
def crimped(tmp_path_factory):
    loose = plain_weave_cell()
    out = tmp_path_factory.mktemp("crimp") / "run"
    result = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(loose, out,
                                                               engine=Engine(progress=False))
    return loose, result


def test_crimp_compacts_and_settles(crimped):
    loose, result = crimped
    s = result.summary
    assert s["quasi_static"], s["criterion"]
    assert s["crimped"]["thickness_m"] < 0.85 * s["loose"]["thickness_m"]
    # the yarns straighten under tension but stay wavy: crimp falls, stays > 0
    for fam in ("warp", "weft"):
        assert 0 < s["crimped"]["crimp_pct"][fam] < s["loose"]["crimp_pct"][fam]
        assert s["crimped"]["tension"][fam]["mean_fibre_tension_n"] > 0
    # the fabric lies on contact: thickness about two yarn diameters, small overlap
    d = float(loose.diameters.max())
    assert 1.85 * d < s["crimped"]["thickness_m"] < 2.05 * d
    files = {p.name for p in result.run_dir.iterdir()}
    assert {"crimped.data", "crimped.json", "summary.json", "history.csv",
            "history.png", "in.crimp"} <= files


def test_no_yarn_passes_through_another(crimped):
    loose, result = crimped
    report = passed_through(loose, result.model)
    assert report["pairs_checked"] > 0
    assert report["flipped_pairs"] == 0
    assert report["max_overlap_ratio"] < 0.1
    # the check can fail: mirror the fabric through its mid-plane
    mirrored = load_crimped(result.run_dir)
    mirrored.positions[:, 2] *= -1
    assert passed_through(loose, mirrored)["flipped_pairs"] > 0


def test_crimped_state_is_reusable_with_its_rest_lengths(crimped):
    loose, result = crimped
    again = load_crimped(result.run_dir)
    ratio = again.bond_type_table[0].rest_length_m / loose.bond_type_table[0].rest_length_m
    assert ratio == pytest.approx(0.9)
    assert again.n_bonds == loose.n_bonds
    assert json.loads((result.run_dir / "crimped.json").read_text())["info"]["crimp"]


def test_crimp_writes_its_trajectory_with_the_crimped_state_last(crimped):
    loose, result = crimped
    run_dir = result.run_dir
    assert result.summary["trajectory"] == "trajectory.h5"
    u = fabmd.load(run_dir)  # checks the bond count against model.data too
    assert len(u.bonds) == data_file_bond_count(run_dir / "model.data") == loose.n_bonds
    steps = [ts.data["step"] for ts in u.trajectory]
    # (summary "steps" is where LAMMPS stopped: the final frame)
    assert steps[0] == 0 and steps[-1] >= result.summary["steps"] and len(steps) >= 3
    assert np.all(np.diff(steps) > 0)
    # the run stopped once quasi-static: the last frame is the crimped state
    last = read_model(run_dir / "trajectory.h5")
    np.testing.assert_allclose(last.positions, load_crimped(run_dir).unwrapped_positions,
                               atol=1e-9 * float(loose.diameters.max()))
    vtu = sorted((run_dir / "paraview").glob("frame_*.vtu"))
    assert len(vtu) == len(steps)
    mesh = meshio.read(vtu[-1])
    assert len(mesh.points) == loose.n_beads
    assert "bond_force_n" in mesh.cell_data and "yarn_id" in mesh.point_data


def test_coupon_relaxation_can_write_a_trajectory(crimped, tmp_path):
    """A relaxation ends with reset_timestep, which LAMMPS refuses while a dump is open:
    the trajectory is closed right after its final frame."""
    _, result = crimped
    coupon = Coupon(length_m=6e-3, width_m=4e-3, trajectory=TrajectoryOutput(frames=4)).run(
        result.model, tmp_path / "coupon", engine=Engine(progress=False))
    assert coupon.summary["trajectory"] == "trajectory.h5"
    u = fabmd.load(coupon.run_dir)
    assert u.trajectory.n_frames >= 2 and u.trajectory[0].data["step"] == 0
    np.testing.assert_allclose(read_model(coupon.run_dir / "trajectory.h5").positions,
                               coupon.model.unwrapped_positions,
                               atol=1e-9 * float(coupon.model.diameters.max()))


def test_finite_piece_holds_fibre_ends(tmp_path):
    loose = plain_weave_cell(periodic=False)
    ends = np.unique(loose.fibre_ends().ravel())
    result = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(
        loose, tmp_path / "f", engine=Engine(progress=False))
    np.testing.assert_allclose(result.model.positions[ends], loose.positions[ends], atol=1e-12)
    assert result.summary["crimped"]["thickness_m"] < result.summary["loose"]["thickness_m"]


def test_measures_of_the_loose_cell():
    loose = plain_weave_cell()
    d = float(loose.diameters.max())
    assert thickness_m(loose) == pytest.approx(1.5 * d + d)  # crossing gap 1.5 d + one d
    c = family_crimp(loose)
    assert c["warp"] == pytest.approx(c["weft"]) and c["warp"] > 0


def test_calibration_reaches_target_thickness(tmp_path):
    loose = plain_weave_cell()
    target = 1.15e-3
    result = calibrate(loose, CrimpTargets(thickness_m=target), out=tmp_path / "cal")
    assert result.reached, result.reason
    assert result.achieved["thickness"] == pytest.approx(target, rel=0.02)
    assert len(result.runs) <= 6
    assert (tmp_path / "cal" / "calibration.json").exists()


def test_calibration_says_why_it_cannot_reach(tmp_path):
    result = calibrate(plain_weave_cell(), CrimpTargets(thickness_m=0.5e-3), max_runs=6,
                       out=tmp_path / "cal")
    assert not result.reached
    assert "change the target" in result.reason or "max_runs" in result.reason


@pytest.mark.parametrize("targets,words", [
    (dict(thickness_m=-1e-3), "calibrate.thickness_m must be > 0"),
    (dict(thickness_m=5e-3), "not below the loose fabric"),
    (dict(crimp_pct={"weft": -1.0}), "calibrate.crimp_pct.weft must be >= 0"),
    (dict(crimp_pct={"binder": 1.0}), "the fabric has"),
])
def test_bad_targets_fail_before_lammps(tmp_path, targets, words):
    with pytest.raises(InputError, match=words.replace("(", r"\(")):
        calibrate(plain_weave_cell(), CrimpTargets(**targets), out=tmp_path / "x")
    assert not (tmp_path / "x").exists()


def test_bad_expansion_is_refused():
    with pytest.raises(InputError, match="crimp.expansion.binder"):
        Crimp(expansion={"binder": -0.7})
    with pytest.raises(InputError, match="does not have"):
        Crimp(expansion={"binder": -0.1}).input_text(plain_weave_cell())


def test_periodic_cell_matches_the_interior_of_a_finite_piece(tmp_path, crimped):
    """The periodic unit cell gives the interior geometry of a large finite piece."""
    from fabmd.model.transform import tile
    from fabmd.results.measure import fabric_measures

    cell, periodic = crimped
    finite = tile(cell, 4, 4, periodic=False)
    result = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(
        finite, tmp_path / "finite", engine=Engine(progress=False))
    period = float(cell.box_hi[0] - cell.box_lo[0])
    interior = fabric_measures(result.model, edge_m=period)
    p = periodic.summary["crimped"]
    assert interior["thickness_m"] == pytest.approx(p["thickness_m"], rel=0.05)
    for fam in ("warp", "weft"):
        assert interior["crimp_pct"][fam] == pytest.approx(p["crimp_pct"][fam], rel=0.05)
    # and it is far cheaper: 16x fewer beads, fewer steps
    assert finite.n_beads == 16 * cell.n_beads
    assert result.summary["steps"] > periodic.summary["steps"]


def test_3d_example_crimps_as_a_periodic_cell_without_pass_through(tmp_path):
    """Binders shrink and compact the 3D interlock cell; no yarn goes through another."""
    from fabmd.examples_dir import example_scene
    from fabmd.pipeline import periodic_cell
    from fabmd.presets import apply_preset
    from fabmd.scenefile import load_scene

    scene = apply_preset(load_scene(example_scene("angle_interlock_3d.toml")), "fast")
    cell = periodic_cell(scene)
    assert cell.periodic[:2] == (True, True) and "binder" in cell.family_names
    result = Crimp(expansion={"binder": -0.1}, contact=scene.contact).run(
        cell, tmp_path / "c3d", engine=Engine(progress=False))
    s = result.summary
    assert s["quasi_static"]
    assert s["crimped"]["thickness_m"] < 0.95 * s["loose"]["thickness_m"]
    assert s["crimped"]["tension"]["binder"]["mean_fibre_tension_n"] > 0
    report = passed_through(cell, result.model)
    assert report["pairs_checked"] > 1000
    assert report["flipped_pairs"] == 0, report["flipped_yarns"]
