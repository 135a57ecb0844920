"""Yarn tension after crimp (N per yarn and cN/tex) against the closed form T = E·A·ε of
straight fibres held at a strain ε."""

import dataclasses
import math

import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.bead_model import Yarn
from fabmd.protocols.crimp import Crimp
from fabmd.results.yarn_tension import tension_line, yarn_tension

from .fabrics import SOFT_GLASS, parallel_fibres

DIAMETER = 0.5e-3
EA = SOFT_GLASS.modulus_pa * math.pi * DIAMETER**2 / 4  # axial stiffness of one fibre [N]


def stretched(strain, model=None):
    """Parallel straight fibres stretched uniformly along x by ``strain``."""
    model = model or parallel_fibres(diameter_m=DIAMETER)
    positions = model.positions.copy()
    positions[:, 0] *= 1 + strain
    return dataclasses.replace(model, positions=positions)


def test_a_stretched_fibre_carries_e_a_strain():
    t = yarn_tension(stretched(0.01))["warp"]
    assert t["fibre_n"] == pytest.approx(EA * 0.01, rel=1e-9)
    assert t["yarn_n"] == pytest.approx(EA * 0.01, rel=1e-9)  # one fibre per yarn
    assert t["cn_per_tex"] is None  # no linear density known
    assert t["yarns"] == 4


def test_a_yarn_carries_the_sum_of_its_fibres_and_cn_per_tex_follows_the_tex():
    base = parallel_fibres(diameter_m=DIAMETER)
    two_per_yarn = dataclasses.replace(
        base, fibre_yarn=[1, 1, 2, 2], yarns=[Yarn("warp-0", "warp"), Yarn("warp-1", "warp")],
        info={"families": {"warp": {"linear_density_tex": 68.0}}})
    t = yarn_tension(stretched(0.002, two_per_yarn))["warp"]
    assert t["yarn_n"] == pytest.approx(2 * EA * 0.002, rel=1e-9)
    assert t["cn_per_tex"] == pytest.approx(100 * 2 * EA * 0.002 / 68.0, rel=1e-9)
    assert "cN/tex" in tension_line({"warp": t})
    slack = yarn_tension(two_per_yarn)["warp"]
    assert abs(slack["yarn_n"]) < 1e-9 * EA


@pytest.mark.lammps
def test_crimp_reports_the_tension_of_fibres_held_at_their_ends(tmp_path):
    # shrink the rest length by 1 % with the ends held: the straight fibres carry E·A·1 %
    result = Crimp(expansion={"warp": -0.01}).run(parallel_fibres(diameter_m=DIAMETER),
                                                   tmp_path / "crimp",
                                                   engine=Engine(progress=False))
    assert result.summary["quasi_static"]
    t = result.summary["yarn_tension"]["warp"]
    assert t["yarn_n"] == pytest.approx(EA * 0.01, rel=0.01)
    assert t["yarn_max_n"] - t["yarn_min_n"] < 0.01 * t["yarn_n"]


def test_bad_target_tensions_are_refused_before_lammps(tmp_path):
    with pytest.raises(InputError, match="crimp.target_tension"):
        Crimp(target_tension="3 furlongs")
    with pytest.raises(InputError, match="must be > 0"):
        Crimp(target_tension={"warp": "-1 cN/tex"})
    with pytest.raises(InputError, match="linear density"):  # the model has no tex
        Crimp(target_tension="1 cN/tex").run(parallel_fibres(), tmp_path / "c")
    assert not (tmp_path / "c").exists()


@pytest.mark.lammps
def test_crimp_reaches_a_target_tension(tmp_path):
    # straight fibres held at their ends carry T = -E·A·e for a rest-length change e: the
    # search must land on e = -T/(E·A) from a start at -1 %
    target = 0.4 * EA * 0.01
    result = Crimp(expansion={"warp": -0.01}, target_tension=f"{target} N").run(
        parallel_fibres(diameter_m=DIAMETER), tmp_path / "crimp", engine=Engine(progress=False))
    search = result.summary["tension_search"]
    assert search["reached"] and len(search["runs"]) <= 3
    assert result.summary["yarn_tension"]["warp"]["yarn_n"] == pytest.approx(target, rel=0.05)
    assert result.summary["expansion"]["warp"] == pytest.approx(-0.004, rel=0.05)
