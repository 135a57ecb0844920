"""The few MPI calls fabmd's Python side needs, through ctypes on MPICH.

Under ``mpirun`` every rank runs the same Python program and drives one LAMMPS
instance on MPI_COMM_WORLD. Only rank 0 writes files and prints; the rank-0
decisions other ranks must share (the run folder's path, an error) are
broadcast. Outside ``mpirun`` nothing here touches MPI.
"""

from __future__ import annotations

import atexit
import ctypes
import functools
import os

from .library import preload_mpi

# MPICH ABI handles (mpi.h of MPICH 3/4/5)
_MPI_COMM_WORLD = 0x44000000
_MPI_BYTE = 0x4C00010D
_MPI_INT = 0x4C000405
_MPI_DOUBLE = 0x4C00080B
_MPI_SUM = 0x58000003
_MPI_THREAD_FUNNELED = 1


def launched_by_mpirun() -> bool:
    """True when this process was started by an MPI launcher with more than one rank."""
    for var in ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "MPI_LOCALNRANKS"):
        if var in os.environ:
            try:
                return int(os.environ[var]) > 1
            except ValueError:
                return False
    return False


@functools.cache
def _lib():
    if not launched_by_mpirun():
        return None
    path = preload_mpi()
    lib = ctypes.CDLL(str(path) if path else "libmpi.so.12", mode=ctypes.RTLD_GLOBAL)
    flag = ctypes.c_int(0)
    lib.MPI_Initialized(ctypes.byref(flag))
    if not flag.value:
        provided = ctypes.c_int(0)
        lib.MPI_Init_thread(None, None, _MPI_THREAD_FUNNELED, ctypes.byref(provided))
        atexit.register(_finalize, lib)
    return lib


def _finalize(lib) -> None:
    flag = ctypes.c_int(0)
    lib.MPI_Finalized(ctypes.byref(flag))
    if not flag.value:
        lib.MPI_Finalize()


def rank() -> int:
    """This process's rank in MPI_COMM_WORLD (0 outside mpirun)."""
    lib = _lib()
    if lib is None:
        return 0
    r = ctypes.c_int(0)
    lib.MPI_Comm_rank(_MPI_COMM_WORLD, ctypes.byref(r))
    return r.value


def size() -> int:
    """Number of ranks (1 outside mpirun)."""
    lib = _lib()
    if lib is None:
        return 1
    s = ctypes.c_int(1)
    lib.MPI_Comm_size(_MPI_COMM_WORLD, ctypes.byref(s))
    return s.value


def is_root() -> bool:
    """True on rank 0: the rank that writes files and prints."""
    return rank() == 0


def barrier() -> None:
    """Wait for every rank (no-op outside mpirun)."""
    lib = _lib()
    if lib is not None:
        lib.MPI_Barrier(_MPI_COMM_WORLD)


def bcast_json(obj):
    """Rank 0's JSON-able ``obj`` on every rank."""
    import json

    return json.loads(bcast_text(json.dumps(obj, default=str) if rank() == 0 else ""))


def bcast_text(text: str | None) -> str:
    """Rank 0's ``text`` on every rank (identity outside mpirun)."""
    lib = _lib()
    if lib is None:
        return text or ""
    data = (text or "").encode() if rank() == 0 else b""
    n = ctypes.c_int(len(data))
    lib.MPI_Bcast(ctypes.byref(n), 1, _MPI_INT, 0, _MPI_COMM_WORLD)
    buf = ctypes.create_string_buffer(data, n.value) if rank() == 0 else \
        ctypes.create_string_buffer(n.value)
    if n.value:
        lib.MPI_Bcast(buf, n.value, _MPI_BYTE, 0, _MPI_COMM_WORLD)
    return buf.raw[: n.value].decode()


def allreduce_sum(values):
    """Element-wise sum over ranks of a float sequence (identity outside mpirun)."""
    lib = _lib()
    data = [float(v) for v in values]
    if lib is None:
        return data
    n = len(data)
    send = (ctypes.c_double * n)(*data)
    recv = (ctypes.c_double * n)()
    lib.MPI_Allreduce(send, recv, n, _MPI_DOUBLE, _MPI_SUM, _MPI_COMM_WORLD)
    return list(recv)
