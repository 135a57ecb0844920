"""The LAMMPS engine: load the library, run an input in-process or as a run folder."""

from .runner import Engine, EngineResult

__all__ = ["Engine", "EngineResult"]
