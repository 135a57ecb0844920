"""Export of a fabric state: yarn reconstruction, voxel mesh, writers, surfaces.

The reference is a fabric of straight yarns whose answers are known in closed form:
a warp yarn along x above a weft yarn along y in a periodic cell, each yarn seven
virtual fibres (a centre fibre and six on a regular hexagon of circumradius a, turned
15° so that no flat side lies along a voxel layer: that worst case of voxel sampling
errs by up to one layer per side), so

* the fibre envelope (hexagon grown by the fibre radius r) has area
  (3√3/2)·a² + 6·a·r + π·r²;
* the yarn fibre volume fraction is 7·A_f / that area;
* the cell fibre volume fraction is 2·7·A_f·L / (Lx·Ly·Lz);
* the fibre direction is x in the warp and y in the weft.
"""

import math

import meshio
import numpy as np
import pytest

from fabmd.analysis.synthetic import woven_sheet
from fabmd.errors import InputError
from fabmd.export import (
    VoxelGrid,
    bead_fibre_volume_fraction,
    direction_errors,
    enclosed_volume,
    export_state,
    periodic_node_sets,
    read_distribution,
    reconstruct_yarns,
    voxel_grid,
    voxelise,
    watertight,
    write_abaqus,
    write_vtu,
    yarn_surface,
)
from fabmd.model.bead_model import BeadModel, BondType, Yarn

D = 0.2e-3                 # fibre (bead) diameter [m]
A = 0.25e-3                # hexagon circumradius of the fibre layout [m]
AREA_F = 0.6 * math.pi * D**2 / 4  # filament area of one virtual fibre [m²]
CELL = 2.0e-3              # periodic cell edge [m]
LIFT = 0.5e-3              # warp centre at z = +LIFT, weft at -LIFT [m]


def hexagon_offsets() -> list[tuple[float, float]]:
    """(across, through-thickness) offsets of the seven fibres of a yarn."""
    angles = [math.radians(15 + 60 * k) for k in range(6)]
    return [(0.0, 0.0)] + [(A * math.cos(t), A * math.sin(t)) for t in angles]


def straight_fabric(angle_deg: float | None = None) -> BeadModel:
    """Warp along x over weft along y in a periodic CELL x CELL cell (closed fibres), or
    with ``angle_deg`` one open straight yarn along (cos, sin, 0) of that angle."""
    n = 20  # beads per fibre (spacing CELL/20 = D/2)
    pos, fib, bonds, fibre_yarn, types = [], [], [], [], []
    yarn_specs = ([("warp", 1, np.array([1.0, 0, 0]), np.array([0, CELL / 2, LIFT])),
                   ("weft", 2, np.array([0, 1.0, 0]), np.array([CELL / 2, 0, -LIFT]))]
                  if angle_deg is None else
                  [("warp", 1, np.array([math.cos(math.radians(angle_deg)),
                                         math.sin(math.radians(angle_deg)), 0.0]),
                    np.zeros(3))])
    periodic = angle_deg is None
    k = 0
    for _fam, t, axis, origin in yarn_specs:
        across = np.cross([0, 0, 1.0], axis)
        for du, dv in hexagon_offsets():
            s = np.arange(n) * (CELL / n)
            p = origin + s[:, None] * axis + du * across + dv * np.array([0, 0, 1.0])
            pos.append(p)
            fibre_yarn.append(t)
            fib += [len(fibre_yarn)] * n
            types += [t] * n
            bonds += [(k + i, k + i + 1) for i in range(n - 1)]
            if periodic:
                bonds.append((k + n - 1, k))
            k += n
    families = tuple(f for f, *_ in yarn_specs)
    pos = np.vstack(pos)
    return BeadModel(
        positions=pos, diameters=D, masses=1.0, atom_types=types, fibre_ids=fib,
        bonds=bonds, bond_types=[types[i] for i, _ in bonds], family_names=families,
        bond_type_table=[BondType(1.0, CELL / n, f) for f in families],
        fibre_yarn=fibre_yarn, yarns=[Yarn(f"{f}-1", f) for f in families],
        box_lo=[0, 0, -2e-3] if periodic else pos.min(axis=0) - 1e-3,
        box_hi=[CELL, CELL, 2e-3] if periodic else pos.max(axis=0) + 1e-3,
        periodic=(periodic, periodic, False),
        info={"families": {f: {"fibre_area_m2": AREA_F} for f in families}})


def envelope_area() -> float:
    r = D / 2
    return 1.5 * math.sqrt(3) * A**2 + 6 * A * r + math.pi * r**2


def test_reconstruction_matches_the_closed_form_section():
    yarns = reconstruct_yarns(straight_fabric())
    assert [y.closed for y in yarns] == [True, True]
    assert np.allclose(yarns[0].period_m, [CELL, 0, 0])
    for y in yarns:
        assert y.area_m2 == pytest.approx(envelope_area(), rel=0.01)
        assert y.fibre_volume_fraction == pytest.approx(7 * AREA_F / envelope_area(), rel=0.01)
        assert np.allclose(np.abs(y.directions), np.abs(y.tangents), atol=1e-9)
        # straight up from the centre: the side between the vertices at 75 and 135 deg,
        # moved out by the fibre radius
        assert y.radii_m[:, y.n_angles // 4] == pytest.approx(
            (A * math.cos(math.pi / 6) + D / 2) / math.cos(math.radians(15)), rel=0.005)


def test_voxel_volume_fraction_and_direction_of_straight_yarns():
    model = straight_fabric()
    grid = voxel_grid(model)
    mesh = voxelise(reconstruct_yarns(model), grid)
    lz = 2 * LIFT + 2 * A * math.sin(math.radians(75)) + D
    assert grid.hi_m[2] - grid.lo_m[2] == pytest.approx(lz)
    closed_form = 2 * 7 * AREA_F * CELL / (CELL * CELL * lz)
    assert bead_fibre_volume_fraction(model, grid) == pytest.approx(closed_form, rel=1e-9)
    assert mesh.cell_fibre_volume_fraction() == pytest.approx(closed_form, rel=0.02)
    assert mesh.yarn_volume_fraction() == pytest.approx(
        2 * envelope_area() * CELL / (CELL * CELL * lz), rel=0.02)
    warp, weft = mesh.yarn_id == 1, mesh.yarn_id == 2
    assert np.allclose(np.abs(mesh.direction[warp]), [1, 0, 0], atol=1e-9)
    assert np.allclose(np.abs(mesh.direction[weft]), [0, 1, 0], atol=1e-9)
    assert np.all(mesh.direction[mesh.yarn_id == 0] == 0)
    assert mesh.overlap_voxels == {}  # the layers do not touch
    errors = direction_errors(model, mesh)
    assert errors["max_deg"] < 1e-6 and errors["beads_in_matrix"] == 0.0


def test_inclined_open_yarn_direction():
    model = straight_fabric(angle_deg=30.0)
    mesh = voxelise(reconstruct_yarns(model), voxel_grid(model))
    inside = mesh.direction[mesh.yarn_id == 1]
    assert len(inside) > 100
    expected = [math.cos(math.radians(30)), math.sin(math.radians(30)), 0.0]
    assert np.allclose(np.abs(inside @ expected), 1.0, atol=1e-9)


def crimped_sheet() -> BeadModel:
    model = woven_sheet(fibres=(3, 2))
    model.info["families"] = {f: {"fibre_area_m2": a}
                              for f, a in model.info["fibre_area_m2"].items()}
    return model


def test_periodic_cell_stays_periodic():
    """Shifting a periodic woven cell by whole voxels along x and y shifts its voxel
    field by as many voxels (nothing is cut at the cell faces)."""
    model = crimped_sheet()
    grid = voxel_grid(model, voxels=40)
    base = voxelise(reconstruct_yarns(model), grid)
    shifted = crimped_sheet()
    shift = np.array([3 * grid.size_m[0], 5 * grid.size_m[1], 0.0])
    shifted.positions = shifted.positions + shift
    moved = voxelise(reconstruct_yarns(shifted), grid)
    shape = grid.counts[::-1]  # (z, y, x) of the flat x-fastest arrays
    rolled = np.roll(base.yarn_id.reshape(shape), (5, 3), axis=(1, 2)).ravel()
    assert np.mean(rolled == moved.yarn_id) > 0.999
    assert moved.cell_fibre_volume_fraction() == pytest.approx(
        base.cell_fibre_volume_fraction(), rel=1e-3)


def test_crimped_sheet_directions_follow_the_bead_tangents():
    model = crimped_sheet()
    mesh = voxelise(reconstruct_yarns(model), voxel_grid(model, voxels=80))
    errors = direction_errors(model, mesh)
    # every fibre of a yarn follows the same sinusoid: the yarn direction is theirs
    assert errors["beads_compared"] == model.n_beads
    assert errors["mean_deg"] < 0.5 and errors["max_deg"] < 2.0


def test_sub_voxel_samples_refine_the_volume_fraction():
    """The crimped sheet's yarn sides lie along voxel columns (the worst case of centre
    sampling); 2³ samples per voxel give the centre value of the twice finer grid."""
    model = crimped_sheet()
    yarns = reconstruct_yarns(model)
    grid = voxel_grid(model, voxels=40)
    coarse = voxelise(yarns, grid, samples=2)
    fine = voxelise(yarns, VoxelGrid(grid.lo_m, grid.hi_m, tuple(2 * c for c in grid.counts),
                                     grid.periodic))
    assert coarse.cell_fibre_volume_fraction() == pytest.approx(
        fine.cell_fibre_volume_fraction(), rel=1e-9)
    assert np.array_equal(coarse.yarn_id, voxelise(yarns, coarse.grid).yarn_id)


@pytest.mark.lammps
@pytest.mark.slow
def test_export_of_the_crimped_plain_weave_cell(tmp_path):
    """The README's example: crimp the plain-weave cell, export it at the default voxel
    size; the voxels keep the beads' fibre volume fraction within 2 % (at rest the cell is
    flat, its voxel centres miss by 3.3 %: sampled inside the voxels). (The drawn section
    at the weaving tension: the search of the loose sections for the stated crimp, a
    crimp run per try, is test_loose_height's.)"""
    import json

    from fabmd.cli import main
    from fabmd.examples_dir import example_scene

    text = example_scene("plain_weave.toml").read_text()
    assert 'crimp_by = "loose_height"\n' in text
    scene = tmp_path / "plain_weave.toml"
    scene.write_text(text.replace('crimp_by = "loose_height"\n', "")
                     .replace("target_crimp_pct = { warp = 1.5, weft = 1.5 }\n", ""))
    run = tmp_path / "crimp"
    assert main(["crimp", str(scene), "--form", "cell",
                 "--out", str(run), "--quiet"]) == 0
    assert main(["export", str(run)]) == 0
    s = json.loads((run / "export" / "export.json").read_text())
    assert abs(s["fibre_volume_fraction"]["relative_error"]) < 0.02
    assert s["direction_error"]["mean_deg"] < 5.0
    assert s["direction_error"]["beads_in_matrix"] < 0.01
    assert s["all_surfaces_watertight"]
    back = meshio.read(run / "export" / "voxels.inp")
    assert {"WARP_1", "WARP_2", "WEFT_1", "WEFT_2", "MATRIX"} <= set(back.cell_sets)
    vtu = meshio.read(run / "export" / "voxels.vtu")
    assert vtu.cell_data["fibre_volume_fraction"][0].mean() == pytest.approx(
        s["fibre_volume_fraction"]["voxels"])


def test_yarn_surfaces_are_closed_and_enclose_the_yarn_volume():
    for model in (straight_fabric(), straight_fabric(30.0), crimped_sheet()):
        for y in reconstruct_yarns(model):
            points, triangles = yarn_surface(y)
            check = watertight(triangles)
            assert check["watertight"], check
            volume = enclosed_volume(points, triangles)
            assert volume > 0
            assert volume == pytest.approx(y.volume_m3(), rel=0.02)


def test_watertight_check_fails_on_a_hole_and_a_flipped_triangle():
    y = reconstruct_yarns(straight_fabric())[0]
    _, triangles = yarn_surface(y)
    assert not watertight(triangles[1:])["watertight"]
    flipped = triangles.copy()
    flipped[0] = flipped[0, ::-1]
    assert watertight(flipped)["inconsistent_edges"] == 3


def test_vtu_and_abaqus_read_back_with_their_data(tmp_path):
    model = straight_fabric()
    mesh = voxelise(reconstruct_yarns(model), voxel_grid(model, voxels=16))
    vtu = meshio.read(write_vtu(mesh, tmp_path / "v.vtu"))
    assert np.array_equal(vtu.cell_data["yarn_id"][0], mesh.yarn_id)
    assert np.allclose(vtu.cell_data["fibre_direction"][0], mesh.direction)
    assert np.allclose(vtu.cell_data["fibre_volume_fraction"][0], mesh.fibre_volume_fraction)
    inp = write_abaqus(mesh, tmp_path / "v.inp")
    back = meshio.read(inp)
    assert len(back.cells[0].data) == mesh.grid.n_voxels
    sets = {k: np.concatenate(v) for k, v in back.cell_sets.items()}
    for k, name in ((1, "WARP_1"), (2, "WEFT_1"), (0, "MATRIX")):
        assert np.array_equal(np.sort(sets[name]), np.flatnonzero(mesh.yarn_id == k))
    ori = read_distribution(inp)
    assert sorted(ori) == list(np.flatnonzero(mesh.yarn_id > 0) + 1)
    for e, v in ori.items():
        assert np.allclose(v[:3], mesh.direction[e - 1], atol=1e-6)
        assert abs(np.dot(v[:3], v[3:])) < 1e-5
    # element volumes positive: the node order is a valid C3D8
    p, h = back.points, back.cells[0].data
    jac = np.einsum("ij,ij->i", p[h[:, 1]] - p[h[:, 0]],
                    np.cross(p[h[:, 3]] - p[h[:, 0]], p[h[:, 4]] - p[h[:, 0]]))
    assert np.all(jac > 0)
    table = (tmp_path / "v_elements.csv").read_text().splitlines()
    assert len(table) == mesh.grid.n_voxels + 1


def test_periodic_node_sets_pair_up_across_the_cell():
    grid = VoxelGrid([0, 0, 0], [2.0, 3.0, 1.0], (4, 3, 2), (True, True, False))
    sets = periodic_node_sets(grid)
    nodes = np.array(np.meshgrid(np.linspace(0, 1, 3), np.linspace(0, 3, 4),
                                 np.linspace(0, 2, 5), indexing="ij")).reshape(3, -1).T[:, ::-1]
    every = np.concatenate(list(sets.values()))
    assert len(every) == len(set(every.tolist()))  # no node in two sets
    boundary = ((nodes == 0) | (nodes == [2.0, 3.0, 1.0])).any(axis=1)
    assert len(every) == boundary.sum()
    for lo, hi, shift in (("XMIN", "XMAX", [2, 0, 0]), ("YMIN", "YMAX", [0, 3, 0]),
                          ("EDGE_XMIN_YMIN", "EDGE_XMAX_YMAX", [2, 3, 0]),
                          ("CORNER_000", "CORNER_110", [2, 3, 0])):
        assert np.allclose(nodes[sets[lo] - 1] + shift, nodes[sets[hi] - 1])


def test_bad_grids_are_refused():
    with pytest.raises(InputError, match="voxels must be >= 1"):
        VoxelGrid.covering([0, 0, 0], [1, 1, 1], (False,) * 3, voxels=0)
    with pytest.raises(InputError, match="voxel_size_m must be > 0"):
        VoxelGrid.covering([0, 0, 0], [1, 1, 1], (False,) * 3, voxel_size_m=-1.0)


def test_export_command_writes_what_meshio_reads(tmp_path):
    from fabmd.cli import main

    crimped_sheet().save(tmp_path / "run", "crimped")
    out = tmp_path / "out"
    assert main(["export", str(tmp_path / "run"), "--voxel", "20", "--out", str(out),
                 "--png"]) == 0
    for name in ("voxels.vtu", "voxels.inp", "voxels_elements.csv", "export.json", "voxels.png",
                 "surfaces/yarn_surfaces.vtu", "surfaces/warp-0.stl"):
        assert (out / name).exists(), name
    assert "yarn_id" in meshio.read(out / "voxels.vtu").cell_data
    assert main(["export", str(tmp_path / "run"), "--out", str(out)]) == 2  # exists
    assert main(["export", str(tmp_path / "run"), "--voxel", "0",
                 "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()  # refused before any file


def test_export_state_summary(tmp_path):
    summary = export_state(straight_fabric(), tmp_path)
    assert summary["all_surfaces_watertight"]
    assert abs(summary["fibre_volume_fraction"]["relative_error"]) < 0.02
    assert summary["interpenetration"]["pairs"] == []


def test_a_coarse_export_warns_with_the_remedy(tmp_path):
    """Voxels of 1.5 fibre diameters miss the bead model's volume fraction by more than
    2 %: the export says so and names the remedy; the default size does not warn."""
    model = straight_fabric()
    with pytest.warns(UserWarning, match="--samples 2"):
        coarse = export_state(model, tmp_path / "coarse", samples=1,
                              voxel_size_m=1.5 * float(model.diameters.min()))
    assert abs(coarse["fibre_volume_fraction"]["relative_error"]) > 0.02
    assert coarse["warnings"]
    fine = export_state(model, tmp_path / "fine")
    assert "warnings" not in fine


def test_an_export_whose_voxel_centres_miss_samples_inside_the_voxels(tmp_path):
    """At the default sampling, a grid whose voxel centres miss the beads' fibre volume
    fraction by more than 2 % is sampled again with 2³ points per voxel, closer to the
    beads, and the summary keeps the centres' miss."""
    import warnings as warnings_module

    model = straight_fabric()
    size = 0.5 * float(model.diameters.min())  # centres -2.4 %, 2^3 points -0.2 %
    with warnings_module.catch_warnings():
        warnings_module.simplefilter("ignore")
        centres = export_state(model, tmp_path / "centres", samples=1, voxel_size_m=size)
        auto = export_state(model, tmp_path / "auto", voxel_size_m=size)
    miss = centres["fibre_volume_fraction"]["relative_error"]
    assert centres["samples_per_axis"] == 1 and auto["samples_per_axis"] == 2
    assert auto["fibre_volume_fraction"]["centre_sampling_error"] == pytest.approx(miss)
    assert abs(auto["fibre_volume_fraction"]["relative_error"]) < 0.5 * abs(miss)
    fine = export_state(model, tmp_path / "fine")  # within 2 % at the centres: no second pass
    assert fine["samples_per_axis"] == 1
    assert fine["fibre_volume_fraction"]["centre_sampling_error"] is None
