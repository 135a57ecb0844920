"""The release of the weaving tension: a crimped periodic cell, taken off the loom, shortens
until its yarns carry only the handling tension (seconds)."""

import dataclasses

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.protocols.crimp import Crimp, load_crimped
from fabmd.protocols.release import Release
from fabmd.results.yarn_tension import yarn_tension

from .fabrics import plain_weave_cell

HANDLING_N = 0.2  # N per (single-fibre) yarn


def test_release_refuses_bad_settings():
    with pytest.raises(InputError, match="release.tolerance"):
        Release(tolerance=0.0)
    with pytest.raises(InputError, match="release.time_constant_transits"):
        Release(time_constant_transits=-1)
    with pytest.raises(InputError, match="release.handling_tension"):
        Release(handling_tension="-1 N")
    with pytest.raises(InputError, match="crimp.release_tension must be true or false"):
        Crimp(release_tension="yes")
    with pytest.raises(InputError, match="crimp.handling_tension"):
        Crimp(release_tension=True, handling_tension="lots")


def test_release_needs_the_periodic_cell():
    piece = plain_weave_cell(spacing_m=1e-3, gap=1.0, periodic=False)
    with pytest.raises(InputError, match="needs the periodic cell"):
        Release().input_text(piece)
    with pytest.raises(InputError, match="needs the periodic cell"):
        Crimp(release_tension=True, handling_tension="0.2 N").check_model(piece)


def test_membrane_target_is_each_yarns_tension_over_the_side_across_it():
    """Two warp yarns along x in a cell ly high: N_xx = 2 T / ly; the weft alike in y."""
    cell = plain_weave_cell(spacing_m=1e-3, gap=1.0)
    lx, ly = (cell.box_hi - cell.box_lo)[:2]
    nxx, nyy = Release(handling_tension={"warp": "0.2 N", "weft": "0.5 N"}) \
        .membrane_target_n_m(cell)
    assert nxx == pytest.approx(2 * 0.2 / ly, rel=1e-12)
    assert nyy == pytest.approx(2 * 0.5 / lx, rel=1e-12)


@pytest.fixture(scope="module")
def released(tmp_path_factory):
    """The cell crimped taut (yarns shrunk 2 %), then released to the handling tension."""
    out = tmp_path_factory.mktemp("released") / "crimp"
    crimp = Crimp(expansion={"warp": -0.02, "weft": -0.02}, release_tension=True,
                  handling_tension=f"{HANDLING_N} N")
    return crimp.run(plain_weave_cell(spacing_m=1e-3, gap=1.0), out,
                     engine=Engine(progress=False))


@pytest.mark.lammps
def test_a_released_cell_shortens_to_the_handling_tension(released):
    s = released.summary
    rel = s["released"]
    assert rel["settled"], rel["stop"]
    # the cell shortened in x and y, and the stage's model is the released one
    assert all(-5 < e < -0.05 for e in rel["strain_pct"]), rel
    size = (released.model.box_hi - released.model.box_lo)[:2]
    assert size.tolist() == pytest.approx(rel["cell_after_m"], rel=1e-9)
    assert load_crimped(released.run_dir).box_hi.tolist() == \
        pytest.approx(released.model.box_hi.tolist(), rel=1e-12)
    # the weaving tension is kept as what the crimp was at; the released yarns carry the
    # handling tension, far less (their mean within the release's tolerance of it, plus
    # what the contacts carry)
    woven_n = s["yarn_tension"]["warp"]["yarn_n"]
    got = yarn_tension(released.model)
    assert woven_n > 5 * HANDLING_N, woven_n
    for fam in ("warp", "weft"):
        assert got[fam]["yarn_n"] == pytest.approx(HANDLING_N, rel=0.5), got[fam]
    target = rel["membrane_force_target_n_m"]
    assert target[0] == pytest.approx(2 * HANDLING_N / rel["cell_before_m"][1], rel=1e-9)
    for left, want in zip(rel["membrane_force_left_n_m"], target, strict=True):
        assert abs(left - want) < 0.06 * want, (left, want)  # tolerance 5 %
    # the crimp's measures are the released cell's, the woven ones kept beside them
    assert s["crimped"]["crimp_pct"]["warp"] > s["woven"]["crimp_pct"]["warp"]
    assert (released.run_dir / "release" / "released.data").exists()


@pytest.mark.lammps
def test_the_released_state_does_not_depend_on_the_release_time_constant(released, tmp_path):
    """Berendsen's time constant is numerical: three times slower, the same released cell
    (strain within 5 % of itself), because the release ends at a stated tension."""
    woven = load_crimped_woven(released.run_dir)
    slow = Release(handling_tension=f"{HANDLING_N} N", time_constant_transits=150).run(
        woven, tmp_path / "slow", engine=Engine(progress=False))
    fast = released.summary["released"]["strain_pct"]
    for a, b in zip(slow.summary["strain_pct"], fast, strict=True):
        assert a == pytest.approx(b, rel=0.05), (slow.summary["strain_pct"], fast)


def load_crimped_woven(run_dir):
    """The woven (taut) cell of a released crimp folder: ``crimped.data`` itself."""
    from fabmd.model.bead_model import BeadModel

    return BeadModel.load(run_dir / "crimped.data", run_dir / "crimped.json")


def test_crimp_release_fields_reach_the_release_stage():
    crimp = Crimp(release_tension=True, handling_tension="0.3 N")
    stage = crimp.release_stage()
    assert stage.handling_tension == "0.3 N" and stage.contact == crimp.contact
    assert dataclasses.replace(crimp, release_tension=False).release_tension is False
    assert np.isfinite(Release().tolerance)
