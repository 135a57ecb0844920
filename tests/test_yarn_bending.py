"""A yarn's bending rigidity as a property of the yarn (``[yarns.*] bending_stiffness_nm2``):
shared by its virtual fibres whatever their number and spacing, and the chain's bending
term against the cantilever's closed form (a LAMMPS run, seconds)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.geometry.fabric import Fabric
from fabmd.geometry.material import GLASS
from fabmd.geometry.weave import Weave
from fabmd.geometry.yarn_spec import YarnSpec
from fabmd.model.bead_model import AngleType
from fabmd.model.beads import Discretisation
from fabmd.model.bending import chain_triples
from fabmd.model.fabric_model import render_loose

from .cantilever import tip_deflection
from .fabrics import parallel_fibres


def _yarn(**kw) -> YarnSpec:
    base = dict(linear_density_tex=600, material=GLASS, width_m=1.6e-3, height_m=0.8e-3,
                spacing_m=2.5e-3, filament_diameter_m="17 um", bending_stiffness_nm2="filaments")
    return YarnSpec(**{**base, **kw})


def test_the_filaments_rigidity_is_the_sum_of_the_filaments():
    spec = _yarn()
    # 600 tex of E-glass in 17 µm filaments: n = (tex/ρ)/(π d²/4) filaments of E·π·d⁴/64
    d = 17e-6
    count = 600e-6 / 2540.0 / (math.pi * d * d / 4)
    assert spec.yarn_bending_stiffness_nm2 == pytest.approx(count * 73e9 * math.pi * d**4 / 64)
    assert spec.yarn_bending_stiffness_nm2 == pytest.approx(3.11e-7, rel=0.01)
    # a measured rigidity in any of its units
    assert _yarn(bending_stiffness_nm2="0.31 N·mm2").yarn_bending_stiffness_nm2 == \
        pytest.approx(3.1e-7)
    assert _yarn(bending_stiffness_nm2="0.31 cN.cm2").yarn_bending_stiffness_nm2 == \
        pytest.approx(3.1e-7)
    assert _yarn(bending_stiffness_nm2=None).yarn_bending_stiffness_nm2 == 0.0


def test_bad_bending_input_is_refused_by_name():
    with pytest.raises(InputError, match="needs filament_diameter_m"):
        _yarn(filament_diameter_m=None)
    with pytest.raises(InputError, match="yarn.bending_stiffness_nm2"):
        _yarn(bending_stiffness_nm2="-1 N·m2")
    with pytest.raises(InputError, match="bending stiffness unit"):
        _yarn(bending_stiffness_nm2="3 N/m")


def _fabric(n_fibres: int, **kw) -> Fabric:
    spec = _yarn(n_fibres=n_fibres, **kw)
    return Fabric(Weave.plain(), warp=spec, weft=dataclasses.replace(spec, name="weft"),
                  clearance_m=0.05e-3)


@pytest.mark.parametrize("n_fibres, spacing_ratio", [(7, 0.5), (19, 0.5), (7, 0.25)])
def test_the_yarns_rigidity_does_not_depend_on_fibres_or_bead_spacing(n_fibres, spacing_ratio):
    fabric = _fabric(n_fibres)
    model = render_loose(fabric, Discretisation(spacing_ratio=spacing_ratio))
    ei = fabric.specs()["warp"].yarn_bending_stiffness_nm2
    # every inner bead of every fibre bends, with K = (E·I/N)/l0: K·l0 summed over a
    # yarn's fibres gives the yarn's E·I back
    assert len(model.angles) == len(chain_triples(model))
    warp = [t for t in model.fibre_bond_types() if t.family == "warp"]
    angle = next(a for a in model.angle_type_table if a.family == "warp")
    for bt in warp:
        assert n_fibres * angle.coefficient * bt.rest_length_m == pytest.approx(ei, rel=1e-6)


def test_yarn_bending_and_the_discretisation_factor_are_not_both_taken():
    with pytest.raises(InputError, match="keep one"):
        render_loose(_fabric(7), Discretisation(bending_factor=0.01))
    # without either the fibres are strings: no bending term is written
    plain_model = render_loose(_fabric(7, bending_stiffness_nm2=None), Discretisation())
    assert len(plain_model.angles) == 0


def _cantilever_deflection(spacing_ratio: float, tmp_path) -> tuple[float, float, float]:
    """Tip deflection of one clamped chain with the bending term of E·I (its bonds as they
    are, no contact) under a small tip force, by energy minimisation in LAMMPS; the
    discrete chain's closed form (each inner bead a hinge of stiffness E·I/l0) and the
    beam's F·L³/(3·E·I)."""
    chain = parallel_fibres(n=1, length_m=4e-3, diameter_m=0.5e-3, spacing_ratio=spacing_ratio)
    l0 = chain.bond_type_table[0].rest_length_m
    # about the solid fibre's E·A·d²/16: far softer bending than the bonds leaves the
    # minimiser unconverged after millions of steps
    ei = 3e-6
    triples = chain_triples(chain)
    chain = dataclasses.replace(chain, angles=triples,
                                angle_types=np.ones(len(triples), np.int64),
                                angle_type_table=[AngleType(ei / l0, "warp")])
    x = chain.positions[:, 0]
    held = np.flatnonzero(x < 1.5 * l0)  # two beads: a clamp
    tip = np.flatnonzero(x > x.max() - 1e-9)
    length = x.max() - x[held].max()
    force = 1e-3 * 3.0 * ei / length**2  # tip deflection 1e-3 of the length
    deflection = tip_deflection(chain, tmp_path, held, tip, force, max_steps=2_000_000,
                                force_tolerance_n=1e-14)
    # m hinges at L, L - l0, ... l0 from the tip, each turning by F·r·l0/E·I
    m = round(length / l0)
    hinges = force * l0**3 / ei * m * (m + 1) * (2 * m + 1) / 6.0
    return deflection, hinges, force * length**3 / (3.0 * ei)


@pytest.mark.lammps
def test_a_chain_with_the_bending_term_bends_as_the_beam_at_two_spacings(tmp_path):
    coarse, coarse_hinges, beam = _cantilever_deflection(0.5, tmp_path / "coarse")
    fine, fine_hinges, fine_beam = _cantilever_deflection(0.25, tmp_path / "fine")
    # the bending term is E·I/l0 per bead: the chain is its hinges' closed form ...
    assert coarse == pytest.approx(coarse_hinges, rel=0.01)
    assert fine == pytest.approx(fine_hinges, rel=0.01)
    # ... which tends to the beam as the beads are refined (error 1.5·l0/L: 10 %, then 5 %)
    assert abs(fine / fine_beam - 1) == pytest.approx(0.5 * abs(coarse / beam - 1), rel=0.15)
    assert abs(fine / fine_beam - 1) < 0.06


def test_a_scene_gives_the_rigidity_in_words_and_the_build_reports_it(tmp_path):
    import tomllib

    from fabmd.cli.build import build, datasheet_lines
    from fabmd.examples_dir import example_scene
    from fabmd.scenefile import parse_scene

    data = tomllib.loads(example_scene("plain_weave.toml").read_text())
    for fam in ("warp", "weft"):
        data["yarns"][fam].update(filament_diameter_m="17 um",
                                  bending_stiffness_nm2="filaments")
    summary = build(parse_scene(data), tmp_path / "build")
    assert summary["yarn_bending_stiffness_nm2"]["warp"] == pytest.approx(3.11e-7, rel=0.01)
    assert summary["n_angles"] > 0
    assert "yarn bending stiffness E·I: warp, weft 0.311 N·mm²" in datasheet_lines(summary)
    data["yarns"]["warp"]["bending_stiffness_nm2"] = "3 N/m"
    with pytest.raises(InputError, match="bending_stiffness_nm2"):
        parse_scene(data)
    data["yarns"]["warp"]["bending_stiffness_nm2"] = "filament"  # a typo of the word
    with pytest.raises(InputError, match="or the word 'filaments'"):
        parse_scene(data)
