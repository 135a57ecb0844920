"""The build says where the within-family law's virtual fibres touch and what part of the
law that cuts off: the contact diameter the section's packing gives is a numerical choice
that changes the yarn's law (benchmarks/RESULTS.md "What sets the picture-frame force past
20°")."""

import tomllib
from pathlib import Path

import pytest

from fabmd.cli.build import datasheet_lines, summarise
from fabmd.scenefile import parse_scene

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plain_weave.toml"
HEX = 3**0.5 / 2  # hexagonal cell of unit spacing


def _scene(text: str):
    return parse_scene(tomllib.loads(text), source=str(EXAMPLE))


def _summary(text: str) -> dict:
    scene = _scene(text)
    return summarise(scene.model(), scene)


def test_the_example_cuts_the_laws_first_kilopascals():
    text = EXAMPLE.read_text()
    s = _summary(text)
    law = _scene(text).contact.within_family_law.law
    for family in ("warp", "weft"):
        r = s["within_family_law"][family]
        # by hand: 600 tex of glass in 7 virtual fibres, each of the inscribed diameter
        area = 600e-6 / 2540.0 / 7
        d = s["fibre_diameter_m"][family]
        touching = area / (HEX * d**2)
        assert r["touching_vf"] == pytest.approx(touching, rel=1e-9)
        assert 0.34 < touching < 0.36 and r["law_vf0"] == law.vf0 < touching
        k = law.coefficient * law.modulus_pa
        assert r["cut_pressure_pa"] == pytest.approx(k * (touching**3 - law.vf0**3), rel=1e-9)
    line = datasheet_lines(s).splitlines()[-1]
    assert line.startswith("  within-family law: warp, weft fibres touch at Vf 0.35")
    assert "kPa cut off" in line


def test_fibres_that_touch_below_the_laws_start_cut_nothing():
    # a section 1.2x as large: the inscribed fibres grow to touch below Vf0 = 0.30
    text = EXAMPLE.read_text().replace('width_m = "1.6 mm"', 'width_m = "1.92 mm"') \
        .replace('height_m = "0.8 mm"', 'height_m = "0.96 mm"') \
        .replace('clearance_m = "0.05 mm"', 'clearance_m = "0.3 mm"')
    s = _summary(text)
    for r in s["within_family_law"].values():
        assert r["touching_vf"] < r["law_vf0"] and r["cut_pressure_pa"] == 0.0
    line = datasheet_lines(s).splitlines()[-1]
    assert "touch at Vf 0.2" in line and "cut off" not in line


def test_without_the_law_nothing_is_said():
    text = EXAMPLE.read_text().replace(
        'within_family = { law = "glass", form = "law" }', "")
    s = _summary(text)
    assert s["within_family_law"] is None
    assert "within-family law" not in datasheet_lines(s)
