"""The Twintex balanced 2/2 twill of Cao et al. (2008), Table 1
(benchmarks/scenes/twintex_twill.toml; not an example: it does not crimp with the law): a dense
fabric (width/spacing 0.90 warp, 0.87 weft) and what its loose state needs."""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import pytest

from fabmd.errors import InputError
from fabmd.model.fabric_model import render_fabric, render_loose
from fabmd.scenefile import load_scene, parse_scene

SCENE = Path(__file__).resolve().parents[1] / "benchmarks" / "scenes" / "twintex_twill.toml"
#: the lift the loose-state search of the shipped scene ends at [m] (tested below)
FOUND_LIFT_M = 1.477e-3


def _scene_text(**swap) -> str:
    text = SCENE.read_text()
    for old, new in swap.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


def _fabric(text: str):
    return parse_scene(tomllib.loads(text), source="twill").fabric


def test_table1_areal_density_is_refused_with_the_arithmetic():
    # 1870 tex x (556 + 375) /m = 1741 g/m2 of straight yarn, 17 % above the 1485 quoted
    given = 'areal_density_kg_m2 = "1485 g/m2"'
    text = _scene_text(**{f"# {given}": given})
    with pytest.raises(InputError, match=r"1741 g/m².*-14.7 %"):
        _fabric(text)


def test_shipped_twill_builds_at_the_woven_widths_fast():
    """The loose state the search finds (lift fixed here; the search is the next test):
    no overlap, the datasheet widths kept, yarn Vf <= 0.8, mass above the straight yarns."""
    fabric = load_scene(SCENE).fabric
    assert fabric.warp.width_m / fabric.warp.spacing_m == pytest.approx(0.90, abs=0.005)
    assert fabric.weft.width_m / fabric.weft.spacing_m == pytest.approx(0.87, abs=0.005)
    model = render_loose(dataclasses.replace(fabric, lift_m=FOUND_LIFT_M))  # raises on overlap
    info = model.info
    assert info["clearance_m"] > 0
    for fam, width in (("warp", 1.62e-3), ("weft", 2.32e-3)):
        pack = info["yarn_packing"][fam]
        assert pack["width_m"] == pytest.approx(width)
        assert pack["yarn_fibre_volume_fraction"] <= 0.8
    straight = sum(info["datasheet"]["straight_areal_density_kg_m2"].values())
    assert straight == pytest.approx(1.741, rel=1e-3)
    assert info["areal_density_kg_m2"] > straight


def test_shipped_twill_loose_state_search():
    """clearance "auto": narrower widths fold at every lift, so the search keeps the full
    widths at the lift with the widest gap below the half clearance it asks for."""
    scene = load_scene(SCENE)
    model = render_fabric(scene.fabric, scene.discretisation)
    info = model.info
    assert info["loose_width_factor"] == 1.0
    assert info["auto_clearance_gap_short"] is True
    assert info["lift_m"] == pytest.approx(FOUND_LIFT_M, rel=1e-3)
    assert 0 < info["clearance_m"] < 0.5 * scene.fabric.clearance_m


def test_no_loose_state_names_the_overlap_and_the_fold():
    """Sections at Vf 0.6 (the plain weave's): lifting folds a yarn before the crossings
    clear; the search tries every width and says both, instead of stopping at the fold."""
    text = _scene_text(**{"fibre_volume_fraction = 0.7": "fibre_volume_fraction = 0.6",
                          "plateau = 0.0": "plateau = 0.85"})
    with pytest.raises(InputError, match=r"no loose state.*at loose width 0.55.*bends with "
                                         r"radius .* at a lift of .*no loose state found"):
        render_fabric(_fabric(text))


def test_a_fibre_whose_beads_coincide_is_a_fold_not_a_nan():
    text = _scene_text(**{"fibre_volume_fraction = 0.7":
                          'fibre_volume_fraction = 0.8\nfibre_packing = "area"',
                          'shape = "lenticular"': 'shape = "ellipse"'})
    fabric = _fabric(text)
    with pytest.raises(InputError, match="weft-2: its fibre .* would fold"):
        # (the crossings stacked by what the area packing's fibres fill: the weft's offset
        # curve has a cusp at lifts 1.3-1.5 mm, before its curvature says fold at 1.6)
        render_loose(dataclasses.replace(fabric, lift_m=1.4e-3))


def test_the_two_families_fibres_differ_in_diameter():
    """The inscribed fibres of the two sections are 0.497 / 0.413 mm: the law takes one
    table per family, but the weft's fibres hold more filament area than a hexagonal
    bundle of their diameter packs (touching Vf 1.225 > 0.907), so the scene with the law
    is refused when read (why the shipped scene keeps the default contact)."""
    fabric = load_scene(SCENE).fabric
    d = {fam: spec.packing()[1] for fam, spec in fabric.specs().items()}
    assert d["warp"] == pytest.approx(0.497e-3, rel=2e-3)
    assert d["weft"] == pytest.approx(0.413e-3, rel=2e-3)
    text = _scene_text(**{"# within_family = {": "within_family = {"})
    with pytest.raises(InputError, match=r"\[contact.within_family\] weft: .*touch at Vf "
                                         r"1.225, at or above the packing limit 0.907"):
        _fabric(text)
