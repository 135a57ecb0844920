"""Expansion from the crimp a fabric needs (``[crimp] target_crimp_pct``): the geometry
arithmetic without LAMMPS, and one tiny crimp (periodic plain-weave cell, one fibre per
yarn) that reaches its targets."""

import pytest

from fabmd import schema
from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.protocols.crimp import Crimp
from fabmd.protocols.crimp_target import derive_expansion, expansion_for, rest_crimp
from fabmd.protocols.crimp_tension import shrink_bounds
from fabmd.results.measure import family_crimp

from .fabrics import parallel_fibres, plain_weave_cell

#: the plain-weave example's crimp lines (a weaving-tension search from −6.8 %)
EXAMPLE_CRIMP = 'target_tension = "1 cN/tex"\nexpansion = { warp = -0.068, weft = -0.068 }'
#: the example's crimp stated and reached by the loose height: out, where a test sets its own
EXAMPLE_PIN = ('target_crimp_pct = { warp = 1.5, weft = 1.5 }\n', 'crimp_by = "loose_height"\n',
               "crimp_tolerance_pct = 0.05\n")


def example_text() -> str:
    """The plain-weave example's file without its stated crimp (the expansion and the
    weaving tension stay)."""
    from pathlib import Path

    text = (Path(__file__).parents[1] / "examples" / "plain_weave.toml").read_text()
    for line in EXAMPLE_PIN:
        assert line in text
        text = text.replace(line, "")
    return text


def test_rest_crimp_is_the_loose_crimp_of_an_unstressed_fabric():
    cell = plain_weave_cell()
    rest = rest_crimp(cell)
    measured = family_crimp(cell)
    for fam in ("warp", "weft"):
        assert rest[fam] == pytest.approx(measured[fam], rel=1e-9)
        assert 0.02 < rest[fam] < 0.1  # a wavy single-fibre yarn
    # scaled rest lengths count: the rest crimp of a cell whose warp rest length is 2 % up
    cell.bond_type_table[0] = type(cell.bond_type_table[0])(
        cell.bond_type_table[0].coefficient, 1.02 * cell.bond_type_table[0].rest_length_m,
        "warp", cell.bond_type_table[0].axial_stiffness_n)
    assert rest_crimp(cell)["warp"] == pytest.approx(1.02 * (1 + rest["warp"]) - 1, rel=1e-9)


def test_expansion_gives_the_target_crimp_without_tension():
    # (1 + c) / (1 + c0) - 1, and back: (1 + c0)(1 + a) - 1 = c
    assert expansion_for(0.139, 0.03) == pytest.approx(1.03 / 1.139 - 1)
    assert expansion_for(0.02, 0.05) == pytest.approx(1.05 / 1.02 - 1)
    for c0, c in ((0.139, 0.03), (0.0348, 0.012), (0.01, 0.04)):
        assert (1 + c0) * (1 + expansion_for(c0, c)) - 1 == pytest.approx(c, abs=1e-15)
    assert expansion_for(0.05, 0.05) == 0.0


def test_derived_expansion_per_family_and_auto():
    cell = plain_weave_cell()
    c0 = rest_crimp(cell)
    out = derive_expansion(cell, {"warp": 1.0, "weft": "auto"}, margin_pct=2.0)
    assert out["warp"]["expansion"] == pytest.approx(1.01 / (1 + c0["warp"]) - 1)
    assert out["warp"]["target_crimp_pct"] == pytest.approx(1.0)
    assert out["warp"]["loose_rest_crimp_pct"] == pytest.approx(100 * c0["warp"], rel=1e-6)
    # auto: shrink by the loose crimp less the margin, i.e. target = margin
    assert out["weft"]["expansion"] == pytest.approx(1.02 / (1 + c0["weft"]) - 1)
    assert out["weft"]["auto"] and not out["warp"]["auto"]
    assert -c0["weft"] < out["weft"]["expansion"] < 0  # a shrink short of the loose crimp
    # the crimp stage uses it: the same input as the explicit expansion
    derived = Crimp(target_crimp_pct={"warp": 1.0, "weft": "auto"}, auto_margin_pct=2.0)
    explicit = Crimp(expansion={f: v["expansion"] for f, v in out.items()})
    assert derived.family_expansion(cell) == explicit.family_expansion(cell)
    assert derived.input_text(cell) == explicit.input_text(cell)
    assert derived.rest_length_scale(cell) == explicit.rest_length_scale(cell)


def test_without_targets_the_expansion_is_as_given():
    crimp = Crimp(expansion={"warp": -0.05})
    assert crimp.family_expansion(plain_weave_cell()) is crimp.expansion
    assert crimp.crimp_targets(plain_weave_cell()) == {}


@pytest.mark.parametrize("targets, words", [
    ({"warp": -1.0}, "must be in [0, 100)"),
    ({"warp": 100.0}, "must be in [0, 100)"),
    ({"warp": "tight"}, "a number) or \"auto\""),
    ([1.0], "must be a table family"),
])
def test_malformed_targets_are_refused_at_construction(targets, words):
    with pytest.raises(InputError, match="crimp.target_crimp_pct") as err:
        Crimp(target_crimp_pct=targets)
    assert words in str(err.value)


def test_targets_that_clash_with_other_settings_are_refused():
    with pytest.raises(InputError, match="both name \\['warp'\\]"):
        Crimp(expansion={"warp": 0.01}, target_crimp_pct={"warp": 1.0})
    with pytest.raises(InputError, match="target_tension both name \\['weft'\\]"):
        Crimp(target_tension={"weft": "1 cN/tex"}, target_crimp_pct={"weft": 1.0})
    with pytest.raises(InputError, match="target_tension both name"):
        Crimp(target_tension="1 cN/tex", target_crimp_pct={"weft": 1.0})
    with pytest.raises(InputError, match="auto_margin_pct must be in"):
        Crimp(target_crimp_pct={"weft": "auto"}, auto_margin_pct=0)
    # other families may have either
    Crimp(target_tension={"weft": "1 cN/tex"}, target_crimp_pct={"warp": 1.0},
          expansion={"weft": -0.01})
    # "auto" beside a tension bounds the tension search's shrink
    Crimp(target_tension="1 N", target_crimp_pct={"warp": "auto"})


def test_auto_bounds_the_tension_search_shrink():
    cell = plain_weave_cell()
    c0 = rest_crimp(cell)["warp"]
    crimp = Crimp(target_tension={"warp": 1.0, "weft": 1.0},
                  target_crimp_pct={"warp": "auto"}, auto_margin_pct=2.5)
    assert shrink_bounds(crimp, cell, ["warp", "weft"]) == {
        "warp": pytest.approx(1.025 / (1 + c0) - 1)}
    assert shrink_bounds(Crimp(target_tension=1.0), cell, ["warp", "weft"]) == {}


def test_targets_the_numbers_cannot_reach_are_refused_with_the_arithmetic():
    cell = plain_weave_cell()
    c0 = 100 * rest_crimp(cell)["warp"]
    with pytest.raises(InputError, match="names families \\['binder'\\]"):
        Crimp(target_crimp_pct={"binder": "auto"}).input_text(cell)
    with pytest.raises(InputError, match="nothing to shrink") as err:
        Crimp(target_crimp_pct={"warp": "auto"}, auto_margin_pct=c0 + 0.5).input_text(cell)
    assert f"{c0:.3g} %" in str(err.value)
    with pytest.raises(InputError, match="cannot be pulled straight"):
        Crimp(target_crimp_pct={"warp": 0}).input_text(cell)
    with pytest.raises(InputError, match=r"\(1 \+ 0.9\) / \(1 \+ 0.0\d+\) - 1 = 0.\d+, is "
                                         r"outside \(-0.5, 0.5\)"):
        Crimp(target_crimp_pct={"warp": 90}).input_text(cell)
    straight = parallel_fibres()
    with pytest.raises(InputError, match="straight in the loose fabric"):
        Crimp(target_crimp_pct={"warp": 1.0}).input_text(straight)
    # a straight family told to stay straight is no expansion at all
    assert Crimp(target_crimp_pct={"warp": 0}).family_expansion(straight)["warp"] == \
        pytest.approx(0.0, abs=1e-12)


def test_scene_file_table_builds_the_targets():
    crimp = schema.build(Crimp, {"target_crimp_pct": {"warp": 1.5, "binder": "auto"},
                                 "auto_margin_pct": 4}, "crimp")
    assert crimp.target_crimp_pct == {"warp": 1.5, "binder": "auto"}
    assert crimp.auto_margin_pct == 4
    with pytest.raises(InputError, match="\\[crimp\\] crimp.target_crimp_pct.warp"):
        schema.build(Crimp, {"target_crimp_pct": {"warp": -2}}, "crimp")


@pytest.mark.lammps
def test_crimp_reaches_its_target_crimps(tmp_path):
    """Periodic plain-weave cell, one fibre per yarn: the warp is told a crimp below its
    loose one (it shrinks and tightens), the weft one above (it expands and takes the
    room the straightening warp leaves). Each ends within 0.25 percentage points of its
    target; what is left is its strain under the tension it ends with."""
    loose = plain_weave_cell()
    c0 = {f: 100 * c for f, c in rest_crimp(loose).items()}
    targets = {"warp": round(c0["warp"] - 1.5, 2), "weft": round(c0["weft"] + 1.5, 2)}
    result = Crimp(target_crimp_pct=targets).run(loose, tmp_path / "run",
                                                 engine=Engine(progress=False))
    s = result.summary
    assert s["quasi_static"], s["criterion"]
    assert s["pass_through"]["flipped_pairs"] == 0
    assert s["crimp_targets"]["warp"]["target_crimp_pct"] == pytest.approx(targets["warp"])
    assert s["expansion"]["warp"] < 0 < s["expansion"]["weft"]
    reached = s["crimped"]["crimp_pct"]
    for fam in ("warp", "weft"):
        assert reached[fam] == pytest.approx(targets[fam], abs=0.25), (fam, reached, targets)
        # what is left is the fibres' strain: their tension over E·A, under 0.25 %
        tension = s["crimped"]["tension"][fam]["mean_fibre_tension_n"]
        axial = loose.bond_type_table[0].axial_stiffness_n
        assert abs(tension) < 2.5e-3 * axial, (fam, tension, axial)


@pytest.mark.lammps
def test_tension_search_stops_at_the_auto_shrink_bound(tmp_path):
    """A yarn tension this loose cell carries only with its warp pulled straighter than
    the "auto" margin allows is not reached: the search stops at the bound (2 runs), says
    so, and the warp keeps the margin's crimp."""
    loose = plain_weave_cell()
    crimp = Crimp(target_tension={"warp": 50.0}, target_crimp_pct={"warp": "auto"})
    with pytest.warns(UserWarning, match="warp at the \"auto\" shrink bound"):
        result = crimp.run(loose, tmp_path / "run", engine=Engine(progress=False))
    search = result.summary["tension_search"]
    bound = search["shrink_bound"]["warp"]
    assert bound == pytest.approx(1.03 / (1 + rest_crimp(loose)["warp"]) - 1)
    assert not search["reached"] and search["at_bound"] == ["warp"]
    assert [r["expansion"]["warp"] for r in search["runs"]] == [0.0, bound]
    assert result.summary["expansion"]["warp"] == bound
    assert result.summary["crimped"]["crimp_pct"]["warp"] >= 3.0 - 0.01


def test_scene_file_targets_on_the_example_cell(tmp_path):
    """The plain-weave example with its expansion replaced by target crimps: the derived
    strains follow the cell's loose geometry; an unreachable one fails before LAMMPS,
    naming the scene file's key and the numbers."""

    from fabmd.pipeline import crimp_stage, periodic_cell
    from fabmd.scenefile import load_scene

    text = example_text()
    assert EXAMPLE_CRIMP in text
    scene_file = tmp_path / "targets.toml"
    scene_file.write_text(text.replace(EXAMPLE_CRIMP,
                                       'target_crimp_pct = { warp = 1.0, weft = "auto" }'))
    scene = load_scene(scene_file)
    cell = periodic_cell(scene)
    crimp = crimp_stage(scene)
    c0 = rest_crimp(cell)
    assert crimp.family_expansion(cell) == {
        "warp": pytest.approx(1.01 / (1 + c0["warp"]) - 1),
        "weft": pytest.approx(1.03 / (1 + c0["weft"]) - 1)}
    assert "crimp" in crimp.input_text(cell)
    scene_file.write_text(text.replace(EXAMPLE_CRIMP,
                                       "target_crimp_pct = { warp = 0 }"))
    with pytest.raises(InputError, match="target_crimp_pct.warp = 0: the warp yarns are "
                                         "woven .* cannot be pulled straight"):
        crimp_stage(load_scene(scene_file)).input_text(periodic_cell(load_scene(scene_file)))


def test_calibration_refuses_a_scene_whose_crimp_derives_its_expansion(tmp_path):

    from fabmd.calibration import run_calibration
    from fabmd.scenefile import load_scene

    text = example_text()
    scene_file = tmp_path / "targets.toml"
    scene_file.write_text(text.replace(EXAMPLE_CRIMP,
                                       "target_crimp_pct = { warp = 1.0 }")
                          + "\n[calibrate]\ncrimp_pct = { weft = 1.0 }\n")
    with pytest.raises(InputError, match="target_crimp_pct derives the expansion itself"):
        run_calibration(load_scene(scene_file), tmp_path / "out")
    assert not (tmp_path / "out").exists()


def _unreachable_auto_scene(tmp_path):
    """The plain-weave example whose weft target is "auto" with a margin (50 points) above
    its loose crimp: nothing to shrink, refused with the numbers."""

    text = example_text()
    scene_file = tmp_path / "targets.toml"
    scene_file.write_text(text.replace(EXAMPLE_CRIMP,
                                       'target_crimp_pct = { weft = "auto" }\n'
                                       "auto_margin_pct = 50"))
    return scene_file


def test_fabmd_crimp_refuses_an_unreachable_target_before_any_folder(tmp_path):
    from fabmd.pipeline import run_crimp
    from fabmd.scenefile import load_scene

    scene_file = _unreachable_auto_scene(tmp_path)
    with pytest.raises(InputError, match="nothing to shrink"):
        run_crimp(load_scene(scene_file), tmp_path / "crimp", form="cell")
    assert list(tmp_path.iterdir()) == [scene_file]


@pytest.mark.parametrize("test", ["picture-frame", "periodic-shear"])
def test_fabmd_test_refuses_an_unreachable_target_before_any_folder(tmp_path, test):
    """`fabmd test` (coupon from the cell, or the cell itself) refuses the target before
    LAMMPS and writes no folder, not even ``<out>.failed``."""
    from fabmd.pipeline import run_test
    from fabmd.scenefile import load_scene

    scene_file = _unreachable_auto_scene(tmp_path)
    with pytest.raises(InputError, match="nothing to shrink"):
        run_test(load_scene(scene_file), test, tmp_path / "out")
    assert list(tmp_path.iterdir()) == [scene_file]


def test_a_crimp_that_went_into_one_family_of_a_balanced_fabric_is_named():
    from fabmd.protocols.crimp_balance import crimp_interchange

    loose = {"crimp_pct": {"warp": 2.75, "weft": 2.76}}
    # the 19-fibre cell from loose yarns 0.84 mm high (benchmarks/RESULTS.md)
    note = crimp_interchange(loose, {"crimp_pct": {"warp": 2.488, "weft": 0.886}})
    assert note and "2.49 / 0.886 %" in note and "crimp_by = \"loose_height\"" in note
    assert crimp_interchange(loose, {"crimp_pct": {"warp": 1.513, "weft": 1.525}}) is None
    # drawn differently (an unbalanced fabric): its crimps may differ
    assert crimp_interchange({"crimp_pct": {"warp": 2.0, "weft": 4.0}},
                             {"crimp_pct": {"warp": 0.5, "weft": 3.0}}) is None
    assert crimp_interchange({"crimp_pct": {"binder": 5.0}}, {"crimp_pct": {}}) is None
