"""The trajectory-cost benchmark runs (tiny) and edits inputs as it says."""

import dataclasses
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

from fabmd.scene.outputs import TrajectoryOutput

ROOT = Path(__file__).resolve().parents[1]


def load_benchmark(name: str):
    """The script ``benchmarks/<name>.py`` as a module (registered under ``name``: its
    dataclasses look their module up)."""
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))  # the scripts import their helpers
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def test_trajectory_block_is_taken_out_and_put_in():
    bench = load_benchmark("trajectory_cost")
    out = TrajectoryOutput(frames=4)
    text = "units si\n" + out.commands(100) + "\nrun 100\n" + out.final_commands() + "\nx\n"
    plain = bench.without_trajectory(text)
    assert "dump" not in plain and "run 0" not in plain and "run 100" in plain
    again = bench.with_trajectory(plain, out)
    assert again.index("fabmd_trajectory all custom 25") < again.index("run 100")
    assert again.index("run 100") < again.index("run             0 pre no post no")
    assert bench.with_trajectory(text, out) == text  # a block already there is kept


@pytest.mark.lammps
def test_benchmark_runs_on_a_tiny_sheet(tmp_path):
    bench = load_benchmark("trajectory_cost")
    report = tmp_path / "cost.json"
    assert bench.main(["--yarns", "2", "--fibres", "2x1", "--steps", "100", "--frames", "2",
                       "--json", str(report)]) == 0
    result = json.loads(report.read_text())
    assert result["frames"] == 3 and result["beads"] == 640
    assert result["trajectory_h5_mb"] > 0 and result["run_without_cpu_s"] > 0


def load_accuracy():
    return load_benchmark("accuracy")


def test_accuracy_configuration_keeps_the_fabric_and_the_physical_speed():
    bench = load_accuracy()
    from fabmd.scenefile import load_scene

    base = load_scene(ROOT / "examples" / "plain_weave.toml")
    scene = bench.Config(n_fibres=19, spacing_ratio=0.25, mass_scaling=100.0,
                         speed=0.5).scene(base)
    assert scene.fabric.warp.n_fibres == 19 and scene.fabric.weft.n_fibres == 19
    assert scene.fabric.warp.spacing_m == base.fabric.warp.spacing_m
    assert scene.discretisation.spacing_ratio == 0.25
    assert scene.discretisation.mass_scaling == 100.0
    # the example's own speeds: from its file (the test's default where it sets none)
    from fabmd.pipeline import build_protocol

    speeds = bench.base_speeds(base)
    for name in ("tension", "picture_frame"):
        own = base.protocols[name].get("speed_fraction")
        assert speeds[name] == (own if own is not None
                                else build_protocol(name.replace("_", "-")).speed_fraction)
        # mass scaling lowers the wave speed by sqrt(m): the fraction grows by sqrt(m)
        assert scene.protocols[name]["speed_fraction"] == pytest.approx(speeds[name] * 0.5 * 10)
    without = dataclasses.replace(base, protocols={k: {kk: vv for kk, vv in v.items()
                                                       if kk != "speed_fraction"}
                                                   for k, v in base.protocols.items()})
    assert bench.base_speeds(without)["tension"] == build_protocol("tension").speed_fraction
    assert scene.protocols["tension"]["coupon"] == {"cells": list(bench.TENSION_CELLS)}
    # the base is untouched
    assert base.protocols["tension"]["coupon"] != scene.protocols["tension"]["coupon"]


def test_accuracy_errors_and_pareto_front():
    bench = load_accuracy()
    curve = {"x": [0.0, 1.0, 2.0, 3.0], "y": [0.0, 1.0, 2.0, 3.0]}
    ref = {"tension": {"values": {"stiffness": 10.0, "F1%": 1.0, "F2%": 2.0, "F3%": 3.0},
                       "curve": curve},
           "picture_frame": {"values": {"F20°": 4.0, "F40°": 8.0, "locking": 40.0},
                             "curve": curve}}
    run = {"tension": {"values": {"stiffness": 11.0, "F1%": 1.0, "F2%": 2.0, "F3%": 3.0},
                       "curve": curve},
           "picture_frame": {"values": {"F20°": 3.0, "F40°": 8.0, "locking": None},
                             "curve": {"x": curve["x"], "y": [0.0, 1.0, 2.0, 6.0]}}}
    e = bench.relative_errors(run, ref)
    assert e["tension"]["values"]["stiffness"] == pytest.approx(0.1)
    assert e["picture_frame"]["values"]["F20°"] == pytest.approx(-0.25)
    assert e["picture_frame"]["values"]["curve"] == pytest.approx(1.0)  # 3 off at 3, of 3
    assert e["picture_frame"]["combined"] == 1.0  # no locking angle found counts as 100 %
    assert e["combined"] == 1.0
    points = [("a", 1.0, 0.5), ("b", 2.0, 0.6), ("c", 3.0, 0.1), ("d", 0.5, 0.9)]
    assert bench.pareto_front(points) == ["d", "a", "c"]


def test_presets_errors_are_taken_past_the_toe_and_at_the_frame_angles():
    """The presets table judges tension by F at 4/5/6 % only (not the toe) and the frame
    by F_norm at 10-40 deg and the locking angle; the locking column is in degrees."""
    bench = load_benchmark("presets")
    curve = {"x": [0.0, 1.0], "y": [0.0, 1.0]}

    def record(label, toe, past, frame, lock, wall):
        return {"label": label, "wall_s": wall,
                "crimp": {"beads": 100, "crimp_pct": 2.0},
                "tension": {"values": {**{f"F{s}%": toe for s in (1, 2, 3)},
                                       **{f"F{s}%": past for s in (4, 5, 6)},
                                       "stiffness": toe}, "curve": curve},
                "picture_frame": {"values": {**{f"F{a}°": frame for a in (10, 20, 30, 40)},
                                             "locking": lock}, "curve": curve}}

    configs = bench.configs()
    assert list(configs) == ["fast", "default", "accurate", "reference"]
    data = {"records": [record(configs["default"].label, 2.0, 110.0, 1.0, 30.0, 10.0),
                        record(configs["reference"].label, 1.0, 100.0, 1.0, 32.0, 40.0)],
            "base_speed": {"tension": 1e-4, "picture_frame": 1e-3}}
    rows, errors = bench.rows(data)
    assert [r[0] for r in rows] == ["default"]
    # the toe's +100 % is shown, not judged; past it +10 %
    assert errors["default"]["tension"]["combined"] == pytest.approx(0.1)
    assert errors["default"]["picture_frame"]["combined"] == pytest.approx(2 / 32)
    assert rows[0][8] == "-2.0"  # locking, degrees
    assert "+100.0 / +100.0 / +10.0 / +10.0 / +10.0" in rows[0][6]
    assert "Reference **N19 s/d 0.5 v×0.5**" in bench.section(data)


def test_presets_at_the_reference_crimp_keep_runs_already_there_and_say_what_missed():
    """--pinned: a preset within the tolerance of the reference's crimp in every family
    keeps its runs; the pinned table judges against the plain reference, counts the
    calibration in the run time and names the closest crimp of a calibration that missed."""
    bench = load_benchmark("presets")
    tol = bench.PIN_TOLERANCE_PCT
    ref_crimp = {"warp": 1.5, "weft": 1.6}
    near = {"crimp": {"crimp_pct_by_family": {"warp": 1.5 + 0.9 * tol, "weft": 1.6}}}
    off = {"crimp": {"crimp_pct_by_family": {"warp": 1.5, "weft": 1.6 + 1.1 * tol}}}
    assert bench.at_crimp(near, ref_crimp) and not bench.at_crimp(off, ref_crimp)
    assert not bench.at_crimp({"crimp": {"crimp_pct": 1.5}}, ref_crimp)  # no families

    curve = {"x": [0.0, 1.0], "y": [0.0, 1.0]}
    configs = bench.configs()

    def record(label, past, wall, crimp):
        return {"label": label, "wall_s": wall,
                "crimp": {"beads": 100, "crimp_pct": sum(crimp.values()) / 2,
                          "crimp_pct_by_family": crimp},
                "tension": {"values": {f"F{s}%": past for s in (2, 3, 4, 5, 6)},
                            "curve": curve},
                "picture_frame": {"values": {**{f"F{a}°": 1.0 for a in (10, 20, 30, 40)},
                                             "locking": 30.0}, "curve": curve}}

    reference = record(configs["reference"].label, 100.0, 40.0, ref_crimp)
    pinned_default = record(configs["default"].label, 105.0, 10.0, ref_crimp)
    pinned_default["pinned"] = {"calibrated": True, "calibration_wall_s": 5.0}
    data = {"records": [record(configs["default"].label, 70.0, 10.0, {"warp": 2, "weft": 2}),
                        reference],
            "base_speed": {"tension": 1e-4, "picture_frame": 1e-3},
            "pinned": {"default": pinned_default,
                       "fast": {"label": configs["fast"].label, "pinned": {
                           "calibrated": False, "missed": "...", "runs": 4,
                           "calibration_wall_s": 3.0,
                           "closest": {"crimp:warp": 2.56, "crimp:weft": 2.6,
                                       "tension:warp": 5.5},
                           "loose_height_m": {"warp": 5.6e-4, "weft": 5.6e-4}}}}}
    plain, errors = bench.rows(data)
    assert errors["default"]["tension"]["combined"] == pytest.approx(0.3)
    rows, errors = bench.rows(data, pinned=True)
    assert [r[0] for r in rows] == ["fast", "default"]
    assert errors["default"]["tension"]["combined"] == pytest.approx(0.05)
    assert rows[1][4] == "15" and rows[1][3].endswith("(calibrated)")
    assert rows[0][3] == "not reached in 4 runs: closest 2.56 / 2.60 (loose height 0.56 / 0.56 mm)"
    assert "**At the reference's crimp**" in bench.section(data)
    assert "**At the reference's crimp**" not in bench.section({**data, "pinned": {}})


def load_convergence():
    return load_benchmark("convergence")


def test_convergence_levels_build_the_refined_scenes():
    """Each level changes its own parameter only, through the scene-file parser."""
    bench = load_convergence()
    data = bench.read_example()
    base = bench.base_levels(data)
    assert base == {"n_fibres": 7, "spacing_ratio": 0.5, "tension_cells": [4, 2],
                    "frame_cells": 3}
    example = bench.build_scene(bench.variant("tension", ("fibres", 7), base), data, base)
    fibres = bench.build_scene(bench.variant("tension", ("fibres", 19), base), data, base)
    for fam in ("warp", "weft"):
        a, b = getattr(example.fabric, fam), getattr(fibres.fabric, fam)
        assert b.n_fibres == 19 and a.n_fibres == 7
        # the yarn is the same yarn: tex, section and spacing unchanged
        assert b.linear_density_kg_m == a.linear_density_kg_m
        assert (b.width_m, b.height_m, b.spacing_m) == (a.width_m, a.height_m, a.spacing_m)
    assert fibres.model(check=False).n_fibres == 19 * example.model(check=False).n_fibres / 7
    # s/d 0.25 halves the bead spacing of the same fibres
    fine = bench.build_scene(bench.variant("compaction", ("sd", 0.25), base), data, base)
    assert fine.discretisation.spacing_ratio == 0.25
    m0, m1 = example.model(check=False), fine.model(check=False)
    assert m1.n_beads == pytest.approx(2 * m0.n_beads, rel=0.05)
    assert m1.diameters.max() == pytest.approx(m0.diameters.max())
    # cells: the tension coupon 6 cells long (width kept), the picture frame 6 x 6
    from fabmd.stages import coupon_stage

    cell = example.fabric.unit_cell_m
    t6 = bench.build_scene(bench.variant("tension", ("cells", 6), base), data, base)
    coupon, _ = coupon_stage(t6, "tension")
    assert (coupon.length_m, coupon.width_m) == pytest.approx((6 * cell[0], 2 * cell[1]))
    f6 = bench.build_scene(bench.variant("picture-frame", ("cells", 6), base), data, base)
    coupon, _ = coupon_stage(f6, "picture-frame")
    assert (coupon.length_m, coupon.width_m) == pytest.approx((6 * cell[0], 6 * cell[1]))
    # compaction and periodic shear run on the periodic cell: no coupon level
    assert bench.variant("compaction", ("cells", 6), base) is None
    assert bench.variant("periodic-shear", ("cells", 6), base) is None
    shear = bench.build_scene(bench.variant("periodic-shear", ("sd", 0.25), base), data, base)
    assert shear.discretisation.spacing_ratio == 0.25
    assert data == bench.read_example()  # the example's dict untouched


def test_convergence_set_reaches_the_contact_and_levels_parse():
    bench = load_convergence()
    from fabmd.cli.validate import parse_settings
    from fabmd.schema import merged

    data = merged(bench.read_example(), parse_settings(["contact.friction=0.1"]))
    base = bench.base_levels(data)
    scene = bench.build_scene(bench.variant("tension", ("sd", 0.5), base), data, base)
    assert scene.contact.friction == 0.1
    assert bench.parse_levels(["fibres=19,1", "sd"]) == {"fibres": (1, 19), "sd": (0.5, 0.25)}
    assert bench.parse_levels(None) == bench.LEVELS
    # s/d 0.125 runs when named, never by default
    assert bench.parse_levels(["sd=0.125,0.5"]) == {"sd": (0.5, 0.125)}
    assert 0.125 not in bench.parse_levels(["sd"])["sd"]
    with pytest.raises(SystemExit):
        bench.parse_levels(["fibres=3"])
    with pytest.raises(SystemExit):
        bench.parse_levels(["cells=0.125"])


def test_convergence_table_judges_the_two_finest_levels():
    bench = load_convergence()
    base = {"n_fibres": 7, "spacing_ratio": 0.5, "tension_cells": [4, 2], "frame_cells": 3}

    def run(level, values):
        v = bench.variant("picture-frame", level, base)
        return v.key, {"key": v.key, "values": values, "beads": 10, "steps": 5,
                       "wall_s": 1.0, "quasi_static": True}

    full = {"F10°": 1.0, "F20°": 2.0, "F30°": 3.0, "F40°": 4.0, "locking": 40.0}
    runs = dict([run(("fibres", 7), full),
                 run(("fibres", 19), {**full, "F40°": 4.4, "locking": 41.0}),
                 run(("sd", 0.25), {**full, "locking": 43.0})])
    rows = {r[0]: r for r in bench.convergence_rows("picture-frame", runs, base)}
    fibres = rows["fibres 7 → 19"]
    assert fibres[4].startswith("+9.1 %") and "fail" in fibres[4]  # (4.4 - 4) / 4.4
    assert fibres[5] == "+1.0° pass" and "fail" in fibres[-1]
    assert rows["sd 0.5 → 0.25"][5] == "+3.0° **fail**"
    assert rows["cells 4 → 6"][1].startswith("not run (cells 4, cells 6 not run)")
    text = bench.runs_table("picture-frame", runs, base, bench.LEVELS)
    assert "not run (not requested in this pass)" in text
    v, reason = bench.parse_not_run("picture-frame/cells=6:estimated 100 min", base)
    assert v.cells == 6 and reason == "estimated 100 min"
    runs[v.key] = {"key": v.key, "not_run": reason}
    assert "not run (estimated 100 min)" in bench.runs_table("picture-frame", runs, base,
                                                            bench.LEVELS)
    assert bench._verdict_text({"quasi_static": False, "trusted": [[1.0, 3.0]]},
                               "tension") == "no; trusted 1–3 %"


def test_convergence_reads_the_periodic_shear_like_the_frame():
    """The periodic cell's curve gives the frame's quantities (F_norm at 10-40 deg from
    the curve, the summary's locking angle), and its refinements are fibres and s/d."""
    bench = load_convergence()
    base = {"n_fibres": 7, "spacing_ratio": 0.25, "tension_cells": [4, 2], "frame_cells": 3}
    g = np.linspace(0.0, 50.0, 101)
    curve = {"shear_angle_deg": g, "normalised_force_n_m": 10.0 * g}
    values = bench.values_of("periodic-shear", {"test_summary": {"locking_angle_deg": 32.1}},
                             curve)
    assert values == pytest.approx({"F10°": 0.1, "F20°": 0.2, "F30°": 0.3, "F40°": 0.4,
                                    "locking": 32.1})
    runs = {}
    for level, f40 in ((("fibres", 7), 0.4), (("fibres", 19), 0.5), (("sd", 0.5), 0.41)):
        v = bench.variant("periodic-shear", level, base)
        runs[v.key] = {"key": v.key, "values": {**values, "F40°": f40}, "beads": 1,
                       "steps": 1, "wall_s": 1.0, "quasi_static": True}
    rows = {r[0]: r for r in bench.convergence_rows("periodic-shear", runs, base)}
    # no cells row (no coupon); the coarser pair 1 -> 7, not run, is left out
    assert set(rows) == {"fibres 7 → 19", "sd 0.5 → 0.25"}
    assert rows["fibres 7 → 19"][4].startswith("+20.0 % **fail**")  # (0.5 - 0.4) / 0.5
    assert rows["sd 0.5 → 0.25"][4].startswith("-2.5 % pass")


def test_convergence_compaction_options_booleans_datasheet_and_monotone():
    """``--set compaction.unload=false`` reaches the scene as a boolean; a datasheet
    pressure adds its thickness column; a non-monotone loading branch is said."""
    bench = load_convergence()
    settings = bench.scene_settings(["compaction.unload=false", "compaction.speed_fraction=2e-5",
                                     "yarns.warp.fibre_packing=area"])
    assert settings["compaction"] == {"unload": False, "speed_fraction": 2e-5}
    assert settings["yarns"]["warp"]["fibre_packing"] == "area"
    from fabmd.schema import merged
    from fabmd.stages import protocol_stage

    data = merged(bench.read_example("twintex_plain.toml"), bench.scene_settings(
        ["compaction.unload=false", "compaction.datasheet_pressure_pa=4.14 kPa"]))
    base = bench.base_levels(data)
    scene = bench.build_scene(bench.variant("compaction", ("fibres", 7), base), data, base)
    protocol = protocol_stage(scene, "compaction")
    assert protocol.unload is False and protocol.datasheet_pressure_pa == 4140.0
    assert bench.pressure_text("120 kPa") == "120 kPa" and bench.pressure_text(None) == ""

    bench.add_datasheet_column(data["compaction"]["datasheet_pressure_pa"])
    assert list(bench.QUANTITIES["compaction"]) == ["h1kPa", "h10kPa", "h100kPa", "h4.14kPa"]
    summary = {"test_summary": {"datasheet_pressure_pa": 4140.0, "thickness_at_pressure_m": {
        "1000": None, "10000": 1.2e-3, "100000": 1.1e-3, "4140": 1.25e-3}}}
    values = bench.values_of("compaction", summary, {})
    assert values == pytest.approx({"h1kPa": None, "h10kPa": 1.2, "h100kPa": 1.1,
                                    "h4.14kPa": 1.25})
    v = bench.variant("compaction", ("fibres", 7), base)
    runs = {v.key: {"key": v.key, "values": values, "beads": 10, "steps": 5, "wall_s": 1.0,
                    "quasi_static": True, "thickness_monotone": False}}
    text = bench.runs_table("compaction", runs, base, {"fibres": (7,)})
    assert "h 4.14 kPa (datasheet) [mm]" in text and "yes; thickness not monotone" in text
    assert "| 1.25 |" in text


def test_convergence_json_name_fits_the_file_system():
    """Many ``--set`` made a JSON name longer than 255 bytes (OSError: File name too long);
    a long name is cut and keeps a digest of the settings, short names are unchanged."""
    bench = load_convergence()
    assert bench.data_path_for("").name == "convergence.json"
    assert bench.data_path_for("contact.friction=0.1").name == \
        "convergence-contact.friction_0.1.json"
    long_a = " ".join(f"compaction.key{i}=value{i}" for i in range(20))
    long_b = long_a + " picture_frame.max_shear_angle_deg=50"
    a, b = bench.data_path_for(long_a), bench.data_path_for(long_b)
    assert len(a.name) <= 255 and len(b.name) <= 255 and a.name.endswith(".json")
    assert a != b and a == bench.data_path_for(long_a)
    assert not a.exists() or a.is_file()  # stat works on the name


def test_interval_compare_reads_each_interval_against_the_last_run(tmp_path, capsys):
    """Two synthetic curves: the faster one 10 % above the reference from 10° on and with
    an inertia-share column; the table gives each interval's mean and difference."""
    import numpy as np

    ic = load_benchmark("interval_compare")
    angle = np.linspace(0.0, 20.0, 81)
    slow = 1e3 * (0.01 + 0.001 * angle)
    fast = np.where(angle >= 10.0, 1.1 * slow, slow)
    paths = []
    for name, force, extra in (("fast", fast, True), ("slow", slow, False)):
        header = "shear_angle_deg,normalised_force_n_m" + (",interval_inertia_share"
                                                           if extra else "")
        lines = [f"{a},{f}" + (",0.2" if extra else "") for a, f in zip(angle, force,
                                                                        strict=True)]
        path = tmp_path / f"{name}.csv"
        path.write_text("\n".join([header, *lines]) + "\n")
        paths.append(path)
    table = ic.interval_table([(p.stem, ic.read_curve(p)) for p in paths], 5.0, 20.0)
    assert [(r["from"], r["to"]) for r in table] == [(0, 5), (5, 10), (10, 15), (15, 20)]
    mean_slow = np.mean(slow[(angle >= 10) & (angle < 15)]) / 1e3
    assert table[2]["runs"][1]["force_n_mm"] == pytest.approx(mean_slow)
    assert table[2]["runs"][0]["difference"] == pytest.approx(0.1)
    assert table[0]["runs"][0]["difference"] == pytest.approx(0.0)
    assert table[2]["runs"][0]["i"] == pytest.approx(0.2) and table[2]["runs"][1]["i"] is None
    ic.main([f"fast={paths[0]}", f"slow={paths[1]}"])
    assert "| 10–15° | " in capsys.readouterr().out


def test_a_crossing_turned_in_place_has_the_same_friction_lever_at_every_spacing():
    """Register-averaged friction torque / normal force of one crossing: the same lever at
    s/d 0.5 and 0.25 (0.068 d at δ = 0.02 d), larger at a deeper overlap (wider patch)."""
    cl = load_benchmark("crossing_lever")
    coarse, fine = cl.crossing_lever(0.5, 0.02, 16), cl.crossing_lever(0.25, 0.02, 16)
    assert fine == pytest.approx(coarse, rel=0.01)
    assert 0.05 < fine < 0.09
    assert cl.crossing_lever(0.25, 0.05, 16) > 1.4 * fine


@pytest.mark.lammps
def test_crossing_sample_reads_load_slip_friction_and_tension():
    """One sliding crossing pair (types 1 and 2, overlap δ, slip speed v, at the Coulomb
    limit) and one stretched bond: N = k_n·δ, P = μ·N·v, slip W/N = v, P/W = μ, tension =
    2K·Δ; a same-type pair in contact is not a crossing."""
    from fabmd.engine.library import new_instance

    cl = load_benchmark("crossing_load")
    d, delta, v, kn, mu, k_bond, stretch = 1e-3, 2e-5, 0.01, 1e4, 0.3, 50.0, 1e-5
    lmp = new_instance()
    lmp.commands_list([
        "units si", "atom_style hybrid sphere bond", "boundary f f f", "comm_modify vel yes",
        "region box block -0.01 0.01 -0.01 0.01 -0.01 0.01",
        "create_box 2 box bond/types 1 extra/bond/per/atom 1 extra/special/per/atom 2",
        "create_atoms 1 single 0 0 0", f"create_atoms 2 single 0 0 {d - delta}",
        "create_atoms 1 single 0.005 0 0", f"create_atoms 1 single 0.005 0 {d - delta}",
        "create_atoms 1 single -0.005 0 0", f"create_atoms 1 single -0.005 0 {d + stretch}",
        f"set group all diameter {d}", "set group all density 2500",
        "bond_style harmonic", f"bond_coeff 1 {k_bond} {d}", "create_bonds single/bond 1 5 6",
        "special_bonds lj 0 1 1",
        "pair_style granular", f"pair_coeff * * hooke {kn} 0.0 tangential linear_history "
        f"{kn} 0.0 {mu} damping mass_velocity", "neighbor 0.0002 bin",
        "group moving id 2 4", "fix slide moving move linear 0.01 0 0",
        "timestep 1e-6", "run 1000"])  # slides 10 µm: past the spring, at μ·N
    lmp.commands_list([*cl.SAMPLING_COMMANDS, "run 1"])
    out = cl.crossing_sample(lmp)
    ids = np.array(lmp.numpy.extract_atom("id"), copy=True)
    x = np.array(lmp.numpy.extract_atom("x"), copy=True)
    lmp.close()
    sep = x[ids == 2][0] - x[ids == 1][0]  # the slider moved on: the normal tilts a little
    normal = sep / np.linalg.norm(sep)
    slip = v * np.sqrt(1 - normal[0] ** 2)
    assert np.linalg.norm(sep) < d - 0.99 * delta
    assert out["pairs"] == 1
    assert out["normal_n"] == pytest.approx(kn * (d - np.linalg.norm(sep)), rel=1e-6)
    assert out["friction_power_w"] == pytest.approx(mu * out["normal_n"] * slip, rel=1e-6)
    assert out["slip_load_w"] / out["normal_n"] == pytest.approx(slip, rel=1e-9)
    assert out["bond_tension_n"] == pytest.approx(2 * k_bond * stretch, rel=1e-6)


@pytest.mark.lammps
def test_a_bead_chain_pulled_over_a_crossing_chain_follows_the_capstan_equation():
    """Fibre over a fixed crossing fibre (both bead chains, s/d 0.5, θ = π/2, μ = 0.3):
    T_out/T_in averaged over the sliding is exp(μθ) within 8 % of μθ (measured +3.2 %
    over a 3 d pull, RESULTS "Crossing friction"); the ripple about it is wide."""
    import math

    cap = load_benchmark("crossing_capstan")
    mean, low, high = cap.ratio(0.5, math.pi / 2, 0.0, pull_d=2.0)
    exact = math.exp(cap.MU * math.pi / 2)
    assert abs(mean - exact) < 0.08 * (exact - 1)
    assert low < exact < high and high - low > 0.2 * (exact - 1)


def test_yarn_sections_read_the_width_of_affinely_sheared_yarns_as_w_cos_gamma():
    """``benchmarks/yarn_sections.py`` on two synthetic yarns of 7 straight fibres along x,
    sheared affinely (the crossing direction y turns by γ, lengths along it kept): their
    width across reads w·cos γ, their height the fibres' z spread; a yarn cut by the
    interior's edge is left out."""
    bench = load_benchmark("yarn_sections")
    spacing, n_beads, w = 2.5e-3, 81, 1.2e-3
    x = np.linspace(0.0, 10e-3, n_beads)
    rows, fibre, yarn_of_fibre = [], [], []
    for yarn, y0 in enumerate((3.75e-3, 6.25e-3)):
        for k, dy in enumerate(np.linspace(-w / 2, w / 2, 7)):
            z = 0.1e-3 * (k % 2)  # two rows: a height of 0.1 mm
            rows.append(np.column_stack([x, np.full(n_beads, y0 + dy), np.full(n_beads, z)]))
            fibre += [len(yarn_of_fibre) + 1] * n_beads
            yarn_of_fibre.append(yarn + 1)
    p0 = np.vstack(rows)
    data = {"fibre": np.array(fibre), "fibre_yarn": np.array(yarn_of_fibre),
            "free_side_m": 4 * spacing}
    for gamma in (0.0, 20.0, 40.0):
        g = np.radians(gamma)
        sheared = p0.copy()
        sheared[:, 0] = p0[:, 0] + p0[:, 1] * np.sin(g)
        sheared[:, 1] = p0[:, 1] * np.cos(g)
        data["pos"] = np.stack([p0, sheared])
        inside = bench.interior(data)
        yarns = bench.whole_yarns(data, inside)
        assert yarns == [1, 2]
        width, height = bench.sections(sheared, data, inside, yarns)
        assert width == pytest.approx(w * np.cos(g), rel=1e-6)
        assert height == pytest.approx(0.1e-3, rel=1e-6)
    # an interior that cuts the second yarn's fibres leaves it out
    data["free_side_m"] = 2 * (6.25e-3 - 5e-3) / bench.CENTRAL + 1e-9
    assert bench.whole_yarns(data, bench.interior(data)) != [1, 2]


def test_crimp_sections_read_a_single_fibre_yarn_as_one_diameter_across_the_boundary():
    """``benchmarks/crimp_sections.py`` on single-fibre yarns: every section is one bead
    diameter wide and high, also where a yarn's beads sit a cell length apart (the
    periodic image: unwrapped), and the span is the beads' z extent plus a diameter."""
    from .fabrics import plain_weave_cell

    bench = load_benchmark("crimp_sections")
    cell = plain_weave_cell()
    d = float(cell.diameters.mean())
    s = bench.sections(cell)
    assert s["width_m"] == pytest.approx(d) and s["height_m"] == pytest.approx(d)
    z = cell.positions[:, 2]
    assert s["span_m"] == pytest.approx(np.ptp(z) + d)
    assert s["fibres_per_yarn"] == 1
    # half of the first warp yarn's beads moved by one cell length across it (y)
    first = np.nonzero(cell.yarn_ids == 1)[0][::2]
    assert cell.yarns[0].family == "warp"
    cell.positions[first, 1] += (cell.box_hi - cell.box_lo)[1]
    assert bench.sections(cell)["width_m"] == pytest.approx(d)


def test_periodic_sections_read_affine_yarns_as_w_cos_gamma_across_images():
    """``benchmarks/periodic_sections.py`` on a synthetic sheared cell: two warp yarns of 5
    straight fibres along x, sheared affinely with the box (b = (ly0·sin γ, ly0·cos γ)),
    read w·cos γ wide, also where one fibre sits a periodic image away (i·a + j·b); a yarn
    that kept its width reads w (the ratio the script prints is then 1/cos γ)."""
    bench = load_benchmark("periodic_sections")
    lx, ly0, w, n = 5e-3, 5e-3, 1.2e-3, 41
    x = np.linspace(0.0, lx, n, endpoint=False)
    fibre, yarn_of_fibre, y0s, z = [], [], [], []
    for yarn, yc in enumerate((1.25e-3, 3.75e-3)):
        for k, dy in enumerate(np.linspace(-w / 2, w / 2, 5)):
            y0s.append(yc + dy)
            z.append(0.1e-3 * (k % 2))
            fibre += [len(yarn_of_fibre) + 1] * n
            yarn_of_fibre.append(yarn + 1)
    fibre, yarn_of_fibre = np.array(fibre), np.array(yarn_of_fibre)
    for gamma in (0.0, 25.0):
        g = np.radians(gamma)
        ly, xy = ly0 * np.cos(g), ly0 * np.sin(g)
        affine, kept = [], []
        for y0, zz in zip(y0s, z, strict=True):
            affine.append(np.column_stack([x + y0 * np.sin(g), np.full(n, y0 * np.cos(g)),
                                           np.full(n, zz)]))
            yc = 1.25e-3 if y0 < 2.5e-3 else 3.75e-3
            kept.append(np.column_stack([x, np.full(n, yc * np.cos(g) + (y0 - yc)),
                                         np.full(n, zz)]))
        pos = np.vstack(affine)
        pos[fibre == 3, :2] += np.array([lx, 0.0]) - np.array([xy, ly])  # an image away
        width, height = bench.cell_sections(pos, lx, ly, xy, fibre, yarn_of_fibre)
        assert width == pytest.approx(w * np.cos(g), rel=1e-6)
        assert height == pytest.approx(0.1e-3, rel=1e-6)
        width, _ = bench.cell_sections(np.vstack(kept), lx, ly, xy, fibre, yarn_of_fibre)
        assert width == pytest.approx(w, rel=1e-6)
        # fibre by fibre (--fibres): offsets across the yarn follow cos(gamma) when affine
        # (also for the fibre an image away), stay when the width is kept
        offsets = bench.fibre_offsets(pos, lx, ly, xy, fibre, yarn_of_fibre)
        start = np.linspace(-w / 2, w / 2, 5)
        for o in offsets:
            assert o == pytest.approx(start * np.cos(g), abs=1e-9)
        for o in bench.fibre_offsets(np.vstack(kept), lx, ly, xy, fibre, yarn_of_fibre):
            assert o == pytest.approx(start, abs=1e-9)


def test_periodic_energy_splits_each_interval_of_the_work(tmp_path, capsys):
    """``benchmarks/periodic_energy.py`` on a synthetic periodic-shear curve: the work of
    each 5° goes into the bonds (quadratic in γ), the contacts (linear), the drag (none
    sampled at one point: NaN is skipped) and a rest that closes the sum; a run read
    against itself differs by 0."""
    bench = load_benchmark("periodic_energy")
    g = np.linspace(0.0, 20.0, 81)
    bonds, contacts, drag = 1e-6 * g**2, 2e-6 * g, 0.5e-6 * g
    work = bonds + contacts + drag + 3e-6 * g  # 3 µJ/deg of friction
    cols = {"time_s": g, "shear_angle_deg": g, "external_work_j": work,
            "strain_energy_j": bonds, "contact_energy_j": contacts,
            "damping_dissipation_j": drag, "kinetic_energy_j": np.zeros_like(g)}
    cols["contact_energy_j"][3] = np.nan
    run = tmp_path / "ps" / "periodic_shear"
    run.mkdir(parents=True)
    with (run / "curve.csv").open("w") as f:
        f.write(",".join(cols) + "\n")
        for i in range(len(g)):
            f.write(",".join("nan" if np.isnan(c[i]) else repr(float(c[i]))
                             for c in cols.values()) + "\n")
    split = bench.interval_split(bench.read_curve(tmp_path / "ps"))
    assert [r["from"] for r in split] == [0, 5, 10, 15]
    row = split[2]  # 10-15 deg
    assert row["bonds"] == pytest.approx(1e-6 * (15**2 - 10**2))
    assert row["contacts"] == pytest.approx(10e-6)
    assert row["rest"] == pytest.approx(15e-6)
    bench.main([str(tmp_path / "ps")])
    out = capsys.readouterr().out
    assert "| 10–15 | " in out and out.count("+0.0 %") == 4
    # a run without the contacts' energy (standalone): NaN, and the rest holds it
    del cols["contact_energy_j"]
    (run / "curve.csv").write_text(",".join(cols) + "\n" + "\n".join(
        ",".join(repr(float(c[i])) for c in cols.values()) for i in range(len(g))) + "\n")
    row = bench.interval_split(bench.read_curve(tmp_path / "ps"))[2]
    assert np.isnan(row["contacts"]) and row["rest"] == pytest.approx(25e-6)


def test_adaptive_verdict_says_when_the_whole_curve_is_rejected():
    """A whole-run measure that failed (fabmd: "do not use the curve") is not shown as a
    trusted range: the benchmark's table hid it once (stop 31)."""
    bench = load_benchmark("adaptive")
    assert bench.verdict_text({"ok": True}) == "yes"
    assert bench.verdict_text({"ok": False, "trusted": [[2.5, 6.0]], "partly": True}) == \
        "no (trusted 2.5–6)"
    assert bench.verdict_text({"ok": False, "trusted": [[2.75, 6.0]], "partly": False}) == \
        "no (whole curve rejected; intervals 2.75–6)"


def test_a_scripts_write_keeps_the_reading_written_by_hand(tmp_path, monkeypatch):
    """``--write`` replaces only the script's generated part of its RESULTS section: the
    reading written by hand around it stays, a section from before the marks gets the
    measurement added at its end, a missing one is created."""
    results = load_benchmark("_results")
    monkeypatch.setattr(results, "RESULTS", tmp_path / "RESULTS.md")
    results.update_section("Ranks", "| table | one |", "python benchmarks/ranks.py --write")
    text = results.RESULTS.read_text()
    assert "## Ranks" in text and "| table | one |" in text
    # a reading written by hand under the table, then a rerun
    results.RESULTS.write_text(text.replace("<!-- /Ranks -->",
                                            "The reading, by hand.\n<!-- /Ranks -->"))
    results.update_section("Ranks", "| table | two |", "python benchmarks/ranks.py --write")
    text = results.RESULTS.read_text()
    assert "| table | two |" in text and "| table | one |" not in text
    assert "The reading, by hand." in text and text.count("## Ranks") == 1
    # a section written before the marks: its text stays, the measurement comes after it
    results.RESULTS.write_text("# r\n\n<!-- Old -->\n## Old\n\nHand-made table.\n<!-- /Old -->\n"
                               "\n<!-- Next -->\n## Next\n<!-- /Next -->\n")
    results.update_section("Old", "| new |", "cmd")
    text = results.RESULTS.read_text()
    assert text.index("Hand-made table.") < text.index("| new |") < text.index("<!-- /Old -->")
    assert text.index("<!-- /Old -->") < text.index("<!-- Next -->")
    results.update_section("Old", "| newer |", "cmd")
    text = results.RESULTS.read_text()
    assert "Hand-made table." in text and "| newer |" in text and "| new |" not in text
