"""Yarn cohesion (fabmd.model.cohesion): which beads are linked, rest shape, and the bending
stiffness of a linked yarn against the composite-beam closed form (a LAMMPS run, seconds)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, Yarn
from fabmd.model.beads import model_critical_time_step_s
from fabmd.model.cohesion import REST_BIN, add_cohesion, close_pairs, cohesion_links
from fabmd.model.transform import cut, tile
from fabmd.results.measure import family_crimp, family_tension_n
from fabmd.scene import blocks
from fabmd.scene.outputs import TrajectoryOutput

from .cantilever import tip_deflection
from .fabrics import parallel_fibres, plain_weave_cell


def _one_yarn(n_fibres=2, length_m=10e-3, diameter_m=0.5e-3) -> BeadModel:
    """``n_fibres`` touching straight fibres in one plane, all of one yarn."""
    model = parallel_fibres(n=n_fibres, length_m=length_m, diameter_m=diameter_m, gap=1.0)
    return dataclasses.replace(model, fibre_yarn=np.ones(n_fibres, np.int64),
                               yarns=[Yarn("warp-0", "warp")])


def test_close_pairs_finds_the_same_pairs_as_brute_force():
    rng = np.random.default_rng(3)
    points = rng.uniform(0, 1e-3, size=(400, 3))
    radius = 1.3e-4
    found = {tuple(p) for p in close_pairs(points, radius).tolist()}
    dist = np.linalg.norm(points[:, None] - points[None], axis=2)
    i, j = np.nonzero(np.triu(dist < radius, k=1))
    assert found == set(zip(i.tolist(), j.tolist(), strict=True))


def test_links_join_touching_fibres_of_one_yarn_only():
    woven = cut(tile(plain_weave_cell(), 3, 3, periodic=False), 4e-3, 4e-3)
    two = _one_yarn(n_fibres=3)
    # two yarns of three fibres side by side, touching: links stay inside each yarn
    pair = dataclasses.replace(_one_yarn(n_fibres=6), fibre_yarn=np.repeat([1, 2], 3),
                               yarns=[Yarn("warp-0", "warp"), Yarn("warp-1", "warp")])
    links = cohesion_links(pair, reach=1.5)
    a, b = links[:, 0], links[:, 1]
    assert (pair.yarn_ids[a] == pair.yarn_ids[b]).all()
    assert (pair.fibre_ids[a] != pair.fibre_ids[b]).all()
    gap = np.linalg.norm(pair.positions[b] - pair.positions[a], axis=1)
    assert gap.max() < 1.5 * pair.diameters.max()
    assert set(pair.fibre_ids[links].ravel().tolist()) == set(range(1, 7))
    # the single-fibre yarns of the test weave have nothing to link
    assert len(cohesion_links(woven)) == 0
    # fibres 1 d apart, beads 0.5 d apart: offsets 0, ±0.5 d, ±1 d along x are within 1.5 d
    per_bead = np.bincount(cohesion_links(two)[:, 0], minlength=two.n_beads)
    first_fibre_inner = np.flatnonzero(two.fibre_ids == 1)[3:-3]
    assert (per_bead[first_fibre_inner] == 5).all()


def test_the_linked_yarn_is_at_rest_and_its_fibres_are_measured_as_before():
    model = _one_yarn(n_fibres=3)
    linked = add_cohesion(model, 0.1)
    cohesion = ~linked.fibre_bond_mask()
    assert cohesion.sum() == len(cohesion_links(model))
    rest = np.array([bt.rest_length_m for bt in linked.bond_type_table])[linked.bond_types - 1]
    misfit = linked.bond_lengths()[cohesion] / rest[cohesion] - 1
    assert np.abs(misfit).max() <= REST_BIN
    for bt in linked.bond_type_table[len(model.bond_type_table):]:
        assert bt.kind == "cohesion"
        assert bt.coefficient == pytest.approx(0.1 * model.bond_type_table[0].coefficient)
    # crimp and fibre tension see the fibre bonds only
    assert family_crimp(linked) == family_crimp(model)
    assert family_tension_n(linked) == family_tension_n(model)
    # the links are stiffness: they shorten the stable time step
    assert model_critical_time_step_s(linked) < model_critical_time_step_s(model)
    # written as harmonic bonds, marked in the input
    assert "cohesion" in blocks.bonds(linked)


def test_a_model_saved_with_links_loads_back_with_them(tmp_path):
    linked = add_cohesion(_one_yarn(), 0.05)
    linked.save(tmp_path, "coupon")
    back = BeadModel.load(tmp_path / "coupon.data", tmp_path / "coupon.json")
    assert (back.fibre_bond_mask() == linked.fibre_bond_mask()).all()
    assert back.bond_type_table == linked.bond_type_table


def test_bad_cohesion_input_is_refused():
    with pytest.raises(InputError, match="cohesion_factor"):
        add_cohesion(_one_yarn(), 0.0)
    with pytest.raises(InputError, match="cohesion_reach"):
        add_cohesion(_one_yarn(), 0.1, reach=5.0)
    with pytest.raises(InputError, match="already has cohesion"):
        add_cohesion(add_cohesion(_one_yarn(), 0.1), 0.1)
    with pytest.raises(InputError, match="periodic"):
        add_cohesion(plain_weave_cell(), 0.1)


def _cantilever_deflection(factor: float, tmp_path) -> tuple[float, float]:
    """Tip deflection of a clamped two-fibre yarn under a small in-plane tip force, by
    energy minimisation in LAMMPS, and the composite-beam value F·L³/(3·E·I)."""
    d = 0.5e-3
    yarn = add_cohesion(_one_yarn(n_fibres=2, length_m=6e-3, diameter_m=d), factor)
    x = yarn.positions[:, 0]
    held = np.flatnonzero(x < 1.25 * d)  # first three beads of each fibre: a clamp
    tip = np.flatnonzero(x > x.max() - 1e-9)
    length = x.max() - x[held].max()
    bt = yarn.bond_type_table[0]
    # two fibres of E·A at ±d/2 from the neutral axis: E·I = 2·E·A·(d/2)²
    ei = 2.0 * (2.0 * bt.coefficient * bt.rest_length_m) * (d / 2) ** 2
    force = 1e-3 * 3.0 * ei / length**2  # tip deflection 1e-3 of the length
    deflection = tip_deflection(yarn, tmp_path, held, tip, force)
    return deflection, force * length**3 / (3.0 * ei)


@pytest.mark.lammps
def test_stiff_links_make_the_yarn_bend_as_a_composite_beam(tmp_path):
    deflection, beam = _cantilever_deflection(1.0, tmp_path / "stiff")
    assert deflection == pytest.approx(beam, rel=0.03)
    # weaker links let the fibres slide against each other: a softer (shear-flexible) yarn
    soft, _ = _cantilever_deflection(0.01, tmp_path / "soft")
    assert soft > 1.03 * deflection


# -- the coupon stage ----------------------------------------------------------------------
def test_the_bias_coupon_of_the_pipeline_links_its_yarns():
    from fabmd.pipeline import TESTS

    assert TESTS["bias-extension"].coupon["cohesion_factor"] > 0
    assert "cohesion_factor" not in TESTS["tension"].coupon


@pytest.mark.lammps
def test_coupon_links_after_its_free_relaxation_and_at_rest_there(tmp_path):
    # two yarns of three touching fibres, a little stretched: cut, they spring back first
    result = _linked_coupon(tmp_path)
    relaxed = result.model
    links = ~relaxed.fibre_bond_mask()
    assert result.summary["cohesion_links"] == int(links.sum()) > 0
    rest = np.array([bt.rest_length_m for bt in relaxed.bond_type_table])[relaxed.bond_types - 1]
    assert np.abs(relaxed.bond_lengths()[links] / rest[links] - 1).max() <= REST_BIN
    # the fibres were unloaded before linking: no stretch held by the links
    fibre_strain = relaxed.bond_lengths()[~links] / rest[~links] - 1
    assert np.abs(fibre_strain).max() < 2e-4


def _linked_coupon(tmp_path):
    """A relaxed coupon of two yarns of three touching fibres, linked."""
    from fabmd.engine import Engine
    from fabmd.protocols.coupon import Coupon
    from fabmd.scene.quasi_static import QuasiStatic

    fabric = dataclasses.replace(_one_yarn(n_fibres=6), fibre_yarn=np.repeat([1, 2], 3),
                                 yarns=[Yarn("warp-0", "warp"), Yarn("warp-1", "warp")])
    fabric = dataclasses.replace(fabric, positions=fabric.positions * [1.002, 1.0, 1.0])
    coupon = Coupon(length_m=6e-3, width_m=2.4e-3, cohesion_factor=0.1, cohesion_reach=2.5,
                    relax=QuasiStatic(max_steps=20_000, check_every=200))
    return coupon.run(fabric, tmp_path / "coupon", engine=Engine(progress=False))


@pytest.mark.lammps
@pytest.mark.mpi
def test_a_linked_coupon_gives_the_same_tension_on_two_mpi_ranks(tmp_path, mpirun):
    """The links reach further than a fibre bond: the ghost cutoff must cover them."""
    from fabmd.engine import Engine
    from fabmd.protocols.tension import Tension

    coupon = _linked_coupon(tmp_path).model
    test = Tension(max_elongation_pct=0.5, trajectory=TrajectoryOutput(frames=0))
    one = test.run(coupon, tmp_path / "one", engine=Engine(backend="standalone"))
    two = test.run(coupon, tmp_path / "two", engine=Engine(backend="standalone", ranks=2))
    assert two.summary["ranks"] == 2
    f1, f2 = one.summary["max_force_n"], two.summary["max_force_n"]
    assert f1 > 0
    assert f2 == pytest.approx(f1, rel=1e-6)


@pytest.mark.lammps
def test_cohesion_on_yarns_of_one_fibre_warns(tmp_path):
    from fabmd.protocols.coupon import Coupon

    single = parallel_fibres(n=3)  # three yarns of one fibre each
    with pytest.warns(UserWarning, match="no effect"):
        Coupon(length_m=6e-3, width_m=1e-3, cohesion_factor=0.1, relax=None).run(
            single, tmp_path / "coupon")


def test_a_picture_frame_preload_shrinks_the_fibres_not_the_links():
    from fabmd.protocols.picture_frame import PictureFrame

    square = add_cohesion(_one_yarn(n_fibres=6, length_m=2.5e-3), 0.1)  # 3 x 3 mm of beads
    prepared = PictureFrame(pretension_strain=0.01).prepare(square)
    preloaded = set(PictureFrame(pretension_strain=0.01).preload_types(prepared))
    assert preloaded
    kinds = {prepared.bond_type_table[t - 1].kind for t in preloaded}
    assert kinds == {"fibre"}
    links = ~prepared.fibre_bond_mask()
    assert not set(prepared.bond_types[links].tolist()) & preloaded
