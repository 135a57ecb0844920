"""Which MPI binding fabmd uses (mpi4py where importable, the MPICH ctypes fallback
otherwise), and that a stop signal seen by one rank stops every rank. No LAMMPS, no
mpirun: the bindings are stood in for."""

import numpy as np
import pytest

from fabmd.engine import interrupt, mpi
from fabmd.errors import EngineUnavailable


class FakeComm:
    """One rank of a world of ``size``; the other ranks contribute ``others`` to sums."""

    def __init__(self, size=3, others=(0.0,)):
        self._size, self.others = size, np.asarray(others, float)

    def Get_rank(self):  # noqa: N802 - mpi4py's names
        return 0

    def Get_size(self):  # noqa: N802
        return self._size

    def Barrier(self):  # noqa: N802
        pass

    def bcast(self, data, root=0):
        return data

    def Allreduce(self, send, recv, op=None):  # noqa: N802
        assert op == "SUM"
        recv[...] = send + self.others


class FakeMPI:
    SUM = "SUM"

    def __init__(self, comm):
        self.COMM_WORLD = comm


@pytest.fixture
def under_mpirun(monkeypatch):
    """As if started by ``mpirun -np 3`` of Open MPI (whose handles the fallback lacks)."""
    for var in ("PMI_SIZE", "MV2_COMM_WORLD_SIZE", "MPI_LOCALNRANKS", "PMIX_SIZE",
                "FABMD_MPI"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "3")
    monkeypatch.setattr(mpi, "_load_ctypes", lambda: "ctypes-binding")
    mpi._binding.cache_clear()
    yield monkeypatch
    mpi._binding.cache_clear()


def test_outside_mpirun_nothing_touches_mpi(monkeypatch):
    for var in mpi._SIZE_VARIABLES:
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setattr(mpi, "_import_mpi4py", lambda: pytest.fail("imported mpi4py"))
    assert mpi.select_binding() is None
    monkeypatch.setenv("PMI_SIZE", "1")  # one rank: no MPI either
    assert mpi.select_binding() is None


def test_mpi4py_is_used_where_importable(under_mpirun):
    comm = FakeComm(size=3, others=[1.0, 2.0])
    under_mpirun.setattr(mpi, "_import_mpi4py", lambda: FakeMPI(comm))
    assert mpi.binding() == "mpi4py"
    assert mpi.size() == 3 and mpi.rank() == 0 and mpi.is_root()
    assert mpi.bcast_json({"run": "folder"}) == {"run": "folder"}
    assert mpi.allreduce_sum([0.5, 0.25]) == [1.5, 2.25]


def test_ctypes_fallback_without_mpi4py_or_when_asked(under_mpirun):
    under_mpirun.setattr(mpi, "_import_mpi4py", lambda: None)
    assert mpi.select_binding() == "ctypes-binding"
    under_mpirun.setattr(mpi, "_import_mpi4py", lambda: FakeMPI(FakeComm()))
    under_mpirun.setenv("FABMD_MPI", "ctypes")
    assert mpi.select_binding() == "ctypes-binding"


def test_asking_for_a_binding_that_is_missing_or_unknown_is_a_clear_error(under_mpirun):
    under_mpirun.setattr(mpi, "_import_mpi4py", lambda: None)
    under_mpirun.setenv("FABMD_MPI", "mpi4py")
    with pytest.raises(EngineUnavailable, match="pip install mpi4py"):
        mpi.select_binding()
    under_mpirun.setenv("FABMD_MPI", "openmpi")
    with pytest.raises(EngineUnavailable, match="FABMD_MPI must be one of mpi4py, ctypes"):
        mpi.select_binding()


def test_a_signal_seen_by_another_rank_stops_this_one(under_mpirun):
    """Launchers may signal rank 0 only: every rank sums the stop flags at the chunk
    boundary, so all stop (and write the checkpoint) together."""
    comm = FakeComm(size=2, others=[0.0])
    under_mpirun.setattr(mpi, "_import_mpi4py", lambda: FakeMPI(comm))
    with interrupt.catching():
        assert not interrupt.stop_requested()
        comm.others = np.array([1.0])  # rank 1 got SIGTERM, this rank did not
        assert interrupt.received() is None and interrupt.stop_requested()
