"""Long runs survive interruption: a resumed run equals an uninterrupted one."""

import h5py
import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.engine.checkpoint import has_checkpoint
from fabmd.errors import InputError
from fabmd.protocols.tension import Tension
from fabmd.results.trajectory import read_lengths
from fabmd.scene.energy import ContactPower

from .fabrics import plain_weave_cell

pytestmark = pytest.mark.lammps


class Interrupt(ContactPower):
    """A contact monitor that stops the run (like Ctrl-C) after some chunks."""

    def __init__(self, after: int):
        super().__init__()
        self.after = after

    def __call__(self, lmp):
        super().__call__(lmp)
        if len(self.steps) == self.after:
            raise KeyboardInterrupt


def test_resume_equals_uninterrupted_run(tmp_path, woven_coupon):
    coupon = woven_coupon.model
    test = Tension(max_elongation_pct=2.0, samples=40)
    engine = Engine(progress=False, checkpoint_every=1)
    whole = test.run(coupon, tmp_path / "whole", engine=engine)
    with pytest.raises(KeyboardInterrupt):
        test.run(coupon, tmp_path / "cut", engine=engine, monitor=Interrupt(after=25))
    assert has_checkpoint(tmp_path / "cut")
    # resumed in this process, its pair style cannot get the interrupted one's number back:
    # the contact history starts afresh, with a warning (a new process restores it exactly,
    # tests/test_interrupt.py)
    with pytest.warns(UserWarning, match="contact history"):
        resumed = test.run(coupon, tmp_path / "cut", engine=engine, resume=True)
    a, b = whole.curve, resumed.curve
    assert len(a["force_n"]) == len(b["force_n"])
    np.testing.assert_allclose(b["elongation_pct"], a["elongation_pct"], rtol=1e-9)
    # close: only the contact history restarted (the chunks are set up anew in both runs)
    np.testing.assert_allclose(b["force_n"], a["force_n"], rtol=1e-5,
                               atol=1e-6 * np.abs(a["force_n"]).max())
    eb_whole, eb_resumed = whole.summary["energy_balance"], resumed.summary["energy_balance"]
    assert eb_whole["contact_work_j"] != 0  # contacts work: their history was restored too
    # sampled contact power is noisy (stick-slip): compare on the scale of the balance
    assert eb_resumed["contact_work_j"] == pytest.approx(
        eb_whole["contact_work_j"], abs=1e-4 * eb_whole["external_work_j"])
    assert eb_resumed["relative_error"] == pytest.approx(eb_whole["relative_error"], abs=1e-4)
    # the trajectory goes on from the checkpoint (dumps cut back, then appended): every
    # frame once, as in the whole run
    assert resumed.summary["trajectory"] == "trajectory.h5"
    with h5py.File(whole.run_dir / "trajectory.h5") as fw, \
            h5py.File(resumed.run_dir / "trajectory.h5") as fr:
        steps = fw["particles/all/position/step"][()]
        np.testing.assert_array_equal(fr["particles/all/position/step"][()], steps)
        assert len(steps) > 5 and np.all(np.diff(steps) > 0)
        # equal to round-off grown by friction (as the forces above): a thousandth of d
        np.testing.assert_allclose(read_lengths(fr["particles/all/position/value"]),
                                   read_lengths(fw["particles/all/position/value"]),
                                   atol=1e-3 * float(coupon.diameters.max()))
        forces = fw["observables/bond_force/value"][()]
        np.testing.assert_allclose(fr["observables/bond_force/value"][()], forces,
                                   atol=1e-3 * np.nanmax(np.abs(forces)))


def test_resume_without_checkpoint_is_a_clear_error(tmp_path):
    with pytest.raises(InputError, match="nothing to resume"):
        Tension().run(plain_weave_cell(periodic=False), tmp_path / "none", resume=True)
