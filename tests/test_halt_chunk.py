"""A ``fix halt ... error continue`` ends its run wherever it fires: mid-chunk and on the
last step of one of the in-process engine's chunks alike, and as plain ``lmp -in`` does."""

import subprocess
import sys
import warnings

import pytest

from fabmd.engine import Engine
from fabmd.engine.inprocess import run_inprocess

from .conftest import clean_env

pytestmark = pytest.mark.lammps

CHECK = 10  # steps between the halt's checks
RUN = 100  # steps the halted run asks for
AGAIN = 30  # steps of the run after it

INPUT = """units           lj
atom_style      atomic
region          box block 0 4 0 4 0 4
create_box      1 box
create_atoms    1 single 1 1 1
mass            1 1.0
pair_style      zero 1.0
pair_coeff      * *
fix             nve all nve
variable        s equal step
fix             h all halt {check} v_s >= {threshold} error continue message {message}
run             {run}
print           "$(step)" file halted.txt screen no
run             {again}
print           "$(step)" file end.txt screen no
"""


def first_check_at_or_after(threshold: int) -> int:
    """The step on which the halt fires: its first check (a multiple of CHECK) >= threshold."""
    return -(-threshold // CHECK) * CHECK


def write_input(folder, threshold: int, message: str = "yes") -> None:
    folder.mkdir()
    (folder / "in.halt").write_text(INPUT.format(check=CHECK, threshold=threshold,
                                                 message=message, run=RUN, again=AGAIN))


def steps_in(folder, name: str) -> int:
    return int(float((folder / name).read_text()))


class Count:
    """A monitor: makes the engine run chunks of ``monitor_every`` steps."""

    def __init__(self):
        self.calls = 0

    def __call__(self, lmp):
        self.calls += 1


# chunks of 20 steps: the halt at 20 and 40 falls on a chunk's last step, the one at 30
# inside a chunk
@pytest.mark.parametrize("threshold", [20, 30, 40])
def test_inprocess_halt_ends_the_run_wherever_it_falls(tmp_path, threshold):
    write_input(tmp_path / "r", threshold)
    done = run_inprocess(tmp_path / "r", "in.halt", monitor=Count(), monitor_every=20)
    halt = first_check_at_or_after(threshold)
    assert steps_in(tmp_path / "r", "halted.txt") == halt
    # the next run goes on; the condition still holds, so it stops at its first check
    assert steps_in(tmp_path / "r", "end.txt") == halt + CHECK
    assert done == halt + CHECK


@pytest.mark.parametrize("threshold", [20, 30])
def test_standalone_and_inprocess_stop_on_the_same_step(tmp_path, threshold):
    for backend in ("inprocess", "standalone"):
        write_input(tmp_path / backend, threshold)
        Engine(backend=backend, progress=False).run(
            tmp_path / backend, "in.halt", monitor=Count() if backend == "inprocess" else None,
            monitor_every=20 if backend == "inprocess" else None)
    for name in ("halted.txt", "end.txt"):
        assert steps_in(tmp_path / "inprocess", name) == steps_in(tmp_path / "standalone", name)


def test_silent_continue_halt_is_warned_about(tmp_path):
    write_input(tmp_path / "r", 30, message="no")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run_inprocess(tmp_path / "r", "in.halt")
    assert any("message no" in str(w.message) for w in caught)


@pytest.mark.mpi
def test_halt_on_a_chunk_end_stops_every_mpi_rank(tmp_path, mpirun):
    # the log (rank 0) tells the halt; every rank must skip the rest of the run alike
    write_input(tmp_path / "r", 20)
    # each rank writes its own file (two ranks' prints interleave on mpirun's stdout)
    code = ("import sys, pathlib; from fabmd.engine import mpi; "
            "from fabmd.engine.inprocess import run_inprocess; "
            "done = run_inprocess(sys.argv[1], 'in.halt', monitor=lambda lmp: None, "
            "monitor_every=20); "
            "pathlib.Path(sys.argv[1], f'done.{mpi.rank()}').write_text(str(done))")
    out = subprocess.run([str(mpirun), "-np", "2", sys.executable, "-c", code,
                          str(tmp_path / "r")], capture_output=True, text=True,
                         env=clean_env(), timeout=120)
    assert out.returncode == 0, out.stderr
    halt = first_check_at_or_after(20)
    done = [(tmp_path / "r" / f"done.{rank}").read_text() for rank in (0, 1)]
    assert done == [f"{halt + CHECK}"] * 2  # both ranks ran the same steps
    assert steps_in(tmp_path / "r", "halted.txt") == halt
