"""The scene-file pipeline: fabmd crimp, fabmd test, fabmd measure (tiny scene, seconds)."""

import json

import pytest

from fabmd.errors import InputError
from fabmd.pipeline import coupon_stage, crimp_stage, protocol_stage, run_test
from fabmd.scenefile import load_scene, parse_scene

from .conftest import run_cli

pytestmark = pytest.mark.lammps

TINY = """
title = "tiny plain weave, one virtual fibre per yarn"
[fabric]
architecture = "plain"
[materials.soft]
modulus_pa = "1 GPa"
density_kg_m3 = 2540
[yarns.warp]
material = "soft"
linear_density_tex = 600
n_fibres = 1
width_m = "1.0 mm"
count_per_m = "4 ends/cm"
[yarns.weft]
material = "soft"
linear_density_tex = 600
n_fibres = 1
width_m = "1.0 mm"
count_per_m = "4 picks/cm"
[crimp]
expansion = { warp = -0.08, weft = -0.08 }
[tension]
max_elongation_pct = 2.0
speed_fraction = 2e-4
coupon = { cells = [3, 2] }
"""


@pytest.fixture
def tiny_scene(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return path


def test_stage_settings_come_from_the_scene(tiny_scene):
    import tomllib

    scene = parse_scene(tomllib.loads(TINY))
    assert crimp_stage(scene).expansion == {"warp": -0.08, "weft": -0.08}
    coupon, source = coupon_stage(scene, "tension")
    assert source == "cell" and coupon.length_m == pytest.approx(3 * 5e-3)
    assert protocol_stage(scene, "tension").max_elongation_pct == 2.0
    bad = parse_scene(tomllib.loads(TINY.replace("max_elongation_pct", "max_elongaton_pct")))
    with pytest.raises(InputError, match="max_elongaton_pct"):
        protocol_stage(bad, "tension")


def test_cli_crimp_test_and_measure(tiny_scene, tmp_path):
    out = run_cli("crimp", str(tiny_scene), "--out", str(tmp_path / "c"), "--form", "cell",
                  "--json")
    assert out.returncode == 0, out.stderr
    crimp = json.loads(out.stdout)
    assert crimp["quasi_static"] and crimp["crimped"]["thickness_m"] < crimp["loose"][
        "thickness_m"]
    out = run_cli("test", "tension", str(tiny_scene), "--out", str(tmp_path / "t"),
                  "--crimped", str(tmp_path / "c"), "--json")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)["test_summary"]
    assert summary["energy_balance"]["relative_error"] < 0.05
    for name in ("coupon/coupon.data", "tension/curve.csv", "tension/curve.png",
                 "summary.json"):
        assert (tmp_path / "t" / name).exists(), name
    out = run_cli("measure", str(tmp_path / "c"), "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["thickness_m"] == pytest.approx(
        crimp["crimped"]["thickness_m"], rel=1e-6)
    again = run_cli("measure", str(tmp_path / "c"))
    assert again.returncode == 2 and "--overwrite" in again.stderr


def test_a_test_of_an_earlier_crimp_reports_that_crimps_law(tmp_path):
    """``fabmd test --crimped DIR`` carries the crimp folder's ``within_family_law`` (where
    the law's fibres touch, the kPa cut off) into its own summary and terminal lines."""
    scene = tmp_path / "tiny_law.toml"
    scene.write_text(TINY.replace(
        "[crimp]", '[contact]\nwithin_family = { law = "glass", form = "law" }\n[crimp]'))
    out = run_cli("crimp", str(scene), "--out", str(tmp_path / "c"), "--form", "cell",
                  "--json")
    assert out.returncode == 0, out.stderr
    law = json.loads(out.stdout)["within_family_law"]
    assert set(law) == {"warp", "weft"}
    out = run_cli("test", "tension", str(scene), "--out", str(tmp_path / "t"),
                  "--crimped", str(tmp_path / "c"))
    assert out.returncode == 0, out.stderr
    assert json.loads((tmp_path / "t" / "summary.json").read_text())["within_family_law"] == law
    assert "within-family law: warp, weft fibres touch at Vf" in out.stdout


def test_resume_of_a_finished_pipeline_keeps_stages(tiny_scene, tmp_path):
    import tomllib

    from fabmd.engine import Engine

    scene = parse_scene(tomllib.loads(TINY), source=str(tiny_scene))
    engine = Engine(progress=False, checkpoint_every=2000)
    first = run_test(scene, "tension", tmp_path / "r", engine=engine)
    assert (tmp_path / "r" / "crimp" / "crimped.data").exists()
    with pytest.raises(InputError, match="nothing to resume"):
        run_test(scene, "tension", tmp_path / "missing", engine=engine, resume=True)
    assert first["test_summary"]["steps"] > 0


def test_a_scene_that_releases_starts_its_tests_from_the_released_cell(tiny_scene, tmp_path):
    """``[crimp] release_tension``: ``fabmd crimp`` ends with the release (``release/``, the
    summary's ``released``, its crimp measured there); a test given a folder crimped without
    it releases that cell in its own folder; one whose scene does not ask for it takes the
    woven cell of a released folder."""
    import tomllib

    from fabmd.engine import Engine
    from fabmd.protocols.crimp import load_crimped

    released = tmp_path / "released.toml"
    released.write_text(TINY.replace("[crimp]\n", "[crimp]\nrelease_tension = true\n"
                                     "handling_tension = \"0.5 N\"\n"))
    out = run_cli("crimp", str(released), "--out", str(tmp_path / "c"), "--form", "cell",
                  "--json")
    assert out.returncode == 0, out.stderr
    crimp = json.loads(out.stdout)
    assert crimp["released"]["settled"] and crimp["released"]["strain_pct"][0] < 0
    assert crimp["crimped"]["crimp_pct"]["warp"] > crimp["woven"]["crimp_pct"]["warp"]
    assert (tmp_path / "c" / "release" / "released.data").exists()
    woven = load_crimped(tmp_path / "c", released=False)
    kept = load_crimped(tmp_path / "c")
    assert kept.box_hi[0] - kept.box_lo[0] < woven.box_hi[0] - woven.box_lo[0]
    # a folder crimped without the release, tested with the scene that asks for it
    engine = Engine(progress=False)
    plain = parse_scene(tomllib.loads(TINY), source=str(tiny_scene))
    run_test(plain, "tension", tmp_path / "t0", engine=engine)
    scene = parse_scene(tomllib.loads(released.read_text()), source=str(released))
    summary = run_test(scene, "tension", tmp_path / "t1", engine=engine,
                       crimped=tmp_path / "t0" / "crimp")
    rel = json.loads((tmp_path / "t1" / "release" / "summary.json").read_text())
    assert rel["strain_pct"][0] < 0 and summary["test_summary"]["steps"] > 0
    assert not (tmp_path / "t0" / "crimp" / "release").exists()  # the input folder untouched


def test_presets_change_discretisation_and_speed_only():
    import tomllib

    from fabmd.presets import apply_preset

    scene = parse_scene(tomllib.loads(TINY.replace("n_fibres = 1", "n_fibres = 7")))
    fast = apply_preset(scene, "fast")
    accurate = apply_preset(scene, "accurate")
    # the values chosen on the run-time/error front (benchmarks/accuracy.py)
    assert fast.fabric.warp.n_fibres == 1 and accurate.fabric.warp.n_fibres == 19
    assert fast.discretisation.spacing_ratio == 0.25
    assert accurate.discretisation.spacing_ratio == 0.5
    # both load at the scene's own speed (speed factor 1)
    assert fast.protocols["tension"]["speed_fraction"] == pytest.approx(2e-4)
    assert accurate.protocols["tension"]["speed_fraction"] == pytest.approx(2e-4)
    # the fabric itself is unchanged: same spacing and yarn size
    assert fast.fabric.warp.spacing_m == scene.fabric.warp.spacing_m
    assert fast.fabric.warp.width_m == scene.fabric.warp.width_m
    assert fast.model().n_beads < scene.model().n_beads < accurate.model().n_beads
    with pytest.raises(InputError, match="preset must be one of"):
        apply_preset(scene, "sloppy")


def test_presets_never_make_a_scene_costlier_or_coarser_than_meant():
    """--fast keeps a scene that is already coarser (the drape example: one fibre, s/d 0.9);
    --accurate keeps one that is already finer."""
    import tomllib

    from fabmd.examples_dir import example_scene
    from fabmd.presets import apply_preset, resolution

    drape = load_scene(example_scene("drape.toml"))
    fast = apply_preset(drape, "fast")
    assert fast.discretisation.spacing_ratio == drape.discretisation.spacing_ratio == 0.9
    assert fast.fabric.warp.n_fibres == 1
    plain = load_scene(example_scene("plain_weave.toml"))
    assert resolution(1, 0.25) < resolution(plain.fabric.warp.n_fibres,
                                            plain.discretisation.spacing_ratio)
    assert apply_preset(plain, "fast").discretisation.spacing_ratio == 0.25
    fine = parse_scene(tomllib.loads(TINY.replace("n_fibres = 1", "n_fibres = 37")))
    accurate = apply_preset(fine, "accurate")
    assert accurate.fabric.warp.n_fibres == 37


def test_a_preset_rebuilds_the_yarn_law_on_its_own_fibre():
    """The plain-weave example carries the within-family law, whose pair forces are built
    on the virtual fibre: ``--fast`` (one fibre of the whole yarn's area) and ``--accurate``
    (19) rebuild it there — kept at 7 fibres, LAMMPS refused the table at the first
    command ("the warp fibres need the law's bead diameter ...")."""
    import dataclasses

    from fabmd import presets
    from fabmd.examples_dir import example_scene
    from fabmd.model.fabric_model import family_beads

    scene = load_scene(example_scene("plain_weave.toml"))
    assert scene.contact.within_family_law is not None
    for name, fibres in (("fast", 1), ("accurate", 19)):
        run = presets.apply_preset(scene, name)
        fibre = family_beads(run.fabric, run.discretisation)["warp"].fibre
        assert run.fabric.warp.n_fibres == fibres
        for _, law in run.contact.within_family_laws:
            assert law.diameter_m == pytest.approx(fibre.diameter_m, rel=1e-12)
            assert law.area_m2 == pytest.approx(fibre.area_m2, rel=1e-12)
        assert run.contact.within_family_law.diameter_m == pytest.approx(fibre.diameter_m)
    # a contact built or replaced in Python is not re-derived from the table: said, or kept
    python_built = dataclasses.replace(scene, contact_table=None)
    with pytest.raises(InputError, match="built or replaced in Python"):
        python_built.with_fibres(1)
    assert python_built.rediscretised(spacing_ratio=0.25).discretisation.spacing_ratio == 0.25
    replaced = dataclasses.replace(scene, contact=dataclasses.replace(
        scene.contact, within_family_law=None, within_family_laws=(), friction=0.1))
    assert presets.apply_preset(replaced, "fast").contact.friction == 0.1  # kept


def test_preset_speed_factor_scales_every_driven_test(monkeypatch):
    import tomllib

    from fabmd import presets

    scene = parse_scene(tomllib.loads(TINY))
    monkeypatch.setitem(presets.PRESETS, "slow", presets.Preset(speed_factor=0.5))
    slow = presets.apply_preset(scene, "slow")
    assert slow.protocols["tension"]["speed_fraction"] == pytest.approx(0.5 * 2e-4)
    # a test the scene has no table for: half its default speed
    assert slow.protocols["picture_frame"]["speed_fraction"] == pytest.approx(0.5 * 1e-3)
    assert slow.fabric == scene.fabric and slow.discretisation == scene.discretisation


def test_demo_fast_runs_end_to_end(tmp_path):
    out = run_cli("demo", "--fast", "--out", str(tmp_path / "demo"))
    assert out.returncode == 0, out.stderr
    assert "picture frame" in out.stdout and "locking angle" in out.stdout
    assert "periodic shear (the fabric without clamps" in out.stdout
    summary = json.loads((tmp_path / "demo" / "summary.json").read_text())
    assert summary["periodic_shear"]["normalised_force_at_angle_n_m"]
    # the tension says whether its initial stiffness comes from a quasi-static toe
    trusted = summary["tension"]["initial_stiffness_trusted"]
    assert ("toe not quasi-static: an upper bound" in out.stdout) is (not trusted)
    # the crimp says where the law's fibres touch in the fabric it crimped (the preset's)
    from fabmd.examples_dir import example_scene
    from fabmd.presets import apply_preset

    scene = apply_preset(load_scene(example_scene("plain_weave.toml")), "fast")
    law = summary["crimp"]["within_family_law"]
    assert law == scene.contact.law_realisation(("warp", "weft"))
    assert law["warp"]["touching_vf"] > 0 and "within-family law: warp, weft fibres touch at" \
        in out.stdout
    for name in ("demo.png", "summary.json", "loose/preview.png", "crimp/sections.png",
                 "tension/tension/curve.png", "picture_frame/picture_frame/curve.png",
                 "periodic_shear/periodic_shear/curve.png"):
        assert (tmp_path / "demo" / name).exists(), name
