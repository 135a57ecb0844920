"""SIGTERM / SIGINT become a stop request while a run is guarded (no LAMMPS)."""

import os
import signal

import pytest

from fabmd.engine import interrupt
from fabmd.errors import FabmdError, RunInterrupted


def test_signals_are_requests_while_guarded_and_restored_after():
    before = signal.getsignal(signal.SIGTERM)
    with interrupt.catching():
        assert not interrupt.stop_requested()
        os.kill(os.getpid(), signal.SIGTERM)  # the handler runs before the next line
        assert interrupt.received() == "SIGTERM" and interrupt.stop_requested()
        with interrupt.catching():  # nested (the engine inside the pipeline): still set
            assert interrupt.stop_requested()
        assert interrupt.stop_requested()
    assert signal.getsignal(signal.SIGTERM) is before
    assert interrupt.received() is None


def test_a_second_ctrl_c_stops_at_once():
    with interrupt.catching():
        os.kill(os.getpid(), signal.SIGINT)
        assert interrupt.received() == "SIGINT"
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)


def test_run_interrupted_is_a_fabmd_error_with_exit_code_5(tmp_path):
    exc = RunInterrupted("stopped", run_dir=tmp_path, step=42)
    assert isinstance(exc, FabmdError) and exc.exit_code == 5
    assert exc.run_dir == tmp_path and exc.step == 42
