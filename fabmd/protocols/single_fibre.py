"""What the single-fibre checks share (capstan, sliding, fibre tension).

Each check is a frozen dataclass with the fields ``fibre``, ``discretisation`` and
``time_step`` that builds its own small model (:meth:`model`), writes its input
(:meth:`input_text`) and reads its curve back (:meth:`reduce`). :class:`SingleFibreCheck`
gives them the bead parameters, the stable time step with the contacts they name
(:meth:`plan_contacts`), the step count of their ``duration_s`` and one :meth:`run`:
write the run folder, run LAMMPS, convert the trajectory where the check writes one,
reduce, write the results and hand rank 0's summary to every rank.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import numpy as np

from ..engine import Engine, mpi
from ..errors import SimulationFailed
from ..model.bead_model import BeadModel
from ..model.beads import BeadParameters, bead_parameters
from ..model.material import GLASS, VirtualFibre
from ..model.timestep import stable_time_step_s
from ..results.trajectory import finalise, salvage
from ..scene.loading import SmoothStartSpeed
from .common import RunResult, run_folder, scene_dict, write_run_folder


def default_fibre() -> VirtualFibre:
    """A 0.1 mm E-glass virtual fibre."""
    return VirtualFibre.solid(GLASS, 0.1e-3)


def load_ramp(ramp_time_s: float) -> str:
    """LAMMPS formula of a load's smooth start over ``ramp_time_s`` [s] (factor 0 → 1 of
    the time variable ``v_t``), the same shape as :class:`SmoothStartSpeed`."""
    return SmoothStartSpeed(1.0, ramp_time_s).lammps_ramp("t")


class SingleFibreCheck:
    """Mixin of the single-fibre checks (see the module docstring)."""

    protocol: ClassVar[str] = ""

    # -- to be defined by the check ------------------------------------------------------
    def model(self) -> BeadModel:
        raise NotImplementedError

    def input_text(self, model: BeadModel) -> str:
        raise NotImplementedError

    def reduce(self, run_dir: Path, model: BeadModel) -> RunResult:
        raise NotImplementedError

    def plan_contacts(self) -> tuple:
        """The contacts whose stiffness bounds the time step (none by default)."""
        return ()

    # -- derived ---------------------------------------------------------------------------
    @property
    def beads(self) -> BeadParameters:
        return bead_parameters(self.fibre, self.discretisation)

    @property
    def time_step_s(self) -> float:
        """Stable time step of the fibre's beads with :meth:`plan_contacts` [s]."""
        return stable_time_step_s(self.beads, self.plan_contacts(), self.time_step)

    @property
    def steps(self) -> int:
        """Steps of the whole run, ``duration_s`` rounded up."""
        return int(np.ceil(self.duration_s / self.time_step_s))

    # -- run -------------------------------------------------------------------------------
    def run(self, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False) -> RunResult:
        """Write the run folder, run LAMMPS, reduce the curve."""
        engine = engine or Engine()
        model = self.model()
        run_dir = write_run_folder(out, self.protocol, model, self.input_text(model),
                                   scene_dict(self), overwrite=overwrite)
        trajectory = getattr(self, "trajectory", None)
        try:
            run = run_folder(engine, run_dir, self.protocol)
        except SimulationFailed:
            if trajectory is not None:  # the frames up to the failure
                salvage(run_dir, paraview=trajectory.paraview, model=model)
            raise
        frames = None
        if trajectory is not None:
            frames = finalise(run_dir, paraview=trajectory.paraview, model=model)
        result = self.reduce(run_dir, model)
        result.summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend)
        if trajectory is not None:
            result.summary["trajectory"] = frames.name if frames else None
        result.write()
        # every rank returns rank 0's summary; the curve stays on rank 0
        result.summary = mpi.bcast_json(result.summary)
        return result
