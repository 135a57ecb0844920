"""Calibrate the crimp stage: find the expansion coefficients that give a measured fabric.

Given targets — thickness, and crimp per family where known — fabmd runs the
crimp stage a few times and adjusts the rest-length strains α·ΔT itself:

* thickness is set by the shrink of the ``thickness_families`` (default: the
  binders of a 3D fabric, else every family), moved together;
* the crimp of a family not used for thickness is set by its own expansion.

Each knob is moved by a secant step on its own quantity, bracketed once the
target is passed (Illinois false position), so a monotone response converges
in a few runs. If a target cannot be reached within the allowed strain range,
the result says so and why.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from .. import inputs
from ..engine import Engine, mpi
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..results.folder import prepare_run_folder, write_json
from ..results.measure import thickness_m
from ..scene.outputs import TrajectoryOutput
from .crimp import Crimp, CrimpResult

#: the largest shrink or expansion the calibration tries
STRAIN_LIMIT = 0.4


@dataclass(frozen=True)
class CrimpTargets:
    """Measured fabric to reach.

    Args:
        thickness_m: fabric thickness [m] (> 0; below the loose fabric's).
        crimp_pct: crimp per family [%] (>= 0), e.g. ``{"weft": 0.8}``.
        thickness_tolerance: relative tolerance on thickness (default 0.02).
        crimp_tolerance_pct: absolute tolerance on crimp [percentage points].
    """

    thickness_m: float | None = None
    crimp_pct: dict[str, float] = field(default_factory=dict)
    thickness_tolerance: float = 0.02
    crimp_tolerance_pct: float = 0.2

    def __post_init__(self):
        if self.thickness_m is not None:
            inputs.positive("targets.thickness_m", self.thickness_m)
        for fam, value in self.crimp_pct.items():
            inputs.non_negative(f"targets.crimp_pct.{fam}", value)
        inputs.in_range("targets.thickness_tolerance", self.thickness_tolerance, 0, 0.5,
                        low_open=True)
        inputs.positive("targets.crimp_tolerance_pct", self.crimp_tolerance_pct)
        if self.thickness_m is None and not self.crimp_pct:
            raise InputError("targets: give thickness_m and/or crimp_pct")


@dataclass
class _Knob:
    """One scalar unknown: a strain applied to some families, and the quantity it sets."""

    name: str
    families: tuple[str, ...]
    target: float
    tolerance: float
    sign: int  # +1: the quantity grows with the strain, -1: it falls
    value: float
    history: list = field(default_factory=list)  # (strain, quantity)
    low: tuple | None = None   # bracket ends (strain, quantity - target)
    high: tuple | None = None

    def error(self, q: float) -> float:
        return q - self.target

    def converged(self, q: float) -> bool:
        return abs(self.error(q)) <= self.tolerance

    def next_value(self) -> float:
        (s, q) = self.history[-1]
        e = self.error(q)
        side = "low" if e * self.sign < 0 else "high"  # strain too low or too high
        if side == "low":
            self.low = (s, e)
        else:
            self.high = (s, e)
        if self.low is not None and self.high is not None:  # false position in the bracket
            (s0, e0), (s1, e1) = self.low, self.high
            new = s0 - e0 * (s1 - s0) / (e1 - e0)
            return min(max(new, min(s0, s1)), max(s0, s1))
        if len(self.history) >= 2:  # secant, limited step
            (sa, qa), (sb, qb) = self.history[-2], self.history[-1]
            if qb != qa:
                new = sb - self.error(qb) * (sb - sa) / (qb - qa)
                step = max(0.1, 2 * abs(sb - sa))
                return min(max(new, sb - step), sb + step)
        step = 0.03 if side == "low" else -0.03
        return s + step


@dataclass
class CalibrationResult:
    """Expansion found, achieved against target, the runs, and whether it was reached."""

    expansion: dict[str, float]
    achieved: dict
    reached: bool
    reason: str
    runs: list[dict]
    best: CrimpResult | None
    run_dir: Path


def default_thickness_families(model: BeadModel) -> tuple[str, ...]:
    return ("binder",) if "binder" in model.family_names else tuple(model.family_names)


def calibrate(model: BeadModel, targets: CrimpTargets, base: Crimp | None = None,
              thickness_families: tuple[str, ...] | None = None, max_runs: int = 8,
              out: Path | None = None, engine: Engine | None = None,
              overwrite: bool = False) -> CalibrationResult:
    """Find the crimp expansion that reaches ``targets`` on ``model`` (the loose fabric).

    Raises:
        InputError: a target is impossible on its face (thickness not below the
            loose fabric's, a family the fabric does not have), before LAMMPS starts.
    """
    # the trial crimps write no trajectory unless the base crimp asks for one
    base = base or Crimp(trajectory=TrajectoryOutput(frames=0))
    engine = engine or Engine(progress=False)
    max_runs = inputs.positive_int("calibration.max_runs", max_runs, minimum=2)
    fams = tuple(thickness_families or default_thickness_families(model))
    knobs = _knobs(model, targets, base, fams)
    root = prepare_run_folder(out, overwrite=overwrite, prefix="calibration")
    runs: list[dict] = []
    best: CrimpResult | None = None
    best_score = float("inf")
    reached, reason = False, ""
    for k in range(1, max_runs + 1):
        expansion = dict(base.expansion)
        for knob in knobs:
            for fam in knob.families:
                expansion[fam] = knob.value
        crimp = dataclasses.replace(base, expansion=expansion)
        result = crimp.run(model, out=root / f"run-{k:02d}", engine=engine)
        achieved = _achieved(result, knobs)
        score = 0.0
        for knob in knobs:
            q = achieved[knob.name]
            knob.history.append((knob.value, q))
            score = max(score, abs(knob.error(q)) / knob.tolerance)
        runs.append({"run": k, "expansion": expansion, "achieved": achieved,
                     "quasi_static": result.summary.get("quasi_static")})
        if score < best_score:
            best, best_score = result, score
        if all(knob.converged(achieved[knob.name]) for knob in knobs):
            reached = True
            break
        reason = _step(knobs, achieved)
        if reason:
            break
    if not reached and not reason:
        reason = f"not reached within {max_runs} crimp runs (raise max_runs)"
    final = runs[[r["run"] for r in runs].index(runs[-1]["run"])]
    best_run = min(runs, key=lambda r: max(abs(r["achieved"][kn.name] - kn.target) / kn.tolerance
                                           for kn in knobs))
    summary = {"targets": dataclasses.asdict(targets), "reached": reached, "reason": reason,
               "expansion": best_run["expansion"], "achieved": best_run["achieved"],
               "runs": runs, "best_run": best_run["run"], "last_run": final["run"]}
    write_json(root / "calibration.json", summary)
    summary = mpi.bcast_json(summary)
    return CalibrationResult(summary["expansion"], summary["achieved"], reached,
                             reason, summary["runs"], best, root)


def _knobs(model: BeadModel, targets: CrimpTargets, base: Crimp,
           fams: tuple[str, ...]) -> list[_Knob]:
    """One knob per target: the thickness (the expansion of ``fams``) and the crimp of
    each other family, started from the base crimp's expansion; impossible targets raise."""
    unknown = (set(fams) | set(targets.crimp_pct)) - set(model.family_names)
    if unknown:
        raise InputError(f"calibration names families {sorted(unknown)}; the fabric has "
                         f"{list(model.family_names)}")
    knobs: list[_Knob] = []
    if targets.thickness_m is not None:
        loose = thickness_m(model)
        if targets.thickness_m >= loose:
            raise InputError(f"targets.thickness_m = {targets.thickness_m:.4g} m is not below "
                             f"the loose fabric's thickness {loose:.4g} m: crimping only compacts; "
                             f"build a thicker loose fabric or lower the target")
        start = min((base.expansion.get(f, 0.0) for f in fams), default=0.0)
        knobs.append(_Knob("thickness", fams, targets.thickness_m,
                           targets.thickness_tolerance * targets.thickness_m, +1,
                           start if start < 0 else -0.03))
    for fam, crimp_target in targets.crimp_pct.items():
        if fam in fams and targets.thickness_m is not None:
            continue  # that family's strain is taken by the thickness
        knobs.append(_Knob(f"crimp:{fam}", (fam,), crimp_target, targets.crimp_tolerance_pct,
                           +1, base.expansion.get(fam, 0.0)))
    return knobs


def _step(knobs: list[_Knob], achieved: dict[str, float]) -> str:
    """Move every knob not yet converged to its next value (within ±STRAIN_LIMIT);
    the reason to stop when one is stuck at the limit, else ""."""
    reason = ""
    for knob in knobs:
        if knob.converged(achieved[knob.name]):
            continue
        new = knob.next_value()
        if abs(new) > STRAIN_LIMIT:
            new = max(-STRAIN_LIMIT, min(STRAIN_LIMIT, new))
            if abs(knob.value) >= STRAIN_LIMIT - 1e-12:
                reason = (f"{knob.name}: target {knob.target:.4g} not reached with a strain "
                          f"of {knob.value:+.2f} on {', '.join(knob.families)} (limit "
                          f"±{STRAIN_LIMIT}); reached {achieved[knob.name]:.4g}. "
                          + ("The yarns are already pressed together as far as their "
                             "fibres and contact allow: lower the target, or describe "
                             "thinner yarns (fewer/smaller virtual fibres)"
                             if knob.name == "thickness" else
                             "the yarns cannot take that waviness: check the target"))
        knob.value = new
    return reason


def _achieved(result: CrimpResult, knobs: list[_Knob]) -> dict[str, float]:
    crimped = result.summary["crimped"]
    out = {}
    for knob in knobs:
        if knob.name == "thickness":
            out[knob.name] = crimped["thickness_m"]
        else:
            out[knob.name] = crimped["crimp_pct"][knob.families[0]]
    return out
