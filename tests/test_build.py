"""Scene files, ``fabmd build`` outputs, and LAMMPS accepting rendered fabrics."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.scenefile import load_scene, parse_scene

from .conftest import run_cli

ROOT = Path(__file__).resolve().parents[1]
PLAIN = ROOT / "examples" / "plain_weave.toml"
INTERLOCK = ROOT / "examples" / "angle_interlock_3d.toml"


def minimal(**extra) -> dict:
    scene = {
        "fabric": {"architecture": "plain"},
        "materials": {"glass": {"modulus_pa": "73 GPa", "density_kg_m3": 2540}},
        "yarns": {fam: {"material": "glass", "linear_density_tex": "600 tex",
                        "width_m": "1.6 mm", "height_m": "0.8 mm", "spacing_m": "2.5 mm"}
                  for fam in ("warp", "weft")},
    }
    for key, value in extra.items():
        section, _, sub = key.partition("__")
        if sub:
            scene.setdefault(section, {}).setdefault(sub, {}).update(value)
        else:
            scene.setdefault(section, {}).update(value)
    return scene


# -- scene files -------------------------------------------------------------------------
def test_examples_load_with_units():
    s = load_scene(PLAIN)
    assert s.fabric.warp.linear_density_tex == pytest.approx(600)
    assert s.fabric.warp.spacing_m == pytest.approx(2.5e-3)  # from "4 ends/cm"
    assert s.fabric.warp.material.modulus_pa == 73e9
    assert s.contact.friction == 0.3 and s.discretisation.spacing_ratio == 0.5
    s3 = load_scene(INTERLOCK)
    assert s3.fabric.yarns_per_unit_cell() == {"warp": 8, "weft": 40, "binder": 8}


def test_protocol_sections_are_kept_raw():
    s = parse_scene(minimal(crimp={"tension_n": 5, "anything": [1, 2]},
                            drape={"punch": {"radius_m": "50 mm"}}))
    assert s.protocols == {"crimp": {"tension_n": 5, "anything": [1, 2]},
                           "drape": {"punch": {"radius_m": "50 mm"}}}


@pytest.mark.parametrize("scene,words", [
    (minimal(yarns__warp={"widht_m": 1e-3}), "[yarns.warp] has no key 'widht_m'"),
    (minimal(fabric={"tilling": [2, 2]}), "[fabric] has no key 'tilling'"),
    (minimal(fabric={"depth": 1}), "[fabric] has no key 'depth'"),
    (minimal(contact={"frction": 0.2}), "[contact] has no key 'frction'"),
    (minimal(discretisation={"spacing": 0.5}), "[discretisation] has no key 'spacing'"),
    (minimal(materials__glass={"E": 1}), "[materials.glass] has no key 'E'"),
    (minimal(fabric={"architecture": "jacquard"}), "architecture must be one of plain"),
    (minimal(yarns__warp={"material": "steel"}), "material 'steel' is not defined"),
    (minimal(yarns__warp={"width_m": "2 furlongs"}), "unknown length unit 'furlongs'"),
    (minimal(yarns__binder={"material": "glass", "linear_density_tex": 300,
                            "width_m": 1e-3}), "only used by 3D"),
    (minimal(yarns__warp={"width_m": "3 mm"}), "does not fit the warp spacing"),
    (minimal(fabric={"architecture": "matrix", "matrix": [[1, 1], [0, 1]]}),
     "warp yarn 1 (row 1) never interlaces"),
    (minimal(fabric={"architecture": "layer_to_layer"}), "[yarns.binder] is required"),
    ({**minimal(), "speed": 3}, "unknown top-level key 'speed'"),
])
def test_bad_scenes_are_one_line_errors(scene, words):
    with pytest.raises(InputError) as err:
        parse_scene(scene, source="s.toml")
    msg = str(err.value)
    assert words in msg and msg.startswith("s.toml") and "\n" not in msg


def test_3d_scene_in_the_general_form(tmp_path):
    scene = minimal(fabric={"architecture": "binder_paths", "weft_layers": 2,
                            "binder_paths": [[[0, 2]], [[2, 0]]], "warp_gaps": [1]},
                    yarns__warp={"spacing_m": "4 mm"},
                    yarns__binder={"material": "glass", "linear_density_tex": 300,
                                   "width_m": "1 mm", "height_m": "0.5 mm", "n_fibres": 3})
    s = parse_scene(scene)
    m = s.model()
    assert [y.family for y in m.yarns].count("binder") == 2 and m.info["clearance_m"] > 0


def test_toml_syntax_errors_are_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[fabric\narchitecture = 'plain'\n")
    with pytest.raises(InputError, match="not valid TOML") as err:
        load_scene(bad)
    assert "\n" not in str(err.value)


# -- fabmd build -----------------------------------------------------------------------------
def _check_folder(out: Path, n_beads: int | None = None):
    import MDAnalysis
    import meshio

    summary = json.loads((out / "summary.json").read_text())
    u = MDAnalysis.Universe(str(out / "model.data"),
                            atom_style="id type x y z diameter density resid", format="DATA")
    assert len(u.atoms) == summary["n_beads"] and len(u.bonds) == summary["n_bonds"]
    if n_beads is not None:
        assert summary["n_beads"] == n_beads
    fibres = meshio.read(out / "fibres.vtu")
    assert len(fibres.points) == summary["n_beads"]
    n_open = summary["n_bonds"] - (summary["n_fibres"] if summary["periodic"] else 0)
    assert len(fibres.cells[0].data) == n_open
    assert set(fibres.cell_data) >= {"yarn_id", "fibre_id", "family"}
    assert fibres.field_data["family_weft"][0] == 2
    yarns = meshio.read(out / "yarns.vtu")
    assert set(np.unique(yarns.cell_data["yarn_id"][0])) == set(range(1, summary["n_yarns"] + 1))
    png = (out / "preview.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000
    scene = json.loads((out / "scene.json").read_text())
    assert scene["fabric"]["type"] == "Fabric"
    return summary


def test_build_plain_weave_example(tmp_path):
    out = tmp_path / "plain"
    res = run_cli("build", str(PLAIN), "--out", str(out))
    assert res.returncode == 0, res.stderr
    assert "beads" in res.stdout and "smallest gap" in res.stdout
    s = _check_folder(out)
    assert s["yarns"] == {"warp": 4, "weft": 4} and s["fibres"] == {"warp": 28, "weft": 28}
    assert 2000 < s["n_beads"] < 20000 and s["clearance_m"] > 0
    # never over an existing folder unless asked
    again = run_cli("build", str(PLAIN), "--out", str(out))
    assert again.returncode == 2 and "--overwrite" in again.stderr
    assert run_cli("build", str(PLAIN), "--out", str(out), "--overwrite").returncode == 0


def test_build_3d_example_and_its_periodic_form(tmp_path):
    from fabmd.cli.build import build

    res = run_cli("build", str(INTERLOCK), "--out", str(tmp_path / "ai"), "--json")
    assert res.returncode == 0, res.stderr
    s = _check_folder(tmp_path / "ai")
    assert json.loads(res.stdout)["n_beads"] == s["n_beads"]
    assert s["yarns"] == {"warp": 8, "weft": 40, "binder": 8} and s["clearance_m"] > 0
    scene = load_scene(INTERLOCK)
    scene.fabric = dataclasses.replace(scene.fabric, periodic=True)
    sp = build(scene, tmp_path / "aip")
    assert sp["periodic"] and sp["clearance_m"] > 0 and sp["n_bonds"] == sp["n_beads"]
    _check_folder(tmp_path / "aip")


def test_bad_scene_on_the_command_line_is_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(PLAIN.read_text().replace("n_fibres = 7", "n_fibers = 7", 1))
    res = run_cli("build", str(bad), "--out", str(tmp_path / "x"))
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and "no key 'n_fibers'" in lines[0]
    assert not (tmp_path / "x").exists()


# -- LAMMPS accepts the rendered data files --------------------------------------------------------
@pytest.mark.lammps
@pytest.mark.parametrize("example,periodic,fibres", [
    (PLAIN, False, None), (PLAIN, True, None), (INTERLOCK, True, 1)],
    ids=["plain", "plain-periodic", "interlock-periodic"])
def test_lammps_reads_the_fabric_and_bonds_are_at_rest(tmp_path, example, periodic, fibres):
    from fabmd.engine import Engine
    from fabmd.model.fabric_model import bead_parameter_list
    from fabmd.protocols.common import write_run_folder
    from fabmd.scene import blocks

    scene = load_scene(example)
    f = dataclasses.replace(scene.fabric, periodic=periodic)
    if fibres:
        f = dataclasses.replace(f, **{fam: dataclasses.replace(spec, n_fibres=fibres)
                                      for fam, spec in f.specs().items()})
    scene.fabric = f
    model = scene.model()
    beads = bead_parameter_list(model, f, scene.discretisation)
    kn = scene.contact.normal_stiffness_n_per_m(beads)
    dt = 0.25 * min(b.critical_time_step_s(kn) for b in beads)
    text = "\n".join([
        blocks.setup(model, "check", "model.data", dt), blocks.bonds(model),
        blocks.contact(model, scene.contact, beads), "fix integrate all nve",
        "compute bond_energy all pe bond",
        "thermo_style custom step atoms c_bond_energy",
        # not a plain 'run 0': the in-process engine skips plain zero-step runs
        "run 0 post no",
        'print "atoms $(atoms) bonds $(bonds) bond_energy_j $(c_bond_energy:%.6e)" '
        'file check.txt screen no',
    ])
    run_dir = write_run_folder(tmp_path / "run", "check", model, text, {},
                               files=blocks.contact_files(scene.contact, beads))
    Engine(progress=False).run(run_dir, "in.check")
    words = (run_dir / "check.txt").read_text().split()
    got = {k: float(v) for k, v in zip(words[::2], words[1::2], strict=True)}
    assert got["atoms"] == model.n_beads and got["bonds"] == model.n_bonds
    # bonds at rest: energy of a strain of 1e-6 in every bond is an upper bound
    k = np.array([bt.coefficient for bt in model.bond_type_table])[model.bond_types - 1]
    r0 = np.array([bt.rest_length_m for bt in model.bond_type_table])[model.bond_types - 1]
    assert got["bond_energy_j"] < float(np.sum(k * (1e-6 * r0) ** 2))
