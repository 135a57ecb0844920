"""Trajectories: the LAMMPS block, trajectory.h5 (H5MD), fabmd.load, ParaView files, MPI."""

import json
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

import fabmd
import fabmd.results.universe
from fabmd import analysis as A
from fabmd.analysis.synthetic import woven_sheet
from fabmd.engine import Engine
from fabmd.engine.lammps_dump import iter_dump
from fabmd.errors import InputError, UnstableRun
from fabmd.protocols.fibre_tension import FibreTension
from fabmd.results.trajectory import (
    BASE_VERSION,
    FORMAT_VERSION,
    Frame,
    TrajectoryFormatError,
    open_trajectory,
    read_lengths,
    read_model,
    read_tilt,
    write_snapshot,
    write_trajectory,
)
from fabmd.results.universe import data_file_bond_count
from fabmd.scene import blocks
from fabmd.scene.outputs import TrajectoryOutput

from .conftest import clean_env, run_cli
from .synthetic_runs import free_run

TINY = ("--set", "length_m=2e-3", "--set", "max_strain=0.012", "--set", "speed_fraction=1e-3",
        "--set", "trajectory_frames=6")


def tiny_tension(**kwargs) -> FibreTension:
    kwargs.setdefault("trajectory", TrajectoryOutput(frames=6))
    return FibreTension(length_m=2e-3, max_strain=0.012, speed_fraction=1e-3, **kwargs)


# -- command text (no LAMMPS) ---------------------------------------------------------------
def test_trajectory_block_text():
    text = blocks.trajectory(25, velocities=True)
    assert ("dump            fabmd_trajectory all custom 25 trajectory.bin "
            "id mol type xu yu zu vx vy vz") in text
    assert "dump_modify     fabmd_trajectory sort id time yes" in text
    assert "dump            fabmd_bonds all local 25 bonds.dump" in text
    assert "{{" not in text and "# >>> fabmd trajectory" in text
    plain = blocks.trajectory(25, bond_forces=False)
    assert "vx" not in plain and "fabmd_bonds" not in plain
    final = blocks.trajectory_final()
    # "pre no": the zero-step run sets nothing up again, so fix print writes no line twice
    assert "dump_modify     fabmd_bonds every 1" in final
    assert "run             0 pre no post no" in final and "undump" not in final
    assert "fabmd_bonds" not in blocks.trajectory_final(bond_forces=False)
    closed = blocks.trajectory_final(close=True)  # before a reset_timestep
    assert "undump          fabmd_trajectory\nundump          fabmd_bonds" in closed


def test_trajectory_output_cadence_and_validation():
    out = TrajectoryOutput(frames=50)
    assert out.every(10_000) == 200 and out.every(10) == 1
    assert TrajectoryOutput(every_steps=7).every(10_000) == 7
    # on a driven test's output steps: rounded up to a multiple of its interval
    assert out.every(10_000, multiple_of=30) == 210 and out.every(10, multiple_of=30) == 30
    assert TrajectoryOutput(every_steps=7).every(10_000, multiple_of=30) == 7
    off = TrajectoryOutput(frames=0)
    assert not off.enabled and "dump" not in off.commands(1000)
    assert "dump" not in off.final_commands()
    assert TrajectoryOutput(frames=3.0).frames == 3
    with pytest.raises(InputError, match="trajectory.frames"):
        TrajectoryOutput(frames=-1)
    with pytest.raises(InputError, match="trajectory.every_steps"):
        TrajectoryOutput(every_steps=0)
    assert "fabmd_trajectory" in tiny_tension().input_text(tiny_tension().model())


def test_import_fabmd_stays_light():
    code = ("import sys, fabmd; print('MDAnalysis' in sys.modules, 'h5py' in sys.modules, "
            "callable(fabmd.load))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=clean_env(), check=True)
    assert out.stdout.split() == ["False", "False", "True"]


# -- trajectory.h5 without LAMMPS -----------------------------------------------------------
def test_snapshot_is_h5md_and_loads_with_yarns_as_segments(tmp_path):
    model = woven_sheet(fibres=(3, 2))
    path = write_snapshot(model, tmp_path / "sheet.h5", paraview_dir=tmp_path)
    with open_trajectory(path) as f:
        assert list(f["h5md"].attrs["version"]) == [1, 1]
        assert f.attrs["fabmd_format_version"] == BASE_VERSION == FORMAT_VERSION
        assert "box_tilt" not in f["observables"]
        assert f["particles/all/position/value"].attrs["unit"] == "nm"
        assert f["particles/all/position/value"].compression == "gzip"
        assert list(f["particles/all/box"].attrs["boundary"]) == ["periodic", "periodic",
                                                                  "none"]
        assert f["connectivity/bonds"].shape == (model.n_bonds, 2)
    back = read_model(path)  # SI again, to an ulp (stored in nm)
    np.testing.assert_allclose(back.positions, model.unwrapped_positions, rtol=4e-16, atol=0)
    np.testing.assert_allclose(back.diameters, model.diameters, rtol=4e-16)
    assert [y.name for y in back.yarns] == [y.name for y in model.yarns]

    u = fabmd.load(path)
    assert len(u.bonds) == model.n_bonds
    assert u.atoms.n_residues == model.n_fibres and len(u.segments) == len(model.yarns)
    warp = u.select_atoms("segid warp-*")
    assert warp.n_atoms == len(model.beads_of_family("warp"))
    assert u.select_atoms("resname weft").n_atoms == len(model.beads_of_family("weft"))
    assert u.select_atoms("segid weft-1").n_atoms == model.n_beads // 4
    assert u.select_atoms("type warp").n_atoms == warp.n_atoms
    frame = A.FabricFrame.from_universe(u)
    assert frame.closed.all()
    assert A.crimp_by_family(frame)["weft"] == pytest.approx(
        A.crimp_by_family(A.FabricFrame.from_model(model))["weft"], rel=1e-4)


def test_a_sheared_cell_keeps_its_box_tilt(tmp_path):
    model = woven_sheet(fibres=(3, 2))
    lx, ly, lz = model.box_hi - model.box_lo
    xy = 0.3 * ly
    frames = [Frame(step=s, time=1e-6 * s, box_lo=model.box_lo, box_hi=model.box_hi,
                    positions=model.unwrapped_positions, tilt=np.array([t, 0.0, 0.0]))
              for s, t in ((0, 0.0), (10, xy))]
    path = tmp_path / "trajectory.h5"
    write_trajectory(path, model, frames)
    with open_trajectory(path) as f:
        assert f.attrs["fabmd_format_version"] == FORMAT_VERSION
        assert f["observables/box_tilt/value"].attrs["unit"] == "nm"
    assert read_tilt(path, 0) == pytest.approx([0, 0, 0])
    assert read_tilt(path) == pytest.approx([xy, 0, 0])
    u = fabmd.load(path)
    u.trajectory[1]
    assert u.trajectory.ts.triclinic_dimensions[1] == pytest.approx([xy, ly, 0], rel=1e-6)
    assert u.dimensions[5] == pytest.approx(np.degrees(np.arctan2(ly, xy)), rel=1e-6)
    frame = A.FabricFrame.from_universe(u)
    assert frame.box_lengths == pytest.approx([lx, ly, lz], rel=1e-6)  # the untilted cell


def as_version_2(path, old):
    """A copy of a version-3 file as fabmd wrote it before the units module (metres)."""
    shutil.copy(path, old)
    with h5py.File(old, "a") as f:
        f.attrs["fabmd_format_version"] = 2
        for name in ("length_unit", "length_scale_m"):
            del f.attrs[name]
        del f["h5md/modules"]
        for ds in ("particles/all/position/value", "particles/all/box/edges/value",
                   "particles/all/diameter", "observables/box_offset/value"):
            f[ds][...] = f[ds][()] * 1e-9
            f[ds].attrs["unit"] = "m"


def test_stock_mdanalysis_reads_the_trajectory(tmp_path):
    """MDAnalysis's own H5MD reader (no fabmd code) loads the positions: the file declares
    the units module and stores lengths in nm; fabmd's readers give the same in SI; a
    version-2 file (metres, before the units module) still reads the same."""
    import MDAnalysis as mda

    model = woven_sheet(fibres=(3, 2))
    shifted = model.unwrapped_positions + np.array([0.0, 0.0, 1e-4])
    frames = [Frame(step=s, time=1e-6 * s, box_lo=model.box_lo, box_hi=model.box_hi,
                    positions=p) for s, p in ((0, model.unwrapped_positions), (7, shifted))]
    path = tmp_path / "trajectory.h5"
    write_trajectory(path, model, frames)
    with h5py.File(path) as f:
        assert list(f["h5md/modules/units"].attrs["version"]) == [1, 0]
        assert f["h5md/author"].attrs["name"] not in ("", "fabmd")  # a person, not the program
        assert f.attrs["length_scale_m"] == 1e-9
    stock = mda.Universe.empty(model.n_beads, trajectory=False)
    stock.load_new(str(path), format="H5MD")  # converts nm to its own unit, the ångström
    ours = fabmd.load(path)
    assert stock.trajectory.n_frames == ours.trajectory.n_frames == 2
    for i, expected in enumerate((model.unwrapped_positions, shifted)):
        stock.trajectory[i]
        ours.trajectory[i]
        # float32 positions in both readers: compare to single precision
        np.testing.assert_allclose(stock.atoms.positions * 1e-10, expected, rtol=1e-6,
                                   atol=1e-6 * np.abs(expected).max())
        np.testing.assert_allclose(ours.atoms.positions, stock.atoms.positions * 1e-10,
                                   rtol=1e-6, atol=1e-6 * np.abs(expected).max())
        np.testing.assert_allclose(stock.dimensions[:3] * 1e-10, model.box_hi - model.box_lo,
                                   rtol=1e-6)
    old = tmp_path / "v2.h5"
    as_version_2(path, old)
    np.testing.assert_allclose(read_model(old).positions, shifted, rtol=1e-15)
    np.testing.assert_allclose(read_model(old).diameters, model.diameters, rtol=1e-15)
    frames_old = [fr.positions for fr in A.FabricFrame.iter_trajectory(old)]
    frames_new = [fr.positions for fr in A.FabricFrame.iter_trajectory(path)]
    np.testing.assert_allclose(frames_old, frames_new, rtol=1e-15)
    u_old = fabmd.load(old)
    u_old.trajectory[1]
    np.testing.assert_allclose(u_old.atoms.positions, ours.atoms.positions, rtol=1e-6)


def test_readers_refuse_unknown_versions_and_formats(tmp_path):
    path = write_snapshot(woven_sheet(), tmp_path / "t.h5")
    newer = tmp_path / "newer.h5"
    shutil.copy(path, newer)
    with h5py.File(newer, "a") as f:
        f.attrs["fabmd_format_version"] = FORMAT_VERSION + 1
    with pytest.raises(TrajectoryFormatError, match=f"version {FORMAT_VERSION + 1}"):
        fabmd.load(newer)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.create_group("particles")
    with pytest.raises(TrajectoryFormatError, match="not a fabmd trajectory"):
        fabmd.load(other)
    with pytest.raises(InputError, match="no fabmd result"):
        fabmd.load(tmp_path / "missing")


def test_load_refuses_a_trajectory_of_another_model(tmp_path):
    sheet = woven_sheet(fibres=(2, 1))
    sheet.save(tmp_path)  # model.data of a 2x1-fibre sheet
    write_snapshot(woven_sheet(fibres=(3, 1)), tmp_path / "trajectory.h5")
    with pytest.raises(InputError, match="bonds loaded but"):
        fabmd.load(tmp_path)
    assert len(fabmd.load(tmp_path, check_bonds=False).bonds) > sheet.n_bonds


# -- real runs ------------------------------------------------------------------------------
@pytest.mark.lammps
def test_fibre_tension_result_opens_in_mdanalysis_and_meshio(tmp_path):
    import meshio

    test = tiny_tension()
    result = test.run(tmp_path / "ft", engine=Engine(progress=False))
    run_dir = result.run_dir
    assert result.summary["trajectory"] == "trajectory.h5"
    for name in ("trajectory.h5", "trajectory.bin", "bonds.dump", "trajectory.pvd",
                 "trajectory.json"):
        assert (run_dir / name).exists(), name
    assert not list(run_dir.glob("*.part"))

    u = fabmd.load(run_dir)
    assert len(u.bonds) == data_file_bond_count(run_dir / "model.data") == test.n_bonds
    steps = np.array([ts.data["step"] for ts in u.trajectory])
    assert steps[0] == 0 and steps[-1] == test.steps  # first and last step are frames
    assert np.all(np.diff(steps) > 0) and len(steps) >= 6
    assert u.trajectory.units["length"] == "m"
    # stock MDAnalysis, no fabmd code: the run folder's data file as topology (bonds too)
    import MDAnalysis as mda

    stock = mda.Universe(str(run_dir / "model.data"), str(run_dir / "trajectory.h5"),
                         format="H5MD", atom_style="id type x y z diameter density resid")
    assert stock.trajectory.n_frames == len(steps) and len(stock.bonds) == len(u.bonds)
    stock.trajectory[-1]
    u.trajectory[-1]
    np.testing.assert_allclose(stock.atoms.positions * 1e-10, u.atoms.positions, rtol=1e-6)

    with open_trajectory(run_dir / "trajectory.h5") as f:
        force = f["observables/bond_force/value"][-1]
        last = read_lengths(f["particles/all/position/value"], -1)
    bt = test.model().bond_type_table[0]
    length = np.linalg.norm(np.diff(last, axis=0), axis=1)  # bond i joins beads i, i+1
    # bond force: tension > 0, in the model's bond order, equal to 2K(r - r0)
    assert np.allclose(force, 2 * bt.coefficient * (length - bt.rest_length_m), rtol=1e-6)
    assert force.mean() == pytest.approx(result.curve["force_n"][-1], rel=0.02)
    u.trajectory[-1]
    assert fabmd.results.universe.bond_forces(u) == pytest.approx(force)

    entries = (run_dir / "trajectory.pvd").read_text().count("<DataSet")
    assert entries == len(steps)
    vtu = sorted((run_dir / "paraview").glob("frame_*.vtu"))
    assert len(vtu) == len(steps)
    mesh = meshio.read(vtu[-1])
    assert np.allclose(mesh.points, last, rtol=1e-6)  # single precision for viewing
    assert mesh.cells_dict["line"].shape == (test.n_bonds, 2)
    assert np.allclose(mesh.cell_data["bond_force_n"][0], force, rtol=1e-6)
    assert set(mesh.point_data) >= {"yarn_id", "fibre_id", "family"}
    report = json.loads((run_dir / "trajectory.json").read_text())
    assert report["frames"] == len(steps) and report["trajectory_bytes"] > 0


@pytest.mark.lammps
def test_periodic_sheet_is_unwrapped_and_paraview_skips_closing_bonds(tmp_path):
    import meshio

    model = woven_sheet(fibres=(2, 1))
    run_dir = free_run(model, tmp_path / "sheet", steps=300,
                       trajectory=TrajectoryOutput(frames=3, velocities=True))
    u = fabmd.load(run_dir)
    rest = model.bond_type_table[0].rest_length_m
    pairs = u.bonds.indices
    closing = np.abs(pairs[:, 1] - pairs[:, 0]) > 1  # last bead back to the first
    assert closing.sum() == model.n_fibres
    k = 2 * model.bond_type_table[0].coefficient
    for ts in u.trajectory:
        lengths = u.bonds.values()  # unwrapped, no minimum image
        assert lengths[~closing].max() < 1.05 * rest
        assert lengths[closing].min() > 0.5 * model.box_hi[0]  # spans the box, unwrapped
        assert u.bonds.values(pbc=True).max() < 1.05 * rest
        assert np.abs(ts.velocities).max() > 0
        # bond forces come in the order of u.bonds: 2K(r - r0) with r from double positions
        exact = read_model(run_dir / "trajectory.h5", ts.frame)
        d = exact.positions[pairs[:, 1]] - exact.positions[pairs[:, 0]]
        d[:, :2] -= model.box_hi[:2] * np.round(d[:, :2] / model.box_hi[:2])
        expected = k * (np.linalg.norm(d, axis=1) - rest)
        force = fabmd.results.universe.bond_forces(u)
        # (LAMMPS's r0 has 10 digits: an offset of ~k·r0·1e-10; a wrong order is ~1e-4 N off)
        assert np.abs(force - expected).max() < k * rest * 1e-9
        assert np.ptp(expected) > 1e-4  # the fibres do carry varying forces
    mesh = meshio.read(sorted((run_dir / "paraview").glob("*.vtu"))[-1])
    assert len(mesh.cells_dict["line"]) == model.n_bonds - model.n_fibres
    assert "velocity_m_s" in mesh.point_data
    u.trajectory[-1]
    frame = A.FabricFrame.from_universe(u)
    assert frame.time_s > 0 and frame.box_lo == pytest.approx(model.box_lo)
    assert A.crimp_by_family(frame)["warp"] == pytest.approx(
        A.crimp_by_family(A.FabricFrame.from_model(model))["warp"], abs=2e-3)


@pytest.mark.lammps
def test_no_trajectory_when_switched_off(tmp_path):
    result = tiny_tension(trajectory=TrajectoryOutput(frames=0)).run(
        tmp_path / "off", engine=Engine(progress=False))
    assert result.summary["trajectory"] is None
    assert not (result.run_dir / "trajectory.bin").exists()
    assert "fabmd_trajectory" not in (result.run_dir / "in.fibre_tension").read_text()
    u = fabmd.load(result.run_dir)  # final.data, one frame
    assert u.trajectory.n_frames == 1 and len(u.bonds) == 40


@pytest.mark.lammps
def test_dump_cut_short_loses_only_its_last_frame(tmp_path):
    run_dir = tiny_tension().run(tmp_path / "ft", engine=Engine(progress=False)).run_dir
    whole = list(iter_dump(run_dir / "trajectory.bin"))
    cut = tmp_path / "cut.bin"
    cut.write_bytes((run_dir / "trajectory.bin").read_bytes()[:-100])
    assert [fr.step for fr in iter_dump(cut)] == [fr.step for fr in whole[:-1]]
    text = (run_dir / "bonds.dump").read_text()
    (tmp_path / "cut.dump").write_text(text[: len(text) - 30])
    assert len(list(iter_dump(tmp_path / "cut.dump"))) == len(whole) - 1


@pytest.mark.lammps
def test_resume_cuts_the_dumps_back_and_joins_them_again(tmp_path):
    """What the in-process engine does to the dumps around a resume (no LAMMPS needed
    after the first run): frames before the checkpoint step are kept and set aside, the
    resumed run writes the rest, and the parts join into the file of an unbroken run."""
    from fabmd.engine.checkpoint import BEFORE_RESUME, cut_outputs, join_dump_parts
    from fabmd.engine.script import logical_lines

    run_dir = tiny_tension().run(tmp_path / "ft", engine=Engine(progress=False)).run_dir
    commands = logical_lines((run_dir / "in.fibre_tension").read_text())
    frames = list(iter_dump(run_dir / "trajectory.bin"))
    cut_step = frames[3].step
    whole = {name: (run_dir / name).read_bytes() for name in ("trajectory.bin", "bonds.dump")}
    text_cut = whole["bonds.dump"].index(f"ITEM: TIMESTEP\n{cut_step}\n".encode())
    later = {"trajectory.bin": whole["trajectory.bin"][frames[3].offset:],
             "bonds.dump": whole["bonds.dump"][text_cut:]}
    cut_outputs(run_dir, commands, cut_step)
    for name in whole:
        assert not (run_dir / name).exists()  # set aside: the resumed run writes it anew
        before = run_dir / (name + BEFORE_RESUME)
        assert before.read_bytes() == whole[name][: len(whole[name]) - len(later[name])]
        (run_dir / name).write_bytes(later[name])  # what the resumed run writes
    join_dump_parts(run_dir, commands)
    for name in whole:
        assert (run_dir / name).read_bytes() == whole[name]
        assert not (run_dir / (name + BEFORE_RESUME)).exists()
    assert [fr.step for fr in iter_dump(run_dir / "trajectory.bin")] == [f.step for f in frames]


@pytest.mark.lammps
def test_frames_before_a_blow_up_are_kept(tmp_path, monkeypatch):
    test = tiny_tension(trajectory=TrajectoryOutput(every_steps=5))
    dt = test.time_step_s
    original = FibreTension.input_text
    monkeypatch.setattr(FibreTension, "input_text", lambda self, model: original(
        self, model).replace(f"timestep        {dt:.10g}", f"timestep        {12 * dt:.10g}"))
    with pytest.raises(UnstableRun):
        test.run(tmp_path / "boom", engine=Engine(progress=False))
    u = fabmd.load(tmp_path / "boom")
    assert u.trajectory.n_frames >= 2  # the frames up to the blow-up, for a look in ParaView


def _h5_contents(path) -> dict:
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
        f.visititems(visit)
        out["attrs"] = {k: v for k, v in f["parameters/fabmd"].attrs.items()}
    return out


def _assert_same_trajectory(a, b):
    ca, cb = _h5_contents(a), _h5_contents(b)
    assert ca.keys() == cb.keys()
    assert ca.pop("attrs") == cb.pop("attrs")
    for name, value in ca.items():
        if value.dtype.kind == "f":
            np.testing.assert_allclose(cb[name], value, rtol=1e-9, atol=1e-12, err_msg=name)
        else:
            assert np.array_equal(cb[name], value), name


@pytest.mark.lammps
@pytest.mark.mpi
def test_two_mpi_ranks_write_the_trajectory_once_and_alike(tmp_path, mpirun):
    one = run_cli("validate", "fibre-tension", *TINY, "--out", str(tmp_path / "one"))
    two = run_cli("validate", "fibre-tension", *TINY, "--out", str(tmp_path / "two"),
                  mpi_ranks=2)
    assert one.returncode == 0, one.stderr
    assert two.returncode == 0, two.stderr
    assert two.stdout.count("fibre-tension: PASSED") == 1  # rank 0 alone prints
    for run in ("one", "two"):
        files = sorted(p.name for p in (tmp_path / run).iterdir())
        assert files.count("trajectory.h5") == 1 and not [f for f in files if ".part" in f]
    _assert_same_trajectory(tmp_path / "one" / "trajectory.h5",
                            tmp_path / "two" / "trajectory.h5")
    # plain LAMMPS on 2 ranks (standalone back end) writes the same trajectory too
    three = run_cli("validate", "fibre-tension", *TINY, "--out", str(tmp_path / "three"),
                    "--backend", "standalone", "--np", "2")
    assert three.returncode == 0, three.stderr
    _assert_same_trajectory(tmp_path / "one" / "trajectory.h5",
                            tmp_path / "three" / "trajectory.h5")
