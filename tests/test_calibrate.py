"""``fabmd calibrate``: targets from the scene, the search (monotone, turning, flat,
jumping responses), the scene file written back, and tiny LAMMPS runs (seconds)."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from fabmd.errors import CalibrationNotReached, InputError
from fabmd.protocols.calibrate_search import Knob, next_strain

TINY = """title = "tiny plain weave for calibration tests"

[fabric]
architecture = "plain"
tiling = [1, 1]
periodic = true
clearance_m = "0.1 mm"

[materials.soft]
modulus_pa = "1 GPa"
density_kg_m3 = "2540 kg/m3"

[yarns.warp]
material = "soft"
linear_density_tex = "200 tex"
n_fibres = 1
width_m = "0.5 mm"
height_m = "0.5 mm"
count_per_m = "5 ends/cm"

[yarns.weft]
material = "soft"
linear_density_tex = "200 tex"
n_fibres = 1
width_m = "0.5 mm"
height_m = "0.5 mm"
count_per_m = "5 picks/cm"

[discretisation]
spacing_ratio = 0.5

[crimp]
expansion = { warp = -0.01, weft = -0.01 }  # a first guess
"""


def scene_file(tmp_path, extra: str = "", text: str = TINY):
    path = tmp_path / "tiny.toml"
    path.write_text(text + extra)
    return path


def cli(capsys, *argv):
    from fabmd.cli import main

    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def calibrated(tmp_path, capsys, extra: str):
    """``fabmd calibrate`` on TINY + ``extra``, which must reach its targets: (out folder,
    terminal text, calibration.json)."""
    out = tmp_path / "cal"
    code, text, err = cli(capsys, "calibrate", str(scene_file(tmp_path, extra)), "--out",
                          str(out), "--np", "1", "--quiet")
    assert code == 0, err
    return out, text, json.loads((out / "calibration.json").read_text())


# ---- the search, on closed-form responses (no LAMMPS) ----------------------------------
def drive(knob: Knob, response, runs: int = 12) -> tuple[int, str]:
    """Run the search on ``response(strain)``; (runs used, why it stopped or "")."""
    for k in range(1, runs + 1):
        q = response(knob.value)
        knob.samples.append((knob.value, q, ()))
        if knob.converged(q):
            return k, ""
        new, why = next_strain(knob)
        if new is None:
            return k, why
        knob.value = new
    return runs, "budget"


def thickness_knob(target, start=-0.01, bounds=(-0.06, 0.4)) -> Knob:
    return Knob("thickness", "thickness", ("warp", "weft"), target, 0.01 * target, +1,
                bounds, start)


def test_search_reaches_a_monotone_target_in_few_runs():
    knob = thickness_knob(1.0e-3)
    runs, why = drive(knob, lambda s: 1.1e-3 + 4e-3 * s)  # thinner with every shrink
    assert why == "" and runs <= 4
    assert knob.samples[-1][1] == pytest.approx(1.0e-3, rel=0.01)


def test_search_finds_the_near_branch_of_a_response_that_turns():
    # thinner with shrink down to -0.05, thicker beyond (yarns riding over each other)
    def turn(s):
        return 1.0e-3 + 20e-3 * (s + 0.05) ** 2

    knob = thickness_knob(1.01e-3)
    runs, why = drive(knob, turn)
    assert why == "", why
    assert knob.samples[-1][0] > -0.05  # on the branch it started on


def test_search_says_where_the_response_turns_when_the_target_is_below_its_bottom():
    def turn(s):
        return 1.0e-3 + 20e-3 * (s + 0.03) ** 2

    knob = thickness_knob(0.95e-3)
    runs, why = drive(knob, turn)
    assert runs < 12
    assert "cannot reach 0.95 mm" in why and "lowest value" in why
    assert "thicker again" in why
    # the turning point and its value, with numbers
    best = min(knob.samples, key=lambda x: x[1])
    assert best[0] == pytest.approx(-0.03, abs=0.006)
    assert f"{1e3 * best[1]:.4g} mm" in why


def test_a_flat_bottom_is_named_the_lowest_value():
    """The twill example's free thickness: the loose thickness over a range of shrinks,
    thicker with more shrink and with expansion (measured: 0.5327 mm from -0.0081 to
    -0.003, 0.5434 mm at -0.01, 0.5769 mm at +0.0097)."""
    knob = thickness_knob(0.5e-3)
    runs, why = drive(knob, lambda s: 0.5327e-3 + 0.5e-3 * max(0.0, -0.009 - s, s - 0.002))
    assert "cannot reach 0.5 mm: the lowest value the strain gives is 0.5327 mm" in why
    assert "more shrink makes the fabric thicker again" in why


def test_search_turns_round_when_shrink_makes_the_fabric_thicker():
    """The issue's commingled fabric: one-row yarns got thicker with every shrink."""
    knob = thickness_knob(0.97e-3)
    runs, why = drive(knob, lambda s: 1.0e-3 - 2e-3 * s)
    assert why == "" and knob.samples[-1][0] > 0  # found on the expansion side
    knob = thickness_knob(0.97e-3, bounds=(-0.06, 0.0))
    runs, why = drive(knob, lambda s: 1.0e-3 - 2e-3 * s)
    assert "not reached at the expansion limit +0.0000" in why
    assert "closest 1 mm at +0.0000" in why and "strains -0." in why


def test_search_crosses_a_flat_slack_range_the_way_physics_says():
    # slack yarns carry nothing until the shrink takes up 3 %, then 500 N per unit strain
    knob = Knob("tension:weft", "tension", ("weft",), 5.0, 0.25, -1, (-0.4, 0.4), -0.01,
                first_step=0.01)
    runs, why = drive(knob, lambda s: 500.0 * max(0.0, -0.03 - s))
    assert why == "", why
    assert knob.samples[-1][0] == pytest.approx(-0.04, abs=0.001)


def test_search_reports_a_jump_across_the_target():
    knob = thickness_knob(1.05e-3)
    runs, why = drive(knob, lambda s: 1.0e-3 if s < -0.02 else 1.1e-3, runs=20)
    assert "jumps from" in why and "no strain in between" in why


def test_a_jump_beside_a_bracket_is_passed_over():
    """The example's cell drawn 0.621 mm (s/d 0.5) against its shrink: it thins steadily,
    then jumps thicker again past -5.4 % (measured). The target 0.70 mm lies in the jump
    and, further back, between -4.43 and -5.08 %: the search must go there, not stop at
    the jump beside its best sample."""
    measured = [(-0.0612, 0.8618e-3), (-0.0559, 0.8626e-3), (-0.0540, 0.6404e-3),
                (-0.0508, 0.6279e-3), (-0.0443, 0.8095e-3)]

    def cell(s):  # piecewise linear through the measured points, the jump at -5.5 %
        if s < -0.055:
            return 0.8626e-3
        xs, ys = zip(*measured[2:], strict=True)
        return float(np.interp(s, xs, ys))

    knob = thickness_knob(0.70e-3, start=-0.0443)
    for s in (-0.0443, -0.0612, -0.0508, -0.0540, -0.0559):  # the measured run's order
        knob.samples.append((s, cell(s), ()))
    knob.value = -0.0559
    new, why = next_strain(knob)  # the bracket where the cell thins with the shrink
    assert why == "" and -0.0508 < new < -0.0443, (new, why)
    runs, why = drive(knob, cell, runs=12)
    assert why == "", why
    assert -0.0508 < knob.samples[-1][0] < -0.0443
    assert cell(knob.samples[-1][0]) == pytest.approx(0.70e-3, rel=0.01)


def test_a_steep_bracket_is_bisected_not_called_a_jump():
    """The same cell at s/d 0.25 thins 0.774 -> 0.619 mm between -4.43 and -4.59 %
    (measured; 0.697 mm at -4.53 %): a bracket 0.16 % wide that holds the target 0.70 mm,
    reached by halving it, not refused as a jump (it was, with 2e-3 as the jump width)."""
    measured = [(-0.0459, 0.6192e-3), (-0.0453, 0.697e-3), (-0.0443, 0.7744e-3)]
    xs, ys = zip(*measured, strict=True)
    knob = thickness_knob(0.70e-3, start=-0.0443)
    for s in (-0.0443, -0.0459):
        knob.samples.append((s, float(np.interp(s, xs, ys)), ()))
    knob.value = -0.0459
    runs, why = drive(knob, lambda s: float(np.interp(s, xs, ys)), runs=8)
    assert why == "", why
    assert knob.samples[-1][1] == pytest.approx(0.70e-3, rel=0.01)


def test_a_stiff_tension_is_refined_not_called_a_jump():
    """A glass yarn's tension follows its fibres' strain (E·A ≈ 33 kN per Twintex yarn):
    18.7 N (1 cN/tex) sits within 6e-4 of strain past the slack point, a bracket far
    narrower than the thickness's 2e-3 — it must be refined to the target, not refused."""
    knob = Knob("tension:weft", "tension", ("weft",), 18.7, 0.05 * 18.7, -1, (-0.4, 0.4),
                0.0, first_step=0.01)
    runs, why = drive(knob, lambda s: 33e3 * max(0.0, -0.012 - s), runs=16)
    assert why == "", why
    assert knob.samples[-1][1] == pytest.approx(18.7, rel=0.05)


# ---- targets from the scene, checked before LAMMPS ------------------------------------
def test_targets_come_from_the_table_and_the_datasheet(tmp_path):
    from fabmd import schema
    from fabmd.protocols.calibrate import CrimpTargets, targets_from_scene
    from fabmd.scenefile import load_scene

    assert schema.unit_of(CrimpTargets, "thickness_m").kind == "length"
    assert schema.unit_of(CrimpTargets, "at_pressure_pa").kind == "pressure"
    path = scene_file(tmp_path, '\n[calibrate]\nthickness_m = "0.9 mm"\n'
                                'at_pressure_pa = "5 kPa"\ncrimp_pct = { weft = 1.5 }\n')
    targets, notes = targets_from_scene(load_scene(path), {"crimp_pct": {"warp": 2.0}})
    assert targets.thickness_m == pytest.approx(0.9e-3) and targets.at_pressure_pa == 5e3
    assert targets.crimp_pct == {"weft": 1.5, "warp": 2.0} and notes == []
    # the datasheet's thickness at its pressure, where the table gives none
    sheet = TINY.replace("clearance_m", 'thickness = "0.95 mm at 4.14 kPa"\nclearance_m')
    targets, notes = targets_from_scene(load_scene(scene_file(tmp_path, text=sheet)))
    assert targets.thickness_m == pytest.approx(0.95e-3)
    assert targets.at_pressure_pa == pytest.approx(4140)
    assert "datasheet" in notes[0] and "4.14 kPa" in notes[0]


@pytest.mark.parametrize("table,words", [
    ('thickness_m = "-1 mm"', r"calibrate.thickness_m must be > 0"),
    ('thikness_m = "1 mm"', r"\[calibrate\] has no key 'thikness_m'"),
    ('at_pressure_pa = "5 kPa"', r"at_pressure_pa = 5000 Pa is given without"),
    ('thickness_m = "1 mm"\nthickness_tolerance = 0.9', r"thickness_tolerance must be"),
    ('crimp_pct = { weft = -1 }', r"calibrate.crimp_pct.weft must be >= 0"),
    ('target_tension = "-2 N"', r"calibrate.target_tension must be > 0"),
    ('max_runs = 8\n', r"nothing to calibrate"),
    ('thickness_m = "1 mm"\nstrain_range = [0.1, -0.1]', r"strain_range must be"),
    ('crimp_pct = { weft = 1.0 }\ncrimp_by = "height"',
     r"crimp_by must be one of expansion, loose_height, got 'height'"),
    ('target_tension = "1 N"\ncrimp_by = "loose_height"', r"give calibrate.crimp_pct too"),
])
def test_bad_calibrate_table_fails_before_lammps(tmp_path, capsys, table, words):
    path = scene_file(tmp_path, f"\n[calibrate]\n{table}\n")
    code, out, err = cli(capsys, "calibrate", str(path), "--out", str(tmp_path / "o"))
    assert code == 2 and err.startswith("fabmd: error: ") and err.count("\n") == 1, err
    assert "tiny.toml" in err
    import re
    assert re.search(words, err), err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("extra,words", [
    ('\n[calibrate]\ncrimp_pct = { weft = 1.0 }\ntarget_tension = { weft = "1 N" }\n'
     'thickness_families = ["warp"]\nthickness_m = "1 mm"\n',
     'serves one target (the other follows from it); give one of them, or reach the crimp '
     'by the loose height (calibrate.crimp_by = "loose_height")'),
    ('\n[calibrate]\nthickness_m = "5 mm"\n', "not below the loose fabric"),
    ('\n[calibrate]\ncrimp_pct = { binder = 1.0 }\n', "the fabric has"),
])
def test_impossible_targets_fail_before_lammps(tmp_path, capsys, extra, words):
    path = scene_file(tmp_path, extra)
    code, out, err = cli(capsys, "calibrate", str(path), "--out", str(tmp_path / "o"))
    assert code == 2 and words in err, err
    assert not (tmp_path / "o").exists()


def test_crimp_target_tension_is_refused_for_calibration(tmp_path, capsys):
    text = TINY.replace("# a first guess", '\ntarget_tension = "1 N"')
    path = scene_file(tmp_path, '\n[calibrate]\nthickness_m = "1 mm"\n', text=text)
    code, out, err = cli(capsys, "calibrate", str(path), "--out", str(tmp_path / "o"))
    assert code == 2 and "[calibrate] target_tension instead" in err


def test_existing_out_is_refused_without_overwrite(tmp_path, capsys):
    path = scene_file(tmp_path, '\n[calibrate]\nthickness_m = "1 mm"\n')
    (tmp_path / "o").mkdir()
    (tmp_path / "o" / "x").write_text("mine")
    code, out, err = cli(capsys, "calibrate", str(path), "--out", str(tmp_path / "o"))
    assert code == 2 and "--overwrite" in err
    assert (tmp_path / "o" / "x").read_text() == "mine"


def test_a_scene_with_a_calibrate_table_still_crimps_and_builds():
    from fabmd.preflight import check_scene
    from fabmd.scenefile import parse_scene

    check_scene(parse_scene(tomllib.loads(TINY + '\n[calibrate]\nthickness_m = "1 mm"\n')))
    with pytest.raises(InputError, match="calibrate.thickness_m must be > 0"):
        check_scene(parse_scene(tomllib.loads(TINY + "\n[calibrate]\nthickness_m = -1\n")))


# ---- the scene file written back --------------------------------------------------------
def test_calibrated_file_changes_the_expansion_and_nothing_else():
    from fabmd.calibration import with_expansion

    new = with_expansion(TINY, {"warp": -0.0412, "weft": -0.05}, header="# top\n")
    assert new.startswith("# top\n") and "# a first guess" not in new
    data, old = tomllib.loads(new), tomllib.loads(TINY)
    assert data["crimp"]["expansion"] == {"warp": -0.0412, "weft": -0.05}
    data["crimp"]["expansion"] = old["crimp"]["expansion"]
    assert data == old
    # only that line differs
    assert [a for a, b in zip(TINY.splitlines(), new.splitlines()[1:], strict=True)
            if a != b] == ["expansion = { warp = -0.01, weft = -0.01 }  # a first guess"]
    # no [crimp] table: one is added; a [crimp.expansion] table is rewritten in place
    bare = TINY[:TINY.index("[crimp]")]
    added = tomllib.loads(with_expansion(bare, {"warp": -0.03}))
    assert added["crimp"] == {"expansion": {"warp": -0.03}}
    sub = bare + "[crimp]\nramp_transits = 30.0\n\n[crimp.expansion]\nwarp = -0.1\n" \
                 "weft = -0.1\n\n[tension]\nmax_elongation_pct = 2.0\n"
    got = tomllib.loads(with_expansion(sub, {"weft": -0.02}))
    assert got["crimp"] == {"ramp_transits": 30.0, "expansion": {"warp": -0.1, "weft": -0.02}}
    assert got["tension"] == {"max_elongation_pct": 2.0}
    with pytest.raises(InputError, match="not a \\[crimp\\] table"):
        with_expansion('crimp.expansion.warp = -0.1\n' + bare, {"warp": -0.02})


def test_calibrated_file_gets_the_loose_heights_and_nothing_else():
    from fabmd.calibration import with_yarn_heights

    new = with_yarn_heights(TINY, {"warp": 0.4123e-3})
    data, old = tomllib.loads(new), tomllib.loads(TINY)
    assert data["yarns"]["warp"]["height_m"] == "0.4123 mm"
    data["yarns"]["warp"]["height_m"] = old["yarns"]["warp"]["height_m"]
    assert data == old
    assert [a for a, b in zip(TINY.splitlines(), new.splitlines(), strict=True) if a != b] \
        == ['height_m = "0.5 mm"']  # in place
    # a section sized by its packing: the packing goes, the height comes
    packed = TINY.replace('height_m = "0.5 mm"\ncount_per_m = "5 ends/cm"',
                          'fibre_volume_fraction = 0.5\ncount_per_m = "5 ends/cm"')
    got = tomllib.loads(with_yarn_heights(packed, {"warp": 0.3e-3, "weft": 0.31e-3}))
    assert "fibre_volume_fraction" not in got["yarns"]["warp"]
    assert (got["yarns"]["warp"]["height_m"], got["yarns"]["weft"]["height_m"]) == (
        "0.3 mm", "0.31 mm")
    # an override table after the family's table is left alone
    over = TINY.replace("[yarns.weft]", '[[yarns.warp.overrides]]\nyarns = [0]\n'
                                        'height_m = "0.45 mm"\n\n[yarns.weft]')
    got = tomllib.loads(with_yarn_heights(over, {"warp": 0.3e-3}))
    assert got["yarns"]["warp"]["overrides"] == [{"yarns": [0], "height_m": "0.45 mm"}]
    inline = TINY.replace('[yarns.weft]\n', 'yarns.weft.n_fibres = 1\n[yarns.weftx]\n')
    with pytest.raises(InputError, match="no \\[yarns.weft\\] table of its own"):
        with_yarn_heights(inline, {"weft": 0.3e-3})


def test_new_loose_heights_give_the_law_the_new_fibre():
    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import load_scene

    scene = load_scene(example_scene("plain_weave.toml"))
    lower = scene.with_yarn_heights({"warp": 0.55e-3, "weft": 0.55e-3})
    assert (lower.fabric.warp.height_m, lower.fabric.weft.height_m) == (0.55e-3, 0.55e-3)
    assert lower.fabric.warp.width_m == scene.fabric.warp.width_m
    old, new = scene.contact.within_family_law, lower.contact.within_family_law
    # the inscribed fibres of a lower section are thinner; the yarn's law is the same
    assert new.diameter_m < 0.9 * old.diameter_m and new.law == old.law
    assert scene.with_yarn_heights({}).contact == scene.contact
    with pytest.raises(InputError, match="no families \\['binder'\\]"):
        scene.with_yarn_heights({"binder": 1e-3})


# ---- tiny LAMMPS runs -------------------------------------------------------------------
@pytest.mark.lammps
@pytest.mark.slow  # ~15-25 s on the shared machine: the final crimp and fabmd crimp draw figures
def test_cli_reaches_a_free_thickness_and_crimp_reproduces_it(tmp_path, capsys):
    path = scene_file(tmp_path, '\n[calibrate]\nthickness_m = "1.0 mm"\n')
    given = path.read_text()
    out = tmp_path / "cal"
    code, text, err = cli(capsys, "calibrate", str(path), "--out", str(out), "--np", "1",
                          "--quiet")
    assert code == 0, err
    assert "thickness        target 1.0000 mm" in text and ": reached" in text
    assert "run                   strains" in text  # the table, one line per run
    cal = json.loads((out / "calibration.json").read_text())
    assert cal["reached"] and len(cal["runs"]) <= 4
    assert cal["achieved"]["thickness"] == pytest.approx(1.0e-3, rel=0.02)
    for run in cal["runs"]:
        assert run["wall_s"] > 0 and set(run["achieved"]) == {"thickness"}
    assert path.read_text() == given  # the input is not touched
    scene = tomllib.loads((out / "calibrated.toml").read_text())
    assert scene["crimp"]["expansion"] == cal["expansion"]
    assert (out / "crimp" / "sections.png").exists()  # the final crimp folder
    # fabmd crimp on the calibrated scene file gives the calibrated state
    code, text, err = cli(capsys, "crimp", str(out / "calibrated.toml"), "--form", "cell",
                          "--out", str(tmp_path / "again"), "--np", "1", "--quiet", "--json")
    assert code == 0, err
    again = json.loads(text)["crimped"]["thickness_m"]
    assert again == pytest.approx(cal["achieved"]["thickness"], rel=1e-3)


@pytest.mark.lammps
def test_thickness_at_a_pressure_is_measured_under_the_platens(tmp_path, capsys):
    soft = '"30 MPa"'
    path = scene_file(tmp_path, f'\n[calibrate]\nthickness_m = "0.96 mm"\n'
                                f'at_pressure_pa = "5 kPa"\nmax_runs = 6\n'
                                f'\n[contact]\nnormal_stiffness_pa = {soft}\n'
                                f'\n[compaction]\nspeed_fraction = 2e-5\nsamples = 200\n'
                                f'tool = {{ normal_stiffness_pa = {soft} }}\n')
    out = tmp_path / "cal"
    code, text, err = cli(capsys, "calibrate", str(path), "--out", str(out), "--np", "1",
                          "--quiet")
    assert code == 0, err
    assert "under the platens at 5000 Pa" in text
    cal = json.loads((out / "calibration.json").read_text())
    best = cal["runs"][cal["best_run"] - 1]
    assert best["pressure_reached"] and best["compaction_wall_s"] > 0
    # the thickness under 5 kPa, not the free one
    assert best["achieved"]["thickness"] == pytest.approx(0.96e-3, rel=0.02)
    assert best["free_thickness_m"] > best["achieved"]["thickness"]
    pressed = json.loads((out / f"run-{cal['best_run']:02d}" / "compaction" /
                          "summary.json").read_text())
    assert pressed["thickness_at_pressure_m"]["5000"] == best["achieved"]["thickness"]
    curve = (out / f"run-{cal['best_run']:02d}" / "compaction" / "curve.csv").read_text()
    assert ",-1" not in curve  # stopped at the pressure: no unloading branch


@pytest.mark.lammps
def test_unreachable_target_says_why_with_numbers(tmp_path, capsys):
    path = scene_file(tmp_path, '\n[calibrate]\nthickness_m = "0.8 mm"\n')
    out = tmp_path / "cal"
    code, text, err = cli(capsys, "calibrate", str(path), "--out", str(out), "--np", "1",
                          "--quiet")
    assert code == CalibrationNotReached.exit_code == 3
    assert err.startswith("fabmd: error: calibration of") and err.count("\n") == 1
    assert "thickness: not reached at the shrink limit -0.0603" in err  # the loose crimp
    assert "closest 0.97" in err and "target 0.8 mm" in err and "strains -0.0603 to" in err
    cal = json.loads((out / "calibration.json").read_text())
    assert not cal["reached"] and cal["reason"] in err
    assert not (out / "calibrated.toml").exists()


TWO_KNOBS = ('\n[calibrate]\nthickness_m = "1.0 mm"\nthickness_families = ["warp"]\n'
             'target_tension = { weft = "0.5 N" }\nmax_runs = 12\n')


@pytest.mark.lammps
@pytest.mark.slow  # the final crimp draws its figures
def test_coupled_knobs_reach_thickness_and_tension_together(tmp_path, capsys):
    out = tmp_path / "cal"
    code, text, err = cli(capsys, "calibrate", str(scene_file(tmp_path, TWO_KNOBS)),
                          "--out", str(out), "--np", "1", "--quiet")
    assert code == 0, err
    cal = json.loads((out / "calibration.json").read_text())
    assert cal["reached"] and [k["name"] for k in cal["knobs"]] == ["thickness",
                                                                     "tension:weft"]
    assert cal["achieved"]["thickness"] == pytest.approx(1.0e-3, rel=0.02)
    assert cal["achieved"]["tension:weft"] == pytest.approx(0.5, rel=0.05)
    # the warp strain serves the thickness, the weft strain the tension
    assert cal["expansion"]["warp"] != cal["expansion"]["weft"]
    assert len(cal["sensitivity"]["matrix"]) == 2


@pytest.mark.lammps
@pytest.mark.slow  # the final crimp draws its figures
def test_tension_on_the_thickness_families_is_reported_not_controlled(tmp_path, capsys):
    extra = '\n[calibrate]\nthickness_m = "1.0 mm"\ntarget_tension = "5 N"\n'
    out = tmp_path / "cal"
    code, text, err = cli(capsys, "calibrate", str(scene_file(tmp_path, extra)),
                          "--out", str(out), "--np", "1", "--quiet")
    assert code == 3
    assert "tension:warp: not controlled (the warp expansion serves the thickness" in err
    assert "free a family with calibrate.thickness_families" in err
    cal = json.loads((out / "calibration.json").read_text())
    assert cal["controlled_reached"] and not cal["reached"]
    assert [k["name"] for k in cal["uncontrolled"]] == ["tension:warp", "tension:weft"]
    # what can be calibrated is: the thickness, written back
    assert (out / "calibrated.toml").exists()


def test_a_failed_run_is_recorded_and_stops_the_search(tmp_path, capsys, monkeypatch):
    from fabmd.errors import UnstableRun
    from fabmd.protocols.crimp import Crimp

    def blow_up(self, model, out=None, **kwargs):
        raise UnstableRun("bond stretch guard tripped", run_dir=out, cause="bond_stretch")

    monkeypatch.setattr(Crimp, "run", blow_up)
    path = scene_file(tmp_path, '\n[calibrate]\nthickness_m = "1 mm"\n')
    code, out, err = cli(capsys, "calibrate", str(path), "--out", str(tmp_path / "o"))
    assert code == 3 and "run 1 failed at strains -0.0100" in err, err
    assert "bond stretch guard tripped" in err
    cal = json.loads((tmp_path / "o" / "calibration.json").read_text())
    assert cal["runs"][0]["failed"] and not cal["reached"]
    assert not (tmp_path / "o" / "calibrated.toml").exists()


def test_thickness_under_a_pressure_from_a_compaction_summary():
    from fabmd.protocols.calibrate import thickness_under

    curve = {"pressure_reached": True, "thickness_at_pressure_m": {"4140": 5.22e-4},
             "contact_pressure_pa": 343.0, "contact_thickness_m": 5.25e-4}
    assert thickness_under(curve, 4140.0) == 5.22e-4
    # a taut fabric pushes back harder than the target as soon as both platens carry it
    # (measured on the twill example at -2.94 %: 5.8 kPa at its first sample)
    taut = {"pressure_reached": True, "thickness_at_pressure_m": {"4140": None},
            "contact_pressure_pa": 5769.0, "contact_thickness_m": 7.3461e-4}
    assert thickness_under(taut, 4140.0) == 7.3461e-4
    assert thickness_under(dict(curve, pressure_reached=False), 4140.0) is None


@pytest.mark.lammps
@pytest.mark.slow  # ~10-20 s: a tension search in every run, the final crimp's figures
def test_crimp_and_tension_of_one_family_together_by_the_loose_height(tmp_path, capsys):
    extra = ('\n[calibrate]\ncrimp_pct = { warp = 2.0, weft = 2.0 }\ntarget_tension = "1 N"\n'
             'crimp_by = "loose_height"\nmax_runs = 10\n')
    out, text, cal = calibrated(tmp_path, capsys, extra)
    assert "reached (by the crimp's tension search)" in text
    assert cal["reached"] and [k["acts_on"] for k in cal["knobs"]] == ["loose_height"] * 2
    for fam in ("warp", "weft"):
        assert cal["achieved"][f"crimp:{fam}"] == pytest.approx(2.0, abs=0.2)
        assert cal["achieved"][f"tension:{fam}"] == pytest.approx(1.0, rel=0.05)
    # the scene's 0.5 mm loose yarns crimp to ~3 % at 1 N: lower ones are needed
    heights = cal["loose_height_m"]
    assert 0.3e-3 < heights["warp"] < 0.5e-3 and 0.3e-3 < heights["weft"] < 0.5e-3
    # along the runs, a lower loose section gave less crimp at the same tension
    runs = [r for r in cal["runs"] if not r.get("failed")]
    pairs = sorted((r["loose_height_m"]["warp"] + r["loose_height_m"]["weft"],
                    r["achieved"]["crimp:warp"]) for r in runs)
    assert pairs[0][1] < pairs[-1][1]
    scene = tomllib.loads((out / "calibrated.toml").read_text())
    assert scene["yarns"]["warp"]["height_m"] == f"{1e3 * heights['warp']:.6g} mm"
    assert scene["crimp"]["expansion"] == cal["expansion"]
    assert cal["expansion"]["warp"] < -0.01  # the tension search moved it
    # the calibrated file crimps again to what was found
    final = cal["final_crimp"]
    assert final["crimp_pct"]["warp"] == pytest.approx(cal["achieved"]["crimp:warp"],
                                                       abs=0.02)


def test_heights_the_cell_cannot_be_drawn_at_step_halfway_back():
    from fabmd.protocols.calibrate import _step_back

    knobs = [Knob(f"crimp:{f}", "crimp", (f,), 1.5, 0.03, +1, (-0.5, 0.5), v,
                  acts_on="loose_height") for f, v in (("warp", -0.4), ("weft", -0.08))]
    runs = [{"run": 1, "knobs": {"crimp:warp": 0.0, "crimp:weft": 0.0},
             "achieved": {"crimp:warp": 2.3, "crimp:weft": 2.8}},
            {"run": 2, "knobs": {"crimp:warp": -0.25, "crimp:weft": -0.07},
             "achieved": {"crimp:warp": 2.08, "crimp:weft": 2.39}},
            {"run": 3, "knobs": {"crimp:warp": -0.4, "crimp:weft": -0.08},
             "achieved": {"crimp:warp": None, "crimp:weft": None}, "failed": "overlap",
             "undrawable": True}]
    assert _step_back(knobs, runs)  # halfway from the failed step to the closest run (2)
    assert [kn.value for kn in knobs] == [pytest.approx(-0.325), pytest.approx(-0.075)]
    # nothing measured yet, or already within 1e-3 of the closest: the search stops
    assert not _step_back(knobs, runs[2:])
    for kn, v in zip(knobs, (-0.2505, -0.0705), strict=True):
        kn.value = v
    assert not _step_back(knobs, runs)
