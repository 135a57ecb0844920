"""fabmd — a virtual testing lab for dry textile reinforcements.

Woven fabrics are modelled as bundles of virtual fibres (bead chains in
LAMMPS): geometry → bead model → LAMMPS scene → protocol → results.

Quick start::

    import fabmd

    scene = fabmd.load_scene("examples/plain_weave.toml")     # a validated fabmd.Scene
    summary = fabmd.run_test(scene, "tension", "runs/t", engine=fabmd.Engine())
    u = fabmd.load("runs/t/tension")                          # an MDAnalysis Universe (SI)

The names below are the public API; everything else is reached through its module
(``fabmd.protocols.fibre_tension.FibreTension``, ``fabmd.analysis`` ...). The heavy
ones (``Scene``, ``load_scene``, ``run_test``, ``Engine``, ``load``, ``__version__``) are
imported when first used, so ``import fabmd`` stays light. Importing fabmd makes
``import lammps`` work without ``LD_LIBRARY_PATH``.
"""

from __future__ import annotations

from .engine.library import preload_mpi as _preload_mpi
from .errors import (
    EngineUnavailable,
    FabmdError,
    InputError,
    NotQuasiStatic,
    OutputExists,
    OverlapWarning,
    QuasiStaticWarning,
    RunInterrupted,
    SimulationFailed,
    UnstableRun,
)

_preload_mpi()

#: public name → the module that defines it (imported on first use)
_LAZY = {
    "Scene": "fabmd.scenefile",
    "load_scene": "fabmd.scenefile",
    "run_test": "fabmd.pipeline",
    "Engine": "fabmd.engine",
    "EngineResult": "fabmd.engine",
    "load": "fabmd.results.universe",
    "__version__": "fabmd.version",  # package metadata: read when asked for
}

__all__ = [
    # a scene, its run, its results
    "Scene",
    "load_scene",
    "run_test",
    "Engine",
    "EngineResult",
    "load",
    # errors (fabmd.errors; the CLI's exit status is each class's exit_code)
    "FabmdError",
    "InputError",
    "EngineUnavailable",
    "OutputExists",
    "SimulationFailed",
    "UnstableRun",
    "NotQuasiStatic",
    "RunInterrupted",
    # warnings
    "OverlapWarning",
    "QuasiStaticWarning",
    "__version__",
]


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value  # the next lookup does not come here
        return value
    raise AttributeError(f"module 'fabmd' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
