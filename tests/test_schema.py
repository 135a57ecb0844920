"""One scene schema (issue 15): every table declared once, built by one builder.

Pure Python: nothing here starts LAMMPS. The schema's imports sit inside the tests so
that each test can be run (and fail) against code without :mod:`fabmd.schema`.
"""

import dataclasses
import importlib
import tomllib

import pytest

from fabmd.errors import InputError
from fabmd.scenefile import parse_scene

from .test_pipeline import TINY
from .test_reliability_input import with_table

#: a unit at the end of a field's name (a field so named must declare its unit)
UNIT_SUFFIXES = ("_m", "_s", "_pa", "_n", "_m2", "_kg_m3", "_kg_m2", "_n_per_m", "_m_s")


def refused(text: str, source: str = "x.toml") -> str:
    """The one-line message of the scene ``text`` (its stage tables checked too)."""
    from fabmd.preflight import check_scene

    with pytest.raises(InputError) as err:
        check_scene(parse_scene(tomllib.loads(text), source=source))
    message = str(err.value)
    assert "\n" not in message and message.startswith(f"{source}: ")
    return message


# ---- bugs of issue 15 -------------------------------------------------------------------
@pytest.mark.parametrize("table", ["tension.contact", "drape.tool"])
def test_stiffness_given_as_a_length_is_refused(table):
    # it was read as a length by its name's "_m": "5 mm" became 0.005 N/m
    test, sub = table.split(".")
    text = TINY + f'\n[{test}.{sub}]\nstiffness_n_per_m = "5 mm"\n'
    if test == "drape":
        text += "[drape.coupon]\nlength_m = \"200 mm\"\nwidth_m = \"200 mm\"\n"
    message = refused(text)
    assert f"{table}.stiffness_n_per_m = '5 mm'" in message
    assert "stiffness unit 'mm'" in message and "n/m" in message


def test_stiffness_with_its_unit_is_read():
    from fabmd.preflight import plan_test

    text = TINY.replace("[tension]", '[tension]\ncontact = { stiffness_n_per_m = "2 kN/m" }')
    scene = parse_scene(tomllib.loads(text))
    assert plan_test(scene, "tension").protocol.contact.stiffness_n_per_m == 2000.0
    bad = TINY.replace("[yarns.warp]", '[contact]\nstiffness_n_per_m = "5 mm"\n[yarns.warp]')
    assert "contact.stiffness_n_per_m = '5 mm'" in refused(bad)


# every table a test reads: a misspelt key fails `fabmd build` naming the key and the file
TEST_TABLES = ["crimp", "tension", "picture_frame", "bias_extension", "drape",
               "periodic_tension", "periodic_shear", "compaction", "tension.time_step",
               "tension.trajectory", "tension.contact", "tension.relax", "picture_frame.coupon",
               "crimp.quasi_static", "drape.tool", "compaction.tool"]


@pytest.mark.parametrize("table", TEST_TABLES)
def test_misspelt_key_in_any_test_table_fails_build(tmp_path, table):
    from fabmd.cli.build import build
    from fabmd.scenefile import load_scene

    text = with_table(table, f"[{table}]\nspeed_fractio = 0.1") if "." not in table else \
        TINY + f"\n[{table}]\nspeed_fractio = 0.1\n"
    path = tmp_path / "typo.toml"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        build(load_scene(path), tmp_path / "out")
    message = str(err.value)
    assert str(path) in message and "'speed_fractio'" in message and f"[{table}]" in message
    assert not (tmp_path / "out").exists()


def test_misspelt_key_fails_the_build_command(tmp_path):
    from fabmd.cli import main

    path = tmp_path / "typo.toml"
    path.write_text(TINY.replace("[tension]", "[tension]\nspeed_fractio = 0.1"))
    assert main(["build", str(path), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()


def test_missing_material_names_the_yarn_and_the_material():
    text = TINY.replace('material = "soft"\nlinear_density_tex = 600\nn_fibres = 1\n'
                        'width_m = "1.0 mm"\ncount_per_m = "4 picks/cm"',
                        'material = "sfot"\nlinear_density_tex = 600\nn_fibres = 1\n'
                        'width_m = "1.0 mm"\ncount_per_m = "4 picks/cm"')
    message = refused(text)
    assert "[yarns.weft] material 'sfot' is not defined" in message
    assert "[materials.sfot]" in message


def test_time_step_factor_has_one_name():
    from fabmd.cli.validate import parse_settings
    from fabmd.verification import capstan, fibre_tension, sliding

    test = fibre_tension.from_settings(parse_settings(["time_step.factor=0.2"]))
    assert test.time_step.factor == 0.2
    assert sliding.from_settings(parse_settings(["time_step.factor=0.2"]), 0.3,
                                 "hooke").time_step.factor == 0.2
    assert capstan.from_settings(parse_settings(["time_step.factor=0.2"]), 0.3,
                                 1.0).time_step.factor == 0.2
    for old, new in (("time_step_factor=0.2", "time_step.factor"),
                     ("time_step_s=1e-9", "time_step.value_s")):
        with pytest.raises(InputError, match=f"is now --set {new}"):
            fibre_tension.from_settings(parse_settings([old]))
    # the scene files' name: [<test>.time_step] factor
    scene = parse_scene(tomllib.loads(TINY + "\n[tension.time_step]\nfactor = 0.2\n"))
    from fabmd.preflight import plan_test

    assert plan_test(scene, "tension").protocol.time_step.factor == 0.2


def test_set_reads_units_and_refuses_unknown_keys():
    from fabmd.cli.validate import parse_settings
    from fabmd.verification import fibre_tension

    test = fibre_tension.from_settings(parse_settings(["diameter_m=0.2 mm", "length_m=2e-3"]))
    assert test.fibre.diameter_m == pytest.approx(2e-4) and test.length_m == 2e-3
    with pytest.raises(InputError, match=r"\[fibre-tension\] has no key 'lenght_m'"):
        fibre_tension.from_settings(parse_settings(["lenght_m=1"]))
    with pytest.raises(InputError, match=r"diameter_m = '3 GPa': unknown length unit"):
        fibre_tension.from_settings(parse_settings(["diameter_m=3 GPa"]))


# ---- the schema itself ------------------------------------------------------------------
def test_units_come_from_declarations_not_name_suffixes():
    from fabmd import schema

    @dataclasses.dataclass
    class Probe:
        gap_m: float = 0.0  # named like a length, declared nothing: numbers only
        size: float = dataclasses.field(default=0.0, metadata=schema.unit("length"))
        depths_m: tuple = ()

    assert schema.unit_of(Probe, "gap_m") is None
    probe = schema.build(Probe, {"size": "2 mm", "depths_m": [1, 2]}, "probe")
    assert probe.size == pytest.approx(2e-3) and probe.depths_m == (1, 2)
    assert schema.build(Probe, {"gap_m": "2 mm"}, "probe").gap_m == "2 mm"  # not read


def test_lists_of_quantities_and_types_from_annotations():
    from fabmd import schema
    from fabmd.protocols.crimp import Crimp
    from fabmd.protocols.drape import Drape

    drape = schema.build(Drape, {"report_depths_m": ["5 mm", 0.01]}, "drape")
    assert drape.report_depths_m == (pytest.approx(0.005), 0.01)
    with pytest.raises(InputError, match=r"\[crimp\] hold_ends must be true or false"):
        schema.build(Crimp, {"hold_ends": "yes"}, "crimp")
    with pytest.raises(InputError, match=r"x.toml: \[crimp\] has no key 'holdends'"):
        schema.build(Crimp, {"holdends": True}, "crimp", where="x.toml")


def _table_classes():
    """Every dataclass a scene-file table builds, sub-tables included."""
    import typing

    from fabmd import schema
    from fabmd.geometry.fabric import Fabric
    from fabmd.model.beads import Discretisation
    from fabmd.model.compaction import CompactionLaw
    from fabmd.model.material import FibreMaterial
    from fabmd.pipeline import TESTS
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.crimp import Crimp
    from fabmd.verification import capstan, fibre_tension, sliding

    todo = [Crimp, Coupon, Fabric, Discretisation, FibreMaterial, CompactionLaw,
            fibre_tension.Settings, capstan.Settings, sliding.Settings]
    todo += [getattr(importlib.import_module(k.module), k.cls) for k in TESTS.values()]
    seen = []
    while todo:
        cls = todo.pop()
        if cls in seen:
            continue
        seen.append(cls)
        hints = typing.get_type_hints(cls)
        todo += [n for f in dataclasses.fields(cls) for n in schema._dataclasses_in(
            hints.get(f.name))]
    return seen


def test_every_field_named_with_a_unit_declares_it():
    from fabmd import schema

    missing = []
    for cls in _table_classes():
        for f in dataclasses.fields(cls):
            if not f.init or not f.name.endswith(UNIT_SUFFIXES):
                continue
            plain = any(f.name in schema.NUMBERS.get(b.__name__, ()) for b in cls.__mro__)
            if schema.unit_of(cls, f.name) is None and not plain:
                missing.append(f"{cls.__name__}.{f.name}")
    assert not missing, f"declare their units in fabmd.schema.UNITS: {missing}"


def test_merged_puts_an_override_into_a_copy_of_nested_tables():
    from fabmd.schema import merged

    base = {"contact": {"friction": 0.3, "law": {"form": "secant"}}, "yarns": ["warp"]}
    override = {"contact": {"friction": 0.1, "law": {"k": 2}}, "yarns": ["weft"],
                "crimp": {"target_tension": "1 cN/tex"}}
    out = merged(base, override)
    assert out == {"contact": {"friction": 0.1, "law": {"form": "secant", "k": 2}},
                   "yarns": ["weft"], "crimp": {"target_tension": "1 cN/tex"}}
    # neither input changed, and the result shares nothing mutable with them
    assert base == {"contact": {"friction": 0.3, "law": {"form": "secant"}}, "yarns": ["warp"]}
    assert override["contact"] == {"friction": 0.1, "law": {"k": 2}}
    out["crimp"]["target_tension"] = 0
    out["contact"]["law"]["form"] = "law"
    out["yarns"].append("binder")
    assert override["crimp"] == {"target_tension": "1 cN/tex"}
    assert base["contact"]["law"] == {"form": "secant"} and override["yarns"] == ["weft"]
    # a table replaces a plain value and the other way round
    assert merged({"a": 1, "b": {"c": 2}}, {"a": {"x": 1}, "b": 3}) == {"a": {"x": 1}, "b": 3}
