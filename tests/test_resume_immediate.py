"""A resumed input keeps the values its immediate variables got in the interrupted run
(``variable t0 equal $(time)``): replaying ``$(time)`` at the checkpoint moved a
compaction's platen back to its start (the time origin of its loading) — and the values its
``internal`` variables had (a ``fix controller`` integrates the compaction platen's travel
and the adaptive boundaries' in one), which the restart file does not hold."""

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.engine.checkpoint import CheckpointState, immediate_variables, resume_commands
from fabmd.results.folder import read_print_file

DATA = """one atom

1 atoms
1 atom types

0 1 xlo xhi
0 1 ylo yhi
0 1 zlo zhi

Masses

1 1.0

Atoms # atomic

1 1 0.5 0.5 0.5

Velocities

1 0.001 0 0
"""

INPUT = """units si
atom_style atomic
boundary p p p
read_data one.data
timestep 0.01
fix nve all nve
variable travel internal 0.0
variable speed equal 2.0
fix integrate all controller 1 1.0 1.0 0.0 0.0 v_speed 0.0 travel
run 100
variable t0 equal $(time:%.15g)
variable since equal "time-v_t0"
fix out all print 10 "$(step) ${since} $(v_travel:%.15g)" file since.dat screen no &
    title "# step since_s travel_m"
run 200
"""


def test_immediate_variables_are_replayed_with_their_frozen_values():
    commands = ["variable a equal 1.0", "variable t0 equal $(time:%.15g)",
                "variable s equal \"time-v_t0\"", "run 10"]
    assert immediate_variables(commands) == ["t0"]
    state = CheckpointState("in.x", 3, 0, 10, 5, 5, frozen_variables={"t0": 1.25})
    out = resume_commands(commands, state)
    assert out[1].split() == ["variable", "t0", "equal", "1.25"]
    assert out[0] == commands[0] and out[2] == commands[2]
    # an internal variable (a fix changes it) is replayed with its value at the checkpoint
    with_internal = ["variable x internal 0.0"] + commands
    assert immediate_variables(with_internal) == ["x", "t0"]
    state = CheckpointState("in.x", 4, 0, 10, 5, 5, frozen_variables={"x": -0.5, "t0": 1.25})
    assert resume_commands(with_internal, state)[0].split() == ["variable", "x", "internal",
                                                                "-0.5"]
    # an old checkpoint (no frozen values) replays the command as written
    state.frozen_variables = None
    assert resume_commands(commands, state)[1] == commands[1]


class StopAfter:
    """A monitor that interrupts the run (like Ctrl-C) after ``after`` calls."""

    def __init__(self, after: int):
        self.after, self.calls = after, 0

    def __call__(self, lmp):
        self.calls += 1
        if self.calls == self.after:
            raise KeyboardInterrupt


@pytest.mark.lammps
def test_resumed_run_keeps_the_time_origin(tmp_path):
    engine = Engine(progress=False, checkpoint_every=1)
    for name in ("whole", "cut"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "in.test").write_text(INPUT)
        (tmp_path / name / "one.data").write_text(DATA)
    engine.run(tmp_path / "whole", "in.test", monitor=lambda lmp: None, monitor_every=20)
    with pytest.raises(KeyboardInterrupt):  # in the second run (after the first's 5 calls)
        engine.run(tmp_path / "cut", "in.test", monitor=StopAfter(9), monitor_every=20)
    engine.run(tmp_path / "cut", "in.test", monitor=lambda lmp: None, monitor_every=20,
               resume=True)
    whole = read_print_file(tmp_path / "whole" / "since.dat")
    cut = read_print_file(tmp_path / "cut" / "since.dat")
    np.testing.assert_array_equal(cut["step"], whole["step"])
    np.testing.assert_allclose(cut["since_s"], whole["since_s"], rtol=0, atol=1e-12)
    assert whole["since_s"][-1] == pytest.approx(2.0)
    # the integrated travel goes on from where it was (-dt * speed each step: -6 m by 300)
    np.testing.assert_allclose(cut["travel_m"], whole["travel_m"], rtol=0, atol=1e-12)
    assert whole["travel_m"][-1] == pytest.approx(-6.0)
