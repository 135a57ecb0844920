"""Deliberately unstable runs are caught at once, named, and leave no curve behind."""

import json

import pytest

from fabmd.engine import Engine
from fabmd.errors import UnstableRun
from fabmd.model.beads import TimeStep, model_bead_parameters
from fabmd.model.contact import ContactModel
from fabmd.protocols.crimp import Crimp
from fabmd.protocols.fibre_tension import FibreTension
from fabmd.protocols.tension import Tension

from .fabrics import plain_weave_cell

pytestmark = pytest.mark.lammps

CAUSES = {"speed", "bond_stretch", "nan", "lost_atoms", "overlap", "runaway_atom"}


def assert_caught_without_curve(err, run_dir):
    assert err.value.cause in CAUSES
    assert "Likely cause and fix" in str(err.value)
    assert not (run_dir / "curve.csv").exists()
    assert not (run_dir / "summary.json").exists()
    failure = json.loads((run_dir / "failure.json").read_text())
    assert failure["cause"] == err.value.cause


@pytest.mark.parametrize("factor", [1.5, 3.0])
def test_time_step_above_critical_is_caught(tmp_path, factor):
    test = FibreTension(length_m=3e-3, time_step=TimeStep(factor=factor, check=False),
                        speed_fraction=1e-3)
    with pytest.raises(UnstableRun) as err:
        test.run(tmp_path / "run", engine=Engine(progress=False))
    assert_caught_without_curve(err, tmp_path / "run")
    assert err.value.step is None or err.value.step < test.steps


def test_contact_stiffer_than_the_time_step_allows_is_caught(tmp_path):
    """Stiffness contrast: a contact 500x the bond spring with a bond-only time step."""
    loose = plain_weave_cell()
    bond_only = min(b.critical_time_step_s() for b in model_bead_parameters(loose))
    crimp = Crimp(expansion={"warp": -0.1, "weft": -0.1},
                  contact=ContactModel(stiffness_factor=500.0),
                  time_step=TimeStep(value_s=0.25 * bond_only, check=False))
    with pytest.raises(UnstableRun) as err:
        crimp.run(loose, tmp_path / "run", engine=Engine(progress=False))
    assert err.value.cause in CAUSES
    # the same contact with fabmd's own time step (which sees the contact) is stable
    fine = Crimp(expansion={"warp": -0.1, "weft": -0.1},
                 contact=ContactModel(stiffness_factor=500.0))
    assert fine.run(loose, tmp_path / "ok", engine=Engine(progress=False)).summary["steps"] > 0


def test_unstable_tension_writes_no_curve(tmp_path, woven_coupon):
    test = Tension(time_step=TimeStep(factor=4.0, check=False), max_elongation_pct=1.0)
    with pytest.raises(UnstableRun) as err:
        test.run(woven_coupon.model, tmp_path / "run", engine=Engine(progress=False))
    assert_caught_without_curve(err, tmp_path / "run")
