"""Fabric geometry: weaves, 3D architectures, sections, paths, rendering to beads (no LAMMPS)."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.geometry import Architecture3D, Fabric, Section, Weave, YarnSpec
from fabmd.geometry.section import hex_packing
from fabmd.model.beads import Discretisation
from fabmd.model.fabric_model import render_fabric
from fabmd.model.material import GLASS
from fabmd.model.overlap import closest_approach


def yarn(n_fibres=7, width="1.6 mm", height="0.8 mm", spacing="2.5 mm", tex="600 tex"):
    return YarnSpec(tex, GLASS, width_m=width, height_m=height, spacing_m=spacing,
                    n_fibres=n_fibres)


def plain(tiling=(1, 1), periodic=False, n_fibres=7, **kw):
    y = yarn(n_fibres)
    return Fabric(Weave.plain(), y, y, tiling=tiling, periodic=periodic, **kw)


def interlock(tiling=(1, 1), periodic=False, n_fibres=1, **arch):
    warp = yarn(n_fibres, "1.8 mm", "0.6 mm", "4 mm", "1200 tex")
    weft = yarn(n_fibres, "1.8 mm", "0.6 mm", "3 mm", "1200 tex")
    binder = YarnSpec("600 tex", GLASS, width_m="1 mm", height_m="0.4 mm", n_fibres=n_fibres)
    a = Architecture3D.layer_to_layer(**({"weft_layers": 5, "columns": 8} | arch))
    return Fabric(a, warp, weft, binder, tiling=tiling, periodic=periodic,
                  clearance_m="0.05 mm")


# -- weaves ------------------------------------------------------------------------------
def test_named_weaves():
    assert Weave.plain().matrix == ((1, 0), (0, 1))
    t = Weave.twill(2, 2).array
    assert t.shape == (4, 4) and list(t[0]) == [1, 1, 0, 0] and list(t[1]) == [0, 1, 1, 0]
    s = Weave.satin(5, 2).array
    assert (s.sum(axis=0) == 1).all() and (s.sum(axis=1) == 1).all()
    assert [int(np.flatnonzero(r)[0]) for r in s] == [0, 2, 4, 1, 3]
    b = Weave.basket(2, 3).array
    assert b.shape == (4, 6) and b[:2, :3].all() and not b[:2, 3:].any()


@pytest.mark.parametrize("matrix,words", [
    ([[1, 0], [0]], "row 2 has 1 entries but row 1 has 2"),
    ([[1, 2], [0, 1]], "row 1, column 2 must be 0 or 1"),
    ([], "non-empty list of rows"),
    ([[1, 1], [0, 1]], "warp yarn 1 (row 1) never interlaces: it stays above every weft"),
    ([[1, 0], [1, 0]], "weft yarn 1 (column 1) never interlaces: it stays below every warp"),
])
def test_malformed_weave_matrices_are_one_line_errors(matrix, words):
    with pytest.raises(InputError) as err:
        Weave.from_matrix(matrix)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_floats_allowed_on_request_and_satin_moves_listed():
    assert Weave.from_matrix([[1, 1], [0, 1]], allow_floats=True).n_warp == 2
    with pytest.raises(InputError, match=r"allowed: 3, 5\), got 2"):
        Weave.satin(8, 2)
    with pytest.raises(InputError, match="no regular satin move"):
        Weave.satin(6)


# -- 3D architectures --------------------------------------------------------------------
def test_layer_to_layer_counts_and_paths():
    a = Architecture3D.layer_to_layer(weft_layers=5, depth=1, dents=2, columns=8)
    assert (a.n_weft, a.n_warp, a.n_binders, a.columns) == (40, 8, 8, 8)
    assert a.binder_paths[0][0] == (0, 1, 2, 1, 0, 1, 2, 1)
    assert a.binder_paths[1][0] == (2, 1, 0, 1, 2, 1, 0, 1)  # second dent half a period on
    t = Architecture3D.through_thickness(weft_layers=3)
    assert t.binder_paths[0][0] == (0, 1, 2, 3, 2, 1)
    o = Architecture3D.orthogonal(weft_layers=3, float_columns=2)
    assert o.binder_paths[0][0] == (0, 0, 3, 3) and o.binder_paths[1][0] == (3, 3, 0, 0)


@pytest.mark.parametrize("paths,words", [
    ([[[0, 4, 0]]], "column 2 must be a gap 0..3"),
    ([[[0, 1], [0, 1, 2]]], "binder 2 of dent 1 has 3 columns"),
    ([[[1, 1, 1]]], "binder 1 of dent 1 stays in gap 1 at every column"),
    ([[[0, 2], [1, 2]]], "binders 1 and 2 of dent 1 are both in gap 2 at column 2"),
    ([[[0, 3, 0, 3], [1, 2, 1, 2]]], "binders 1 and 2 of dent 1 cross between columns 1 and 2"),
    ([], "list of dents"),
])
def test_impossible_binder_paths_are_one_line_errors(paths, words):
    with pytest.raises(InputError) as err:
        Architecture3D(3, paths)
    assert words in str(err.value) and "\n" not in str(err.value)


def test_columns_must_fit_the_binder_period():
    # orthogonal floats keep whole periods (angle interlocks spread one over any cell)
    with pytest.raises(InputError, match="multiple of the binder period 4"):
        Architecture3D.orthogonal(weft_layers=3, float_columns=2, columns=6)


# -- sections ----------------------------------------------------------------------------
@pytest.mark.parametrize("n,ratio", [(1, 1), (7, 3), (19, 5), (37, 7), (61, 9)])
def test_hexagonal_packings_fill_a_circle(n, ratio):
    offsets, d = Section("1 mm").packing(n)
    assert len(offsets) == n
    assert d == pytest.approx(1e-3 / ratio, rel=1e-9)
    assert np.linalg.norm(offsets, axis=1).max() + d / 2 == pytest.approx(0.5e-3, rel=1e-9)


@pytest.mark.parametrize("n", [2, 5, 7, 12, 19, 30])
@pytest.mark.parametrize("w,h", [(1.0, 1.0), (2.0, 0.5), (1.6, 0.8), (0.5, 1.0)])
def test_any_packing_stays_inside_and_does_not_overlap(n, w, h):
    offsets, d = Section(w * 1e-3, h * 1e-3).packing(n)
    a, b = w * 5e-4 - d / 2, h * 5e-4 - d / 2
    assert np.all((offsets[:, 0] / a) ** 2 + (offsets[:, 1] / b) ** 2 <= 1 + 1e-9)
    gaps = np.linalg.norm(offsets[:, None] - offsets[None], axis=2) + np.eye(n) * 1e9
    assert gaps.min() >= d * (1 - 1e-9)
    assert len(hex_packing(n, w / h)) == n


# -- fabrics: validation -----------------------------------------------------------------
@pytest.mark.parametrize("n", [7, 19, 37])
def test_area_packing_tiles_the_section_and_spans_it(n):
    """``fibre_packing = "area"``: N hexagonal cells of the contact diameter tile the
    section's area, and the fibres span a flat yarn (inscribed: 19 fibres span 70 %)."""
    section = Section(4.2e-3, 0.638e-3)
    offsets, d = section.packing(n, "area")
    assert n * math.sqrt(3) / 2 * d * d == pytest.approx(section.area_m2, rel=1e-12)
    width = np.ptp(offsets[:, 0]) + d
    height = np.ptp(offsets[:, 1]) + d
    assert 0.95 < width / section.width_m < 1.12 and 0.9 < height / section.height_m < 1.12
    gaps = np.linalg.norm(offsets[:, None] - offsets[None], axis=2)[np.triu_indices(n, 1)]
    assert gaps.min() == pytest.approx(d, rel=1e-9)  # neighbours touch, none overlap
    inscribed, d_in = section.packing(n)
    if n == 19:
        assert (np.ptp(inscribed[:, 0]) + d_in) / section.width_m < 0.71
    spec = YarnSpec(1870, GLASS, width_m=4.2e-3, height_m=0.638e-3, n_fibres=n,
                    fibre_packing="area")
    assert spec.packing()[1] == pytest.approx(d)
    assert YarnSpec(1870, GLASS, width_m=4.2e-3, height_m=0.638e-3,
                    n_fibres=n).packing()[1] == pytest.approx(d_in)
    with pytest.raises(InputError, match="fibre_packing must be one of inscribed, area"):
        YarnSpec(1870, GLASS, width_m=4.2e-3, n_fibres=n, fibre_packing="dense")


def test_the_clearance_is_the_gap_between_the_fibres_of_crossing_yarns():
    """An ``"area"`` packing pokes out of a thin section (7 fibres in 1.6 x 0.576 mm stand
    0.645 mm high); crossing yarns are stacked by the height their fibres fill, so the
    loose fabric keeps the clearance between fibres (by the sections alone its crossings
    overlapped by 0.088 mm). Inscribed fibres stay inside: their heights are the sections'."""
    def spec(packing):
        return YarnSpec("600 tex", GLASS, width_m="1.6 mm", height_m="0.576 mm",
                        spacing_m="2.5 mm", n_fibres=7, fibre_packing=packing)

    inscribed, area = spec("inscribed"), spec("area")
    assert inscribed.occupied_height_m == inscribed.height_m
    assert inscribed.occupied_width_m == inscribed.width_m
    offsets, d = area.packing()
    assert area.occupied_height_m == pytest.approx(np.ptp(offsets[:, 1]) + d)
    assert area.occupied_height_m > 1.1 * area.height_m
    assert area.occupied_width_m > area.width_m
    clearance = 0.05e-3
    fabric = Fabric(Weave.plain(), area, area, clearance_m=clearance, plateau=0.7)
    half = fabric.levels()["crossing_half_separation"][0]
    assert half == pytest.approx(0.5 * area.occupied_height_m + 0.5 * clearance)
    model = render_fabric(fabric)  # raises on overlapping beads
    assert model.info["clearance_m"] > 0.0  # closest where the crossing yarn bends down


def test_impossible_fabrics_are_one_line_errors():
    with pytest.raises(InputError, match="does not fit the warp spacing"):
        Fabric(Weave.plain(), yarn(width="3 mm"), yarn())
    with pytest.raises(InputError, match=r"fabric.binder \(yarns.binder\) is required"):
        Fabric(Architecture3D.orthogonal(), yarn(), yarn())
    with pytest.raises(InputError, match="only used by 3D"):
        Fabric(Weave.plain(), yarn(), yarn(), binder=yarn())
    with pytest.raises(InputError, match="tiling must be two integers"):
        Fabric(Weave.plain(), yarn(), yarn(), tiling=(2,))
    with pytest.raises(InputError, match="yarns.weft needs spacing_m"):
        Fabric(Weave.plain(), yarn(), YarnSpec(600, GLASS, width_m=1e-3))
    with pytest.raises(InputError, match="clearance_m must be >= 0"):
        plain(clearance_m=-1e-5)


def test_tight_bends_and_overlaps_are_refused_naming_yarns():
    # a through-thickness binder over a tall stack with little room between columns folds
    warp = yarn(7, "1 mm", "0.6 mm", "3 mm")
    weft = yarn(7, "1.8 mm", "0.6 mm", "2 mm")
    binder = YarnSpec(600, GLASS, width_m="1 mm", height_m="0.6 mm", n_fibres=7)
    tall = Fabric(Architecture3D.orthogonal(weft_layers=6), warp, weft, binder, plateau=0.9)
    with pytest.raises(InputError, match=r"yarn binder-\d+ bends with radius .* fold"):
        render_fabric(tall)
    # crossing yarns pressed together: no clearance and a flat wave
    squeezed = dataclasses.replace(plain(n_fibres=7), clearance_m=0.0, plateau=0.0)
    squeezed = dataclasses.replace(squeezed, warp=dataclasses.replace(
        squeezed.warp, height_m=0.2e-3, linear_density_tex=300),
        weft=dataclasses.replace(squeezed.weft, height_m=0.2e-3, linear_density_tex=300))
    with pytest.raises(InputError) as err:
        render_fabric(squeezed)
    msg = str(err.value)
    assert "overlap" in msg and "warp-" in msg and "weft-" in msg and "clearance" in msg
    assert "\n" not in msg


# -- rendering: counts and identity --------------------------------------------------------
@pytest.mark.parametrize("tiling", [(1, 1), (2, 3)])
def test_counts_follow_from_the_description(tiling):
    f = plain(tiling=tiling)
    m = render_fabric(f)
    nx, ny = tiling
    assert [y.family for y in m.yarns] == ["warp"] * 2 * ny + ["weft"] * 2 * nx
    assert m.n_fibres == 7 * len(m.yarns)
    l0 = m.info["families"]["warp"]["bond_length_m"]
    lengths = {"warp": f.size_m[0], "weft": f.size_m[1]}
    ends = m.fibre_ends()
    per_fibre = ends[:, 1] - ends[:, 0] + 1
    for k, fam in enumerate(np.array([y.family for y in m.yarns])[m.fibre_yarn - 1]):
        arc = lengths[fam] * (1 + m.info["crimp"][fam])
        assert abs(per_fibre[k] - (arc / l0 + 1)) < 0.06 * arc / l0  # fibres off-centre differ
    assert m.n_bonds == m.n_beads - m.n_fibres
    assert np.all(np.diff(m.fibre_ids) >= 0) and np.all(np.diff(m.fibre_ids) <= 1)
    assert set(np.unique(m.atom_types)) == {1, 2} and m.family_names == ("warp", "weft")
    assert [bt.family for bt in m.bond_type_table] == ["warp", "weft"]
    assert m.info["yarns_per_unit_cell"] == {"warp": 2, "weft": 2}
    assert m.info["tiling"] == list(tiling)


def test_3d_counts_and_identity():
    m = render_fabric(interlock(n_fibres=7))
    fams = [y.family for y in m.yarns]
    assert (fams.count("warp"), fams.count("weft"), fams.count("binder")) == (8, 40, 8)
    assert m.family_names == ("warp", "weft", "binder") and m.n_fibres == 56 * 7
    binder = m.beads_of_family("binder")
    assert m.yarn_ids[binder].min() == 49
    assert m.info["architecture"]["columns"] == 8 and m.info["clearance_m"] > 0


def test_bending_adds_angles_along_each_fibre():
    m = render_fabric(plain(), Discretisation(bending_factor=0.5))
    assert len(m.angles) == m.n_beads - 2 * m.n_fibres
    assert np.all(m.fibre_ids[m.angles[:, 0]] == m.fibre_ids[m.angles[:, 2]])
    assert len(m.angle_type_table) == len(m.bond_type_table)


# -- periodic form ---------------------------------------------------------------------------
@pytest.mark.parametrize("fabric", [plain(tiling=(2, 1), periodic=True),
                                    interlock(periodic=True, n_fibres=7)],
                         ids=["plain", "interlock"])
def test_periodic_fibres_are_unbroken_at_the_boundary(fabric):
    m = render_fabric(fabric)
    assert m.periodic == (True, True, False)
    assert m.n_bonds == m.n_beads  # every fibre closes on itself
    rest = np.array([bt.rest_length_m for bt in m.bond_type_table])[m.bond_types - 1]
    np.testing.assert_allclose(m.bond_lengths(), rest, rtol=1e-6)
    # positions inside the box; unwrapped chains continuous except the closing bond
    assert np.all(m.positions[:, :2] >= 0) and np.all(m.positions[:, :2] < m.box_hi[:2])
    u = m.unwrapped_positions
    step = np.linalg.norm(u[m.bonds[:, 1]] - u[m.bonds[:, 0]], axis=1)
    closing = np.abs(step - rest) > 1e-6 * rest
    assert closing.sum() == m.n_fibres
    ends = m.fibre_ends()
    np.testing.assert_array_equal(np.sort(m.bonds[closing, 0]), ends[:, 1])
    # bond types of one family are contiguous
    fams = [bt.family for bt in m.bond_type_table]
    assert fams == sorted(fams, key=m.family_names.index)


# -- overlaps -------------------------------------------------------------------------------
def test_cell_list_matches_brute_force():
    rng = np.random.default_rng(3)
    n = 600
    box = np.array([1.0, 1.0, 0.3])
    pos = rng.random((n, 3)) * box
    diam = rng.uniform(0.02, 0.05, n)
    groups = rng.integers(0, 20, n)
    for periodic in [(False,) * 3, (True, True, False)]:
        res = closest_approach(pos, diam, groups, [0, 0, 0], box, periodic, cutoff_m=0.2)
        d = pos[:, None] - pos[None]
        for k in range(3):
            if periodic[k]:
                d[..., k] -= box[k] * np.round(d[..., k] / box[k])
        gap = np.linalg.norm(d, axis=2) - 0.5 * (diam[:, None] + diam[None])
        gap[groups[:, None] == groups[None]] = np.inf
        assert res.gap_m == pytest.approx(gap.min())
        assert res.overlaps == int((gap < 0).sum() // 2)
        assert {res.i, res.j} == set(np.unravel_index(np.argmin(gap), gap.shape))


def test_clearance_reported_matches_geometry():
    f = plain()
    m = render_fabric(f)
    # crossing centrelines are (h_warp + h_weft)/2 + clearance apart; the outer fibres lie
    # inside the section, so the bead gap is at least the requested clearance
    assert m.info["clearance_m"] >= f.clearance_m * (1 - 1e-6)
    assert math.isclose(m.info["requested_clearance_m"], 0.08e-3)


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("example", sorted(
    (Path(__file__).resolve().parents[1] / "examples").glob("*.toml")), ids=lambda p: p.stem)
def test_shipped_examples_have_no_overlapping_yarns(example, periodic):
    from fabmd.scenefile import load_scene

    scene = load_scene(example)
    fabric = dataclasses.replace(scene.fabric, periodic=periodic)
    m = render_fabric(fabric, scene.discretisation)  # raises on any overlap
    assert not m.info.get("auto_clearance_gap_short", False)
    assert m.info["clearance_m"] > 0.5 * fabric.clearance_m
    assert m.periodic[0] == periodic
