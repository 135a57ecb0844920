"""A run plan: the numbers a protocol derives once and the run folder keeps.

A driven protocol decides its time step, step count, output interval, loading
schedule and damping once per model (:meth:`fabmd.protocols.driven.DrivenTest.plan`),
renders its input from them, writes them to ``plan.json`` beside the input, and its
``reduce`` reads them back (:func:`read_plan`) instead of deriving them again after
the run. Protocol-specific numbers (a settling phase, a pre-tension ramp) go into
``extra`` under unit-suffixed keys.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ..errors import InputError
from .loading import SmoothStartSpeed

PLAN_FILE = "plan.json"
PLAN_FORMAT = "fabmd-run-plan"
PLAN_FORMAT_VERSION = 1


@dataclass(frozen=True)
class RunPlan:
    """What a run was planned with (SI).

    Args:
        time_step_s: the time step [s].
        steps: steps of the loading [-].
        every: output interval [steps]; ``steps`` is a whole number of them where the
            protocol asks for it.
        duration_s: nominal duration of the loading [s].
        speed_m_s: boundary speed after the smooth start [m/s] (0: no moving boundary).
        ramp_time_s: smooth-start time [s].
        damping_time_s: drag time τ [s] (0: none).
        gamma_kg_s: drag coefficient γ = m/τ [kg/s] (0: none).
        extra: protocol-specific numbers (JSON-able, unit-suffixed keys).
    """

    time_step_s: float
    steps: int
    every: int
    duration_s: float
    speed_m_s: float = 0.0
    ramp_time_s: float = 0.0
    damping_time_s: float = 0.0
    gamma_kg_s: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def loading(self) -> SmoothStartSpeed:
        """The boundary motion: ``speed_m_s`` reached smoothly over ``ramp_time_s``."""
        return SmoothStartSpeed(self.speed_m_s, self.ramp_time_s)

    def to_dict(self) -> dict:
        return {"format": PLAN_FORMAT, "version": PLAN_FORMAT_VERSION, **asdict(self)}

    def write(self, run_dir: Path) -> Path:
        """Write ``plan.json`` into ``run_dir`` (call on rank 0 only)."""
        path = Path(run_dir) / PLAN_FILE
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return path


def cached_plan(owner, model, derive) -> RunPlan:
    """``derive(model)`` once per model: kept on ``owner`` (a frozen protocol; the cache is
    no dataclass field, so equality, ``scene.json`` and ``dataclasses.replace`` ignore it)
    until asked for another model object."""
    cached = owner.__dict__.get("_plan")
    if cached is None or cached[0] is not model:
        cached = (model, derive(model))
        object.__setattr__(owner, "_plan", cached)
    return cached[1]


def read_plan(run_dir: Path) -> RunPlan | None:
    """The plan of a run folder, or None where the folder has no ``plan.json`` (written
    before plans were kept). Floats come back exactly (JSON keeps 17 digits)."""
    path = Path(run_dir) / PLAN_FILE
    if not path.exists():
        return None
    data = json.loads(path.read_text())
    if data.pop("format", None) != PLAN_FORMAT or data.pop("version", None) != \
            PLAN_FORMAT_VERSION:
        raise InputError(f"{path} is not a fabmd run plan of version {PLAN_FORMAT_VERSION}")
    return RunPlan(**data)
