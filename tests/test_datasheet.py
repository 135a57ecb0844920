"""Fabrics from their datasheet: section sizing, datasheet checks, dense weaves, 3D binders."""

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.geometry import Fabric, Weave, YarnSpec
from fabmd.geometry.architecture3d import Architecture3D
from fabmd.geometry.section import Section
from fabmd.model.fabric_model import render_fabric
from fabmd.model.material import CARBON, GLASS, FibreMaterial
from fabmd.protocols.crimp import Crimp
from fabmd.results.measure import areal_density_kg_m2, passed_through
from fabmd.scene.outputs import TrajectoryOutput
from fabmd.scenefile import load_scene, parse_scene

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
DATASHEET_EXAMPLES = ("carbon_plain_3k", "glass_twill_600", "through_thickness_3d")


# -- sections hold the filament area ------------------------------------------------------
def _numeric_area(section: Section) -> float:
    """2·∫ half-thickness du by the trapezoid rule on a fine grid (independent of area_m2)."""
    u = np.linspace(-0.5 * section.width_m, 0.5 * section.width_m, 200001)
    return float(np.trapezoid(2 * section.half_thickness_m(u), u))


@pytest.mark.parametrize("shape", ["ellipse", "lenticular", "racetrack"])
@pytest.mark.parametrize("vf", [0.4, 0.6, 0.8])
def test_sections_hold_the_filament_area_at_the_stated_packing(shape, vf):
    spec = YarnSpec("600 tex", GLASS, width_m="2 mm", fibre_volume_fraction=vf, shape=shape,
                    n_fibres=1)
    filament_area = 600e-6 / 2540.0  # tex·1e-6/ρ
    # the section's own area integrated numerically holds tex/ρ at the packing
    assert _numeric_area(spec.section) * vf == pytest.approx(filament_area, rel=1e-5)
    assert spec.yarn_fibre_volume_fraction == pytest.approx(vf, rel=1e-9)
    assert spec.width_m == pytest.approx(2e-3)


@pytest.mark.parametrize("shape", ["lenticular", "racetrack"])
def test_packings_of_new_shapes_stay_inside_and_do_not_overlap(shape):
    sec = Section("2 mm", "0.4 mm", shape)
    offsets, d = sec.packing(7)
    assert d > 0
    # every fibre circle inside the outline: centre at least d/2 below the local half-height
    # (sampled under the circle)
    for u, v in offsets:
        du = np.linspace(-0.5 * d, 0.5 * d, 41)
        dv = np.sqrt(np.clip(0.25 * d * d - du * du, 0.0, None))
        assert np.all(np.abs(v) + dv <= sec.half_thickness_m(u + du) * (1 + 1e-6) + 1e-12)
    gaps = np.linalg.norm(offsets[:, None] - offsets[None], axis=2) + np.eye(7) * d
    assert gaps.min() >= d * (1 - 1e-9)


def test_width_defaults_to_the_spacing_and_height_follows():
    spec = YarnSpec("198 tex", CARBON, count_per_m="5 ends/cm", fibre_volume_fraction=0.6)
    assert spec.width_m == pytest.approx(2e-3)
    assert math.pi / 4 * spec.width_m * spec.height_m * 0.6 == pytest.approx(198e-6 / 1780)


# -- refused datasheets, with the numbers -------------------------------------------------
def test_over_full_yarn_is_refused_with_the_numbers():
    with pytest.raises(InputError) as err:
        YarnSpec("600 tex", GLASS, width_m="1.6 mm", height_m="0.2 mm", name="weft")
    msg = str(err.value)
    ellipse = math.pi / 4 * 1.6 * 0.2  # mm²
    assert "weft" in msg and "0.8" in msg and f"{600 / 2540:.4g}" in msg
    assert f"{ellipse:.4g}" in msg and f"{600 / 2540 / ellipse:.3g}" in msg
    assert "\n" not in msg
    with pytest.raises(InputError, match=r"fibre_volume_fraction must be in \(0, 0.8\]"):
        YarnSpec("600 tex", GLASS, width_m="2 mm", fibre_volume_fraction=0.85)


def test_inconsistent_filaments_are_refused_with_the_arithmetic():
    carbon = FibreMaterial("230 GPa", "1.76 g/cm3")
    ok = YarnSpec("198 tex", carbon, width_m="2 mm", fibre_volume_fraction=0.6,
                  filament_diameter_m="7 um", filament_count="3K")
    assert ok.filament_count == 3000
    with pytest.raises(InputError) as err:  # 12K filaments cannot weigh 198 tex
        YarnSpec("198 tex", carbon, width_m="2 mm", fibre_volume_fraction=0.6,
                 filament_diameter_m="7 um", filament_count="12K")
    msg = str(err.value)
    assert "12000 filaments" in msg and f"{12000 * math.pi / 4 * 49e-6:.4g}" in msg
    assert f"{198 / 1760:.4g}" in msg


def test_areal_density_below_the_straight_yarns_is_refused_with_the_sum():
    yarn = YarnSpec("198 tex", CARBON, count_per_m="5 ends/cm", fibre_volume_fraction=0.6)
    straight = 2 * 198 * 5e2 * 1e-3  # Σ tex·count [g/m²]
    fabric = Fabric(Weave.plain(), yarn, yarn, areal_density_kg_m2="200 g/m2")
    assert sum(fabric.straight_areal_density_kg_m2().values()) == pytest.approx(straight * 1e-3)
    with pytest.raises(InputError) as err:
        Fabric(Weave.plain(), yarn, yarn, areal_density_kg_m2="150 g/m2")
    msg = str(err.value)
    assert "150 g/m²" in msg and f"{straight:.4g} g/m²" in msg and "crimp" in msg
    with pytest.raises(InputError, match="heavier than its straight yarns"):
        Fabric(Weave.plain(), yarn, yarn, areal_density_kg_m2="400 g/m2")


def test_scene_reads_thickness_at_pressure_and_counts_from_fabric():
    data = {"fabric": {"architecture": "plain", "thickness": "1.2 mm at 4.14 kPa",
                       "ends_per_m": "5 ends/cm", "picks_per_m": "4 picks/cm"},
            "yarns": {f: {"material": "glass", "linear_density_tex": "600 tex",
                          "fibre_volume_fraction": 0.5} for f in ("warp", "weft")}}
    fabric = parse_scene(data).fabric
    assert fabric.thickness_m == pytest.approx(1.2e-3)
    assert fabric.thickness_pressure_pa == pytest.approx(4140.0)
    assert fabric.warp.spacing_m == pytest.approx(2e-3)
    assert fabric.weft.spacing_m == pytest.approx(2.5e-3)
    data["yarns"]["warp"]["count_per_m"] = "5 ends/cm"
    with pytest.raises(InputError, match="both set the warp count"):
        parse_scene(data)


# -- the shipped datasheet examples -------------------------------------------------------
@pytest.mark.parametrize("name", DATASHEET_EXAMPLES)
def test_datasheet_examples_parse_and_their_arithmetic_holds(name):
    path = EXAMPLES / f"{name}.toml"
    raw = tomllib.loads(path.read_text())
    scene = load_scene(path)
    fabric = scene.fabric
    # Σ tex · yarn length per area, from the file's own numbers
    lx, ly = fabric.unit_cell_m
    counts = fabric.yarns_per_unit_cell()
    straight = sum(float(raw["yarns"][f]["linear_density_tex"].split()[0]) * 1e-6 * n
                   * (lx if f != "weft" else ly) / (lx * ly) for f, n in counts.items())
    assert sum(fabric.straight_areal_density_kg_m2().values()) == pytest.approx(straight)
    model = render_fabric(fabric, scene.discretisation)
    info = model.info
    # built areal density = Σ tex · count · (1 + crimp), within 3 % of the datasheet
    assert info["areal_density_kg_m2"] == pytest.approx(areal_density_kg_m2(model), rel=0.01)
    assert abs(info["datasheet"]["areal_density_deviation"]) < 0.03
    for fam, pack in info["yarn_packing"].items():
        assert pack["yarn_fibre_volume_fraction"] <= 0.8, fam


# -- dense fabrics ------------------------------------------------------------------------
def _dense_plain(ratio=0.95):
    spacing = 2e-3
    yarn = YarnSpec("198 tex", CARBON, width_m=ratio * spacing, spacing_m=spacing,
                    fibre_volume_fraction=0.3, n_fibres=8)  # one row across the width
    return Fabric(Weave.plain(), yarn, yarn, periodic=True, clearance_m="auto")


def test_dense_plain_weave_builds_a_loose_state_without_overlap():
    fabric = _dense_plain()
    assert fabric.warp.width_m / fabric.warp.spacing_m == pytest.approx(0.95)
    # as given, the full-width rows of fibres collide where crossing yarns change level
    with pytest.raises(InputError, match="overlap"):
        render_fabric(Fabric(Weave.plain(), fabric.warp, fabric.weft, periodic=True))
    model = render_fabric(fabric)
    info = model.info
    assert info["clearance_m"] >= -1e-6 * float(model.diameters.min())
    assert info["loose_width_factor"] < 1 or info["lift_m"] > 0
    # a narrower loose yarn keeps its filament area at the same section area
    pack = info["yarn_packing"]["warp"]
    assert pack["woven_width_m"] == pytest.approx(1.9e-3)
    assert pack["yarn_fibre_volume_fraction"] == pytest.approx(0.3, rel=1e-9)


@pytest.mark.lammps
def test_dense_plain_weave_crimps(tmp_path):
    loose = render_fabric(_dense_plain())
    crimp = Crimp(expansion={"warp": -0.02, "weft": -0.02},  # loose crimp 2.7 %
                  trajectory=TrajectoryOutput(frames=0))
    result = crimp.run(loose, tmp_path / "crimp", engine=Engine(progress=False))
    s = result.summary
    assert s["quasi_static"], s["criterion"]
    assert s["pass_through"]["flipped_pairs"] == 0
    assert s["crimped"]["thickness_m"] < s["loose"]["thickness_m"]
    for fam in ("warp", "weft"):  # tightened but still woven
        assert 0 < s["crimped"]["crimp_pct"][fam] < s["loose"]["crimp_pct"][fam]
    # mass is conserved: the crimped cell weighs what the loose one does
    assert s["areal_density_kg_m2"] == pytest.approx(areal_density_kg_m2(loose), rel=1e-9)
    assert passed_through(loose, result.model)["flipped_pairs"] == 0


# -- any 3D binder layout -----------------------------------------------------------------
def _expected_gap(column: int, phase: int, layers: int = 5, columns: int = 8) -> int:
    q = (column - phase) % columns
    return int(round(layers * (1 - abs(1 - 2 * q / columns))))


def test_through_thickness_cell_with_40_weft_and_8_binders_renders_the_binder_paths():
    arch = Architecture3D.through_thickness(weft_layers=5, columns=8, dents=2, binders=4)
    assert (arch.n_weft, arch.n_warp, arch.n_binders) == (40, 8, 8)
    stated = [list(p) for dent in arch.binder_paths for p in dent]
    # binder q: one full crossing per cell, a column later than binder q - 1
    assert stated == [[_expected_gap(c, q) for c in range(8)] for q in range(8)]
    glass = FibreMaterial("30 GPa", "1.9 g/cm3")
    warp = YarnSpec("1000 tex", glass, "1.8 mm", 1, spacing_m="10 mm", fibre_volume_fraction=0.6)
    weft = YarnSpec("1000 tex", glass, "2 mm", 1, spacing_m="3 mm", fibre_volume_fraction=0.6)
    binder = YarnSpec("300 tex", glass, "0.9 mm", 1, fibre_volume_fraction=0.6)
    fabric = Fabric(arch, warp, weft, binder, periodic=True, plateau=0.3)
    model = render_fabric(fabric)
    gap_z = fabric.levels()["gap"]
    columns_x = (np.arange(8) + 0.5) * 3e-3
    binder_ids = [k for k, y in enumerate(model.yarns, start=1) if y.family == "binder"]
    planes = set()
    rendered = []
    for yid in binder_ids:
        beads = model.unwrapped_positions[model.yarn_ids == yid]
        planes.add(round(float(beads[:, 1].mean()), 9))
        at = [beads[np.argmin(np.abs(beads[:, 0] - x)), 2] for x in columns_x]
        rendered.append([int(np.argmin(np.abs(np.array(gap_z) - z))) for z in at])
    assert sorted(map(tuple, rendered)) == sorted(map(tuple, stated))
    assert len(planes) == 8  # every binder in its own plane


def test_3d_example_at_7_fibres_builds_with_narrower_loose_weft():
    """At 7 fibres per yarn the through-thickness example's binders pass between weft
    columns too wide for them (no lift separates yarns side by side); the auto search
    narrows warp and weft (binders keep their size) until the loose state exists. At its
    own 3 fibres the example still builds as given (factor 1: unchanged)."""
    text = (EXAMPLES / "through_thickness_3d.toml").read_text()
    assert text.count("n_fibres = 3") == 3
    scene = parse_scene(tomllib.loads(text.replace("n_fibres = 3", "n_fibres = 7")))
    model = render_fabric(scene.fabric, scene.discretisation)
    info = model.info
    assert info["loose_width_factor"] < 1
    assert info["clearance_m"] is None or info["clearance_m"] >= 0
    pack = info["yarn_packing"]
    assert pack["weft"]["woven_width_m"] == pytest.approx(2e-3)  # spread back in the crimp
    assert pack["binder"]["width_m"] == pytest.approx(0.9e-3)
    assert areal_density_kg_m2(model) == pytest.approx(2.2, rel=0.03)


def test_binders_every_second_dent_and_old_layouts_unchanged():
    arch = Architecture3D.through_thickness(weft_layers=4, dents=4, binder_every=2)
    assert [len(d) for d in arch.binder_paths] == [1, 0, 1, 0]
    ortho = Architecture3D.orthogonal(weft_layers=3, dents=4, binder_every=2)
    assert [len(d) for d in ortho.binder_paths] == [1, 0, 1, 0]
    # a layer-to-layer cell of any width: binder b between gaps b and b + 2, in order
    l2l = Architecture3D.layer_to_layer(weft_layers=5, depth=1, columns=6, dents=2)
    assert l2l.columns == 6 and l2l.n_binders == 8
    for dent in l2l.binder_paths:
        for b, path in enumerate(dent):
            assert min(path) == b and max(path) == b + 2
    old = Architecture3D.through_thickness(weft_layers=4, dents=2)
    assert old.columns == 8 and not old.separate_binders
    assert list(old.binder_paths[0][0]) == [0, 1, 2, 3, 4, 3, 2, 1]
    assert list(old.binder_paths[1][0]) == [4, 3, 2, 1, 0, 1, 2, 3]  # half a period on


# -- crimp that ends where a woven fabric is ----------------------------------------------
def test_shrink_beyond_the_loose_crimp_is_flagged():
    yarn = YarnSpec("600 tex", GLASS, width_m="1.6 mm", height_m="0.8 mm", spacing_m="2.5 mm",
                    n_fibres=1)
    model = render_fabric(Fabric(Weave.plain(), yarn, yarn, periodic=True))
    loose = model.info["crimp"]["warp"]
    assert loose > 0
    over = Crimp(expansion={"warp": -1.1 * loose, "weft": -0.9 * loose})
    messages = over.shrink_warnings(model)
    assert len(messages) == 1 and "crimp.expansion.warp" in messages[0]
    assert f"{100 * loose:.3g} %" in messages[0]
    assert Crimp(expansion={"warp": -0.9 * loose}).shrink_warnings(model) == []


def test_fabmd_build_prints_areal_density_thickness_and_packing(tmp_path):
    from .conftest import run_cli

    out = run_cli("build", str(EXAMPLES / "carbon_plain_3k.toml"), "--out",
                  str(tmp_path / "b"), check=True).stdout
    assert "areal density" in out and "(datasheet 200 g/m²" in out
    assert "datasheet 0.25 mm at 4.14 kPa" in out
    assert "yarn packing: warp Vf 0.60" in out and "weft Vf 0.60" in out


@pytest.mark.parametrize("shape", ["lenticular", "racetrack"])
def test_lenticular_and_racetrack_yarns_build_a_weave(shape):
    yarn = YarnSpec("600 tex", GLASS, width_m="1.8 mm", spacing_m="2.5 mm", shape=shape,
                    fibre_volume_fraction=0.6, n_fibres=5)
    model = render_fabric(Fabric(Weave.plain(), yarn, yarn, periodic=True))  # no overlap
    pack = model.info["yarn_packing"]["warp"]
    assert pack["shape"] == shape
    assert pack["filament_area_m2"] / pack["section_area_m2"] == pytest.approx(0.6)
    # the fibres stay inside the section: their offsets span at most its height and width
    offsets, d = yarn.packing()
    assert 2 * np.abs(offsets[:, 1]).max() + d <= yarn.height_m * (1 + 1e-9)
    assert 2 * np.abs(offsets[:, 0]).max() + d <= yarn.width_m * (1 + 1e-9)
