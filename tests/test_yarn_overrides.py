"""Per-yarn and per-layer yarn specs within a family (YarnOverride)."""

import tomllib

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.geometry import Fabric, Weave, YarnSpec
from fabmd.geometry.architecture3d import Architecture3D
from fabmd.geometry.overrides import YarnOverride
from fabmd.model.beads import model_bead_parameters
from fabmd.model.fabric_model import bead_parameter_list, render_fabric
from fabmd.model.material import GLASS, FibreMaterial
from fabmd.protocols.crimp import Crimp
from fabmd.protocols.crimp_tension import yarn_axial_stiffness_n
from fabmd.results.measure import areal_density_kg_m2, passed_through
from fabmd.scene.outputs import TrajectoryOutput
from fabmd.scenefile import parse_scene

LIGHT, HEAVY = 600.0, 1200.0  # tex
N_FIBRES = 3


def _heavy_warp_fabric(**kw) -> Fabric:
    """A periodic plain-weave cell (2 warp, 2 weft) whose warp 2 is twice as heavy."""
    light = YarnSpec(LIGHT, GLASS, width_m="1.6 mm", height_m="0.5 mm", spacing_m="3 mm",
                     n_fibres=N_FIBRES)
    heavy = YarnSpec(HEAVY, GLASS, width_m="2.2 mm", height_m="0.8 mm", spacing_m="3 mm",
                     n_fibres=N_FIBRES)
    return Fabric(Weave.plain(), light, light, periodic=True, clearance_m="0.05 mm",
                  overrides=(YarnOverride("warp", heavy, yarns=[2]),), **kw)


def _fibre_facts(model):
    """Per fibre: yarn name, bead mass, E·A of its bonds, and Σ rest lengths (its length)."""
    out = []
    fib = model.fibre_ids[model.bonds[:, 0]]
    for fid in np.unique(model.fibre_ids):
        beads = model.fibre_ids == fid
        types = np.unique(model.bond_types[fib == fid])
        assert len(types) == 1  # one bond type per fibre
        bt = model.bond_type_table[types[0] - 1]
        yarn = model.yarns[model.fibre_yarn[fid - 1] - 1].name
        n_bonds = int(np.sum(fib == fid))
        out.append((yarn, np.unique(model.masses[beads]), 2 * bt.coefficient * bt.rest_length_m,
                    n_bonds * bt.rest_length_m, bt))
    return out


def test_heavier_warp_yarn_beads_follow_its_tex():
    fabric = _heavy_warp_fabric()
    model = render_fabric(fabric)  # the overlap check passes
    E, rho = GLASS.modulus_pa, GLASS.density_kg_m3
    names = {p.name: fabric.spec_of(p).linear_density_tex for p in fabric.yarn_paths()}
    assert names == {"warp-1": LIGHT, "warp-2": HEAVY, "weft-1": LIGHT, "weft-2": LIGHT}
    for yarn, mass, ea, length, bt in _fibre_facts(model):
        tex = names[yarn]
        area = tex * 1e-6 / rho / N_FIBRES  # filament area of one virtual fibre
        assert len(mass) == 1
        assert mass[0] == pytest.approx(rho * area * bt.rest_length_m, rel=1e-12)
        assert ea == pytest.approx(E * area, rel=1e-12)
        assert bt.axial_stiffness_n == pytest.approx(E * area, rel=1e-12)
        assert bt.spec == ("warp:1" if yarn == "warp-2" else yarn.split("-")[0])
        # the chain of a closed fibre weighs tex/N per metre of its length
        assert mass[0] * length / bt.rest_length_m == pytest.approx(area * rho * length)
    # the stage parameters see the heavy spec too (time step, contact)
    params = bead_parameter_list(model, fabric)
    recovered = model_bead_parameters(model)
    assert [p.mass_kg for p in params] == pytest.approx([p.mass_kg for p in recovered])
    assert [p.axial_stiffness_n for p in params] == pytest.approx(
        [p.axial_stiffness_n for p in recovered])
    assert model.info["yarn_spec"] == ["warp", "warp:1", "weft", "weft"]
    # the crimp's tension search sees the mean yarn stiffness: (3 E·A + 3 · 2 E·A) / 2
    ea = E * LIGHT * 1e-6 / rho / N_FIBRES
    assert yarn_axial_stiffness_n(model, "warp") == pytest.approx(1.5 * N_FIBRES * ea)
    assert yarn_axial_stiffness_n(model, "weft") == pytest.approx(N_FIBRES * ea)
    assert model.info["yarn_specs"]["warp:1"]["yarns"] == ["warp-2"]


def test_heavier_warp_yarn_areal_density_sums_per_yarn():
    fabric = _heavy_warp_fabric()
    model = render_fabric(fabric)
    s = 3e-3
    straight = fabric.straight_areal_density_kg_m2()
    # Σ tex · length per area: two warps (600 + 1200 tex) and two wefts across a 6 x 6 mm cell
    assert straight["warp"] == pytest.approx((LIGHT + HEAVY) * 1e-6 / (2 * s), rel=1e-12)
    assert straight["weft"] == pytest.approx(2 * LIGHT * 1e-6 / (2 * s), rel=1e-12)
    # built: tex × centreline length per yarn; the bead masses agree (fibres off the
    # centreline are a little longer or shorter)
    info = model.info
    assert info["areal_density_kg_m2"] == pytest.approx(areal_density_kg_m2(model), rel=0.01)
    assert info["areal_density_kg_m2"] > sum(straight.values())
    heavy = model.yarn_ids == 2
    assert float(model.masses[heavy].sum()) == pytest.approx(
        2 * float(model.masses[model.yarn_ids == 1].sum()), rel=0.02)


def test_heavier_warp_yarn_crosses_further_from_the_mid_plane():
    fabric = _heavy_warp_fabric()
    paths = {p.name: p for p in fabric.yarn_paths()}
    c = fabric.clearance_m
    for name, h_warp in (("warp-1", 0.5e-3), ("warp-2", 0.8e-3)):
        expected = 0.25 * (h_warp + 0.5e-3) + 0.5 * c
        assert np.abs(paths[name].node_z_m) == pytest.approx([expected] * 2, rel=1e-12)
    # each weft meets each warp at that warp's separation, on the other side
    weft = paths["weft-1"]
    assert np.abs(weft.node_z_m) == pytest.approx(
        [0.25 * (0.5e-3 + 0.5e-3) + 0.5 * c, 0.25 * (0.8e-3 + 0.5e-3) + 0.5 * c])


@pytest.mark.lammps
def test_heavier_warp_yarn_cell_crimps(tmp_path):
    loose = render_fabric(_heavy_warp_fabric())
    shrink = 0.5 * min(loose.info["crimp"].values())
    crimp = Crimp(expansion={"warp": -shrink, "weft": -shrink},
                  trajectory=TrajectoryOutput(frames=0))
    assert crimp.shrink_warnings(loose) == []
    result = crimp.run(loose, tmp_path / "crimp", engine=Engine(progress=False))
    s = result.summary
    assert s["quasi_static"], s["criterion"]
    assert s["pass_through"]["flipped_pairs"] == 0
    assert passed_through(loose, result.model)["flipped_pairs"] == 0
    assert s["crimped"]["thickness_m"] < s["loose"]["thickness_m"]
    # mass is conserved, and the heavy yarn keeps its own bead mass and bond types
    assert s["areal_density_kg_m2"] == pytest.approx(areal_density_kg_m2(loose), rel=1e-9)
    assert result.model.masses == pytest.approx(loose.masses, rel=1e-9)
    assert [bt.spec for bt in result.model.bond_type_table] == \
        [bt.spec for bt in loose.bond_type_table]


def test_heavier_middle_layer_stuffers_render_with_the_larger_section():
    arch = Architecture3D.through_thickness(weft_layers=4, dents=2)  # stuffers in gaps 1..3
    glass = FibreMaterial("30 GPa", "1.9 g/cm3")
    warp = YarnSpec("600 tex", glass, "1.6 mm", 4, spacing_m="8 mm", fibre_volume_fraction=0.5)
    k = 1.25  # the middle stuffers: a section k x wider and k x taller, k² x the tex at Vf 0.5
    heavy = YarnSpec(600 * k * k, glass, k * 1.6e-3, 4, spacing_m="8 mm",
                     fibre_volume_fraction=0.5)
    weft = YarnSpec("600 tex", glass, "2 mm", 4, spacing_m="4 mm", fibre_volume_fraction=0.5)
    binder = YarnSpec("300 tex", glass, "0.9 mm", 1, fibre_volume_fraction=0.5)
    fabric = Fabric(arch, warp, weft, binder, periodic=True, plateau=0.3,
                    overrides=[YarnOverride("warp", heavy, layers=[2])])
    assert heavy.height_m == pytest.approx(k * warp.height_m, rel=1e-9)
    model = render_fabric(fabric)  # no overlap
    assert fabric.levels()["gap_height"][2] == pytest.approx(heavy.height_m)
    extent = {}
    for yid, yarn in enumerate(model.yarns, start=1):
        if yarn.family != "warp":
            continue
        beads = model.unwrapped_positions[model.yarn_ids == yid]
        d = float(model.diameters[model.yarn_ids == yid].max())
        spans = np.ptp(beads[:, 1:], axis=0) + d
        extent.setdefault(model.info["yarn_spec"][yid - 1], []).append(spans)
    assert len(extent["warp:1"]) == 2 and len(extent["warp"]) == 4  # gap 2 of both dents
    # the packing is self-similar: the heavy stuffers' fibres spread k x as far in y and z
    assert np.array(extent["warp:1"]) == pytest.approx(k * np.array(extent["warp"][:2]),
                                                       rel=1e-6)
    mass = {key: model.masses[model.yarn_ids == 1 + model.info["yarn_spec"].index(key)].sum()
            for key in ("warp", "warp:1")}
    assert mass["warp:1"] / mass["warp"] == pytest.approx(k * k, rel=1e-9)


SCENE = """
[fabric]
architecture = "plain"
periodic = true
clearance_m = "0.05 mm"
[yarns.warp]
material = "glass"
linear_density_tex = "600 tex"
n_fibres = 3
width_m = "1.6 mm"
height_m = "0.5 mm"
spacing_m = "3 mm"
[[yarns.warp.overrides]]
yarns = [2]
linear_density_tex = "1200 tex"
width_m = "2.2 mm"
height_m = "0.8 mm"
[yarns.weft]
material = "glass"
linear_density_tex = "600 tex"
n_fibres = 3
width_m = "1.6 mm"
height_m = "0.5 mm"
spacing_m = "3 mm"
"""


def test_scene_file_overrides_build_the_same_cell():
    scene = parse_scene(tomllib.loads(SCENE))
    expected = _heavy_warp_fabric()
    assert scene.fabric.overrides[0].spec == expected.overrides[0].spec
    a, b = render_fabric(scene.fabric), render_fabric(expected)
    assert np.array_equal(a.masses, b.masses) and np.allclose(a.positions, b.positions)


OVERRIDE = 'yarns = [2]\nlinear_density_tex = "1200 tex"\nwidth_m = "2.2 mm"\nheight_m = "0.8 mm"\n'


@pytest.mark.parametrize("body, message", [
    ("yarns = [2]\nlayers = [1]\n", "layers are for 3D"),
    ("yarns = [3]\n", r"positions 1\.\.2"),
    ('yarns = [2]\nspacing_m = "4 mm"\n', "differs from the family's"),
    ('linear_density_tex = "1200 tex"\n', "give yarns"),
    ('yarns = [2]\nlinear_density_tex = "2000 tex"\n', "packing limit"),
    ("yarns = [2]\nmaterial = \"kevlar\"\n", "not defined"),
])
def test_bad_overrides_are_refused_before_lammps(body, message):
    assert OVERRIDE in SCENE
    with pytest.raises(InputError, match=message):
        parse_scene(tomllib.loads(SCENE.replace(OVERRIDE, body)))


def test_a_heavier_weft_layer_sets_its_own_level_spacing():
    arch = Architecture3D.through_thickness(weft_layers=4, dents=2)
    glass = FibreMaterial("30 GPa", "1.9 g/cm3")
    warp = YarnSpec("600 tex", glass, "1.6 mm", 4, spacing_m="8 mm", fibre_volume_fraction=0.5)
    weft = YarnSpec("600 tex", glass, "2 mm", 4, spacing_m="4 mm", fibre_volume_fraction=0.5)
    heavy = YarnSpec("900 tex", glass, "2 mm", 4, spacing_m="4 mm", fibre_volume_fraction=0.5)
    binder = YarnSpec("300 tex", glass, "0.9 mm", 1, fibre_volume_fraction=0.5)
    fabric = Fabric(arch, warp, weft, binder, periodic=True, plateau=0.3,
                    overrides=[YarnOverride("weft", heavy, layers=[2])])
    model = render_fabric(fabric)  # no overlap
    lev, c = fabric.levels(), fabric.clearance_m
    gap, h = lev["gap"], lev["gap_height"]
    for k, hf in enumerate([weft.height_m, heavy.height_m, weft.height_m, weft.height_m]):
        # weft layer k + 1 lies half its height plus half the gap's height (+ c) from each gap
        assert gap[k] - lev["weft"][k] == pytest.approx(0.5 * (h[k] + hf) + c, rel=1e-9)
        assert lev["weft"][k] - gap[k + 1] == pytest.approx(0.5 * (h[k + 1] + hf) + c,
                                                            rel=1e-9)
    names = [y.name for y, key in zip(model.yarns, model.info["yarn_spec"], strict=True)
             if key == "weft:1"]
    assert len(names) == arch.columns
