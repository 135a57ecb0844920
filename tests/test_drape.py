"""Hemispherical-punch draping: shear-angle analysis, validation, holder force control,
quarter against full model."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from fabmd.analysis import grid_edges, surface_shear_angle_field
from fabmd.analysis.synthetic import woven_sheet
from fabmd.errors import InputError
from fabmd.protocols.drape import Drape, DrapeGeometry, contact_angle_rad

from .fabrics import plain_weave_cell

#: a small drape of the tiny plain weave (2 mm yarn spacing): punch, depth, clearance
SMALL = {"punch_radius_m": 5e-3, "depth_m": 3e-3, "die_clearance_m": 1.5e-3,
         "holder_force_n": 20.0, "speed_fraction": 1e-3}


# -- shear angle from the yarn tangents ------------------------------------------------------
def _sheets(shear_deg: float):
    flat = woven_sheet(8, 8, spacing_m=2e-3, fibres=(2, 2), periodic=False)
    sheared = woven_sheet(8, 8, spacing_m=2e-3, fibres=(2, 2), periodic=False,
                          shear_deg=shear_deg)
    p = flat.positions
    cell = 4e-3  # one unit cell of the plain weave: the crimp cancels
    edges = (grid_edges(p[:, 0].min(), p[:, 0].max(), cell),
             grid_edges(p[:, 1].min(), p[:, 1].max(), cell))
    return flat, sheared, edges


@pytest.mark.parametrize("shear_deg", [0.0, 10.0, 30.0, 45.0])
def test_shear_angle_of_a_sheared_grid_is_the_imposed_angle(shear_deg):
    flat, sheared, (xe, ye) = _sheets(shear_deg)
    field = surface_shear_angle_field(flat.positions, sheared.positions, flat.fibre_ids,
                                      flat.families, xe, ye)
    values = field.values[np.isfinite(field.values)]
    assert values.size == 16
    assert np.abs(values - shear_deg).max() < 1e-6


@pytest.mark.parametrize("shear_deg", [10.0, 40.0])
def test_shear_angle_on_a_curved_surface_uses_the_tangents(shear_deg):
    """The sheared sheet bent onto a cylinder (an isometry: angles in the surface keep their
    size) still shows the imposed angle; its in-plane projection would not."""
    flat, sheared, (xe, ye) = _sheets(shear_deg)
    radius = 20e-3
    x, y, z = sheared.positions.T
    bent = np.column_stack([(radius - z) * np.sin(x / radius), y,
                            radius - (radius - z) * np.cos(x / radius)])
    field = surface_shear_angle_field(flat.positions, bent, flat.fibre_ids, flat.families,
                                      xe, ye)
    values = field.values[np.isfinite(field.values)]
    assert np.abs(values - shear_deg).max() < 0.1  # the bundle's thickness: ~ z/R
    # the bead values carry their cell's angle
    assert np.nanmax(np.abs(field.extra["bead_shear_deg"] - shear_deg)) < 0.1


def test_shear_angle_sign_does_not_depend_on_fibre_direction():
    flat, sheared, (xe, ye) = _sheets(20.0)
    reverse = flat.fibre_ids == flat.fibre_ids.max()  # one weft fibre numbered backwards
    order = np.arange(flat.n_beads)
    order[reverse] = order[reverse][::-1]
    field = surface_shear_angle_field(flat.positions[order], sheared.positions[order],
                                      flat.fibre_ids, flat.families[order], xe, ye)
    values = field.values[np.isfinite(field.values)]
    assert np.abs(values - 20.0).max() < 1e-6


def test_contact_angle_of_a_taut_fabric():
    # die edge level with the punch centre: the fabric leaves the punch at its equator
    # when the die edge is on the sphere
    assert math.degrees(contact_angle_rad(10.0, 10.0, 0.0, 0.0)) == pytest.approx(90.0)
    # shallow: die edge far out, well above the punch's lowest point
    shallow = contact_angle_rad(50e-3, 53e-3, 45e-3, 1e-3)
    assert 0 < shallow < math.radians(30)


# -- validation before LAMMPS ----------------------------------------------------------------
@pytest.mark.parametrize("kwargs, message", [
    ({"depth_m": 0.06}, "drape.depth_m must be <= punch_radius_m"),
    ({"holder_force_n": -5.0}, "drape.holder_force_n must be > 0"),
    ({"die_clearance_m": -1e-3}, "drape.die_clearance_m must be >= 0"),
    ({"symmetry": "half"}, "drape.symmetry must be one of"),
    ({"modulus_scale": 2.0}, "drape.modulus_scale must be in (0, 1]"),
    ({"holder_inner_radius_m": 0.04}, "drape.holder_inner_radius_m must be >="),
    ({"loading_speed": {"adaptive": True}}, "drape.loading_speed must be an AdaptiveLoading"),
    ({"loading_speed": __import__("fabmd.scene.adaptive", fromlist=["x"]).AdaptiveLoading(
        adaptive=True, max_speed_factor=100), "speed_fraction": 1e-3},
     "drape.loading_speed.max_speed_factor = 100"),
])
def test_bad_input_is_refused_in_one_line(kwargs, message):
    with pytest.raises(InputError) as err:
        Drape(**kwargs)
    assert message in str(err.value)
    assert "\n" not in str(err.value)


def test_a_blank_too_small_for_the_tools_is_refused():
    from fabmd.model.transform import cut, tile

    blank = cut(tile(plain_weave_cell(), 4, 4, periodic=False), 14e-3, 14e-3)
    with pytest.raises(InputError, match="must reach past the holder's opening"):
        Drape(**SMALL).prepare(blank)


def test_the_fabric_must_pass_between_punch_and_die():
    from fabmd.model.transform import cut, tile

    blank = cut(tile(plain_weave_cell(), 7, 7, periodic=False), 26e-3, 26e-3)
    drape = Drape(**{**SMALL, "depth_m": 5e-3, "die_clearance_m": 0.2e-3})
    with pytest.raises(InputError, match="raise drape.die_clearance_m"):
        drape.prepare(blank)


def test_cli_refuses_a_bad_drape_in_one_line_before_lammps(tmp_path):
    from .conftest import run_cli

    scene = tmp_path / "scene.toml"
    text = (Path(__file__).resolve().parents[1] / "examples" / "drape.toml").read_text()
    scene.write_text(text.replace('depth_m = "40 mm"', 'depth_m = "60 mm"'))
    done = run_cli("test", "drape", str(scene), "--out", str(tmp_path / "run"), timeout=120)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "drape.depth_m must be <= punch_radius_m" in lines[0]
    assert not (tmp_path / "run").exists()  # refused before any stage ran


def test_scene_table_builds_a_drape_with_units():
    from fabmd.pipeline import TESTS, build_protocol

    assert "drape" in TESTS
    drape = build_protocol("drape", {"punch_radius_m": "40 mm", "depth_m": "25 mm",
                                     "holder_force_n": "50 N", "symmetry": "full",
                                     "tool": {"friction": 0.15}})
    assert drape.punch_radius_m == pytest.approx(0.04)
    assert drape.tool.friction == 0.15
    with pytest.raises(InputError, match=r"\[drape\] drape.depth_m must be <="):
        build_protocol("drape", {"punch_radius_m": "40 mm", "depth_m": "45 mm"})


def test_adaptive_drape_integrates_the_punch_speed_and_the_default_does_not():
    """Opt-in adaptive punch (issue 20): the punch's travel is the integral of the adapted
    speed and the run halts at the travel; the default input has none of it."""
    from fabmd.model.transform import cut, tile
    from fabmd.scene.adaptive import AdaptiveLoading

    blank = Drape(**SMALL).prepare(cut(tile(plain_weave_cell(spacing_ratio=0.9), 7, 7,
                                            periodic=False), 26e-3, 26e-3))
    fixed = Drape(**SMALL)
    assert "adapt" not in fixed.input_text(blank)
    adaptive = Drape(**SMALL, loading_speed=AdaptiveLoading(adaptive=True, max_speed_factor=8))
    text = adaptive.input_text(blank)
    for line in ("fix             punch_integrate all controller 1 1.0 1.0 0.0 0.0 v_punch_vz",
                 "variable        punch_travel equal \"v_punch_travel_int\"",
                 "*v_adapt_factor", "fix             adapt_end all halt",
                 "v_punch_travel >= "):
        assert line in text, line
    plan, base = adaptive.plan(blank), fixed.plan(blank)
    assert plan.extra["adaptive"] and plan.every < base.every
    assert plan.extra["travel_m"] == pytest.approx(fixed.travel_m(blank))


# -- the quarter model and its input -----------------------------------------------------------
@pytest.fixture(scope="module")
def small_blank(tmp_path_factory):
    """A 26 mm blank tiled from the crimped tiny plain weave (coarse beads, s/d = 0.9)."""
    from fabmd.engine import Engine
    from fabmd.model.transform import cut, tile
    from fabmd.protocols.crimp import Crimp

    root = tmp_path_factory.mktemp("drape")
    crimped = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(
        plain_weave_cell(spacing_ratio=0.9), root / "crimp", engine=Engine(progress=False))
    return cut(tile(crimped.model, 7, 7, periodic=False), 26e-3, 26e-3)


@pytest.mark.lammps
def test_quarter_blank_holds_the_cut_fibre_ends_on_the_symmetry_planes(small_blank):
    drape = Drape(**SMALL)
    quarter = drape.prepare(small_blank)
    full = Drape(**{**SMALL, "symmetry": "full"}).prepare(small_blank)
    p = quarter.positions
    assert (p[:, 0] > 0).all() and (p[:, 1] > 0).all()
    assert 3.5 < full.n_beads / quarter.n_beads < 4.5
    g = drape.geometry(quarter)
    ends = np.unique(quarter.fibre_ends().ravel())
    assert set(g.sym_x) <= set(ends.tolist()) and g.sym_x and g.sym_y
    # warp ends (fibres along x) on x = 0, weft ends on y = 0
    assert set(quarter.families[list(g.sym_x)]) == {"warp"}
    assert set(quarter.families[list(g.sym_y)]) == {"weft"}
    # no yarn on a symmetry plane: the planes run between yarns
    d = quarter.diameters.max()
    assert (np.abs(full.positions[full.families == "weft", 0]) > 0.5 * d).all()
    text = drape.input_text(quarter)
    for line in ("region          punch sphere", "region          die cone",
                 "region          die_wall cylinder",
                 "fix             sym_x sym_x setforce 0.0 NULL NULL",
                 "fix             holder_control all controller", "wall/gran/region granular"):
        assert line in text


@pytest.mark.lammps
def test_tool_zones_skip_only_beads_that_cannot_reach_the_tools(small_blank):
    near = Drape(**SMALL)
    model = near.prepare(small_blank)
    g = near.geometry(model)
    r = np.hypot(model.positions[:, 0], model.positions[:, 1])
    zones = near.reach(g)
    assert 0 < (r <= zones["punch_reach"]).sum() < len(r)  # the skip skips something
    # a bead outside the punch zone cannot reach the punch: its arc at full depth
    assert zones["punch_reach"] > SMALL["punch_radius_m"] * np.arccos(
        1 - SMALL["depth_m"] / SMALL["punch_radius_m"])
    every = Drape(**SMALL, tool_zones=False).reach(g)
    assert (r <= every["punch_reach"]).all() and (r >= every["die_reach"]).all()
    assert (r <= every["flange_reach"]).all()


@pytest.mark.lammps
def test_blank_holder_force_holds_its_set_value(small_blank, tmp_path):
    from fabmd.engine import Engine
    from fabmd.scene.plan import read_plan

    drape = Drape(**SMALL, trajectory=__import__("fabmd.scene.outputs", fromlist=["x"])
                  .TrajectoryOutput(frames=2, paraview=False))
    result = drape.run(small_blank, tmp_path / "drape", engine=Engine(progress=False))
    s = result.summary
    holder = s["holder_force"]
    assert holder["max_relative_error"] < 0.10, holder
    assert abs(holder["mean_force_n"] - 20.0) < 0.5
    assert s["max_punch_force_n"] > 0 and s["max_shear_angle_deg"] > 1.0
    assert s["energy_balance"]["relative_error"] < 0.05
    plan = read_plan(result.run_dir)  # the summary reports the plan the run was written with
    assert (s["time_step_s"], s["steps"]) == (plan.time_step_s, plan.steps)
    assert s["punch_speed_m_s"] == plan.speed_m_s
    # punch_reach: the punch's reach against its zone (it held the zone radii alone)
    reach = s["punch_reach"]
    assert reach["touching_beads"] > 0 and reach["zone_holds"]
    assert 0 < reach["furthest_touching_start_radius_m"] <= reach["punch_zone_radius_m"]
    assert reach["punch_zone_radius_m"] == s["tool_zone_radii_m"]["punch_reach"]
    for name in ("curve.csv", "summary.json", "curve.png", "shear_angle.png",
                 "shear_angle.csv", "shear_angle.npz", "final.vtu", "shape.png",
                 "trajectory.h5"):
        assert (result.run_dir / name).exists(), name


@pytest.mark.lammps
def test_inprocess_drape_is_the_standalone_run(small_blank, tmp_path):
    """The in-process engine runs the drape's input in chunks (here of 20 steps, the
    adaptive punch's output interval); its curve is the one ``lmp -in`` makes of the same
    run folder. A set-up at every chunk (as before 2026-12-06) reset the moving punch's
    velocity, which LAMMPS takes from its travel over the last step: the punch met the
    fabric as if at rest in one force evaluation per chunk and its force read 2-6x the
    standalone run's below 2 mm."""
    from fabmd.engine import Engine
    from fabmd.scene.adaptive import AdaptiveLoading
    from fabmd.scene.outputs import TrajectoryOutput

    drape = Drape(**SMALL, trajectory=TrajectoryOutput(frames=0),
                  loading_speed=AdaptiveLoading(adaptive=True, max_speed_factor=8))
    a = drape.run(small_blank, tmp_path / "inprocess", engine=Engine(progress=False)).curve
    b = drape.run(small_blank, tmp_path / "standalone",
                  engine=Engine(backend="standalone", ranks=1)).curve
    assert len(a["punch_force_n"]) == len(b["punch_force_n"]) > 100
    peak = np.abs(b["punch_force_n"]).max()
    assert peak > 0
    assert np.abs(a["punch_force_n"] - b["punch_force_n"]).max() <= 1e-6 * peak


@pytest.mark.lammps
@pytest.mark.filterwarnings("ignore::fabmd.errors.QuasiStaticWarning")
def test_adaptive_punch_reaches_its_depth_and_follows_the_fixed_run(small_blank, tmp_path):
    """The adaptive punch travels the depth (halted at its travel, the speed history in the
    curve, within its bounds), keeps its base speed until it carries the floor force (a
    punch sped up in its free travel reached the blank at 4x its base speed), and its
    force follows the fixed-speed run's. Measured 2026-12-06: work to 3 mm -0.1 %, force
    at 2 / 3 mm +4.8 / -4.3 %. (Before the in-process chunks stopped being set up anew,
    each set-up met the fabric with the punch at rest, 8x as often in the adaptive run,
    whose output interval is shorter: its work read +29 ... +42 % of the fixed run's.)"""
    from fabmd.engine import Engine
    from fabmd.scene.adaptive import AdaptiveLoading
    from fabmd.scene.outputs import TrajectoryOutput

    quiet = TrajectoryOutput(frames=0)
    fixed = Drape(**SMALL, trajectory=quiet)
    adaptive = dataclasses.replace(fixed, loading_speed=AdaptiveLoading(
        adaptive=True, max_speed_factor=8))
    f = fixed.run(small_blank, tmp_path / "fixed", engine=Engine(progress=False)).curve
    result = adaptive.run(small_blank, tmp_path / "adaptive", engine=Engine(progress=False))
    c, s = result.curve, result.summary
    blank = adaptive.prepare(small_blank)
    assert c["punch_travel_m"][-1] >= adaptive.travel_m(blank)  # the halt: at or past it
    speed = c["punch_speed_m_s"] / adaptive.plan(blank).speed_m_s
    assert speed.min() > -0.05 and speed.max() <= 8.0 * 1.05
    floor = 0.01 * adaptive.holder_share_n(adaptive.geometry(blank))
    engaged = int(np.argmax(c["punch_force_n"] > floor))
    assert 0 < engaged and speed[:engaged + 1].max() <= 1.0 + 1e-6
    run = s["adaptive_loading"]
    assert 0 < run["steps"] <= adaptive.plan(blank).steps

    def work_j(curve, depth=3e-3):
        inside = curve["depth_m"] <= depth
        return np.trapezoid(curve["punch_force_n"][inside], curve["depth_m"][inside])

    assert work_j(c) == pytest.approx(work_j(f), rel=0.05)
    for depth in (2e-3, 3e-3):
        a, b = (np.interp(depth, x["depth_m"], x["punch_force_n"]) for x in (c, f))
        assert a == pytest.approx(b, rel=0.1)


@pytest.mark.lammps
@pytest.mark.slow
def test_quarter_and_full_model_agree(tmp_path):
    """A 56 mm blank of the tiny plain weave under a 12 mm punch, 7.5 mm deep (about 75 s:
    the full model has 7000 beads): punch force and largest shear angle within 5 %."""
    from fabmd.engine import Engine
    from fabmd.model.contact import ContactModel, ToolContact
    from fabmd.model.transform import cut, tile
    from fabmd.protocols.crimp import Crimp
    from fabmd.scene.outputs import TrajectoryOutput

    # the legacy per-bead contact (k_n = 0.1·E·A/l0) as this test was set up: at this
    # fabric's s/d 0.9 the per-length default is 3.2x stiffer, and the quarter model's
    # draw-in then differs from the full one's by 13 % (an open item, issue 16)
    legacy = ContactModel(stiffness_factor=0.1)
    crimped = Crimp(expansion={"warp": -0.1, "weft": -0.1}, contact=legacy).run(
        plain_weave_cell(spacing_ratio=0.9), tmp_path / "crimp", engine=Engine(progress=False))
    blank = cut(tile(crimped.model, 15, 15, periodic=False), 56e-3, 56e-3)
    case = {"punch_radius_m": 12e-3, "depth_m": 7.5e-3, "die_clearance_m": 1.5e-3,
            "holder_force_n": 40.0, "speed_fraction": 2e-3, "contact": legacy,
            "tool": ToolContact(friction=0.2, stiffness_factor=0.1),
            "trajectory": TrajectoryOutput(frames=0)}
    result = {}
    for symmetry in ("quarter", "full"):
        run = Drape(**case, symmetry=symmetry).run(blank, tmp_path / symmetry,
                                                   engine=Engine(progress=False))
        result[symmetry] = run.summary
    q, f = result["quarter"], result["full"]
    assert 3.5 < f["n_beads"] / q["n_beads"] < 4.5
    for key in ("max_punch_force_n", "final_punch_force_n", "max_shear_angle_deg"):
        assert abs(q[key] - f[key]) / f[key] < 0.05, (key, q[key], f[key])
    assert abs(q["draw_in"]["warp_m"] - f["draw_in"]["warp_m"]) < 0.1 * f["draw_in"]["warp_m"]


def test_blank_shear_of_a_sheared_turned_and_drawn_blank():
    """The whole-blank shear is the imposed in-plane shear; a rigid turn or a pure draw-in
    gives none."""
    from fabmd.protocols.drape import blank_shear_deg

    xs = np.linspace(-0.05, 0.05, 21)
    ref = np.array([(x, y, 0.0) for x in xs for y in xs])
    g = DrapeGeometry(quarter=False, radius_m=0.02, die_radius_m=0.023, holder_radius_m=0.023,
                      z_die_m=0.0, z_holder_m=0.0, punch_z_m=0.0, gap_m=0.0, thickness_m=1e-3,
                      spacing_m=5e-3, half_size_m=(0.05, 0.05), punch_reach_m=0.03,
                      die_reach_m=0.02, contact_angle_rad=1.0, flange_reach_m=0.04,
                      face_radius_m=0.2, diameter_m=1e-3, sym_x=(), sym_y=())
    k = 0.01  # u = k·(y, x): engineering shear 2k
    sheared = ref + k * ref[:, [1, 0, 2]] * np.array([1.0, 1.0, 0.0])
    assert blank_shear_deg(ref, sheared, g) == pytest.approx(np.degrees(2 * k), rel=1e-9)
    a = np.radians(1.0)
    turned = ref @ np.array([[np.cos(a), np.sin(a), 0], [-np.sin(a), np.cos(a), 0], [0, 0, 1]])
    assert abs(blank_shear_deg(ref, turned, g)) < 1e-9
    assert abs(blank_shear_deg(ref, ref * np.array([0.9, 0.9, 1.0]), g)) < 1e-12


def test_punch_reach_is_how_far_out_the_fabric_on_the_punch_started():
    """summary["punch_reach"] held the tool-zone radii (stop 15's note): it is the start
    radius of the furthest bead on the punch against the punch zone's radius."""
    from fabmd.protocols.drape.measures import punch_reach

    g = DrapeGeometry(quarter=False, radius_m=0.02, die_radius_m=0.023, holder_radius_m=0.023,
                      z_die_m=0.0, z_holder_m=0.0, punch_z_m=0.03, gap_m=0.0,
                      thickness_m=1e-3, spacing_m=5e-3, half_size_m=(0.05, 0.05),
                      punch_reach_m=0.03, die_reach_m=0.02, contact_angle_rad=1.0,
                      flange_reach_m=0.04, face_radius_m=0.2, diameter_m=1e-3, sym_x=(),
                      sym_y=())
    ref = np.array([[0.0, 0.0, 0.0], [0.01, 0.0, 0.0], [0.025, 0.0, 0.0], [0.04, 0.0, 0.0]])
    travel = 0.02  # the punch centre ends at z = 0.01: beads on its sphere touch it
    final = np.array([[0.0, 0.0, -0.0105], [0.0, 0.012, -0.006], [0.015, 0.0, -0.0032],
                      [0.04, 0.0, 0.0]])  # the last one stayed flat, clear of the punch
    out = punch_reach(ref, final, g, travel, zone_radius_m=0.03)
    assert out["touching_beads"] == 3
    assert out["furthest_touching_start_radius_m"] == pytest.approx(0.025)
    assert out["zone_holds"] and out["punch_zone_radius_m"] == 0.03
    assert not punch_reach(ref, final, g, travel, zone_radius_m=0.02)["zone_holds"]
    assert punch_reach(ref, ref, g, 0.0, 0.03)["furthest_touching_start_radius_m"] is None
