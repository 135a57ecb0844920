"""Fabric compaction between two rigid platens: thickness against pressure.

The standard characterisation of a dry reinforcement (and the source for
calibrating its transverse behaviour): the as-woven fabric — a cell periodic in x
and y, so no edges — first settles free with its centre of mass held (a platen it
touched while still moving would kick it into the other one: Cundall damping does not
damp a drift); then it lies on a fixed bottom platen at its lowest bead surface, and
the top platen, from its highest, comes down — faster as the pressure rises
(``speed_schedule``) — until the mean pressure over an output interval reaches
``max_pressure_pa``, then goes back up the same way until the pressure is down to the
lowest reported one (below it the pace is at its slowest: on the plain-weave example the
last kilopascal took 0.8 M steps, the 199 before it 1.04 M) or it is back where it
started. The base speed is set by the fabric's
through-thickness wave speed so that the reported thicknesses are measured with the load
through the fabric (:mod:`fabmd.protocols.compaction_speed`); ``speed_fraction`` overrides
it with a fraction of the fibres' axial wave speed. Both platens are
``fix wall/gran/region`` planes (``granular hooke ... linear_history``, see
:class:`~fabmd.model.contact.ToolContact`).

* pressure p = (force on the top platen) / (lx·ly) [Pa], interval mean;
* thickness h = distance between the platens [m] (a bead touches a platen at its
  surface, so h is the fabric's thickness including the bead radii), interval mean;
* ``curve.csv``: ``pressure_pa``, ``thickness_m``, ``phase`` (1 loading, −1 unloading),
  the bottom platen's pressure (equal to the top's when quasi-static), kinetic energy, the
  platen's speed;
* ``summary.json``: thickness at 1, 10 and 100 kPa (loading branch, first
  crossing) and at ``datasheet_pressure_pa`` when given, and whether the loading
  thickness fell monotonically with pressure.

Quasi-static: local (Cundall) damping, which opposes each bead's unbalanced force
rather than its velocity, so the slow following motion carries no drag into the
pressure; the summary reports the largest kinetic energy over the work done and the
largest top/bottom pressure mismatch on the loading branch from first contact (both platens
carry the load) and above 10 % of the peak (:func:`quasi_static_measures`).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import inputs
from ..engine import Engine, mpi
from ..errors import InputError, QuasiStaticWarning
from ..model.bead_model import BeadModel
from ..model.beads import TimeStep, model_bead_parameters
from ..model.contact import ContactModel, ToolContact
from ..model.timestep import stable_time_step_s
from ..results.folder import read_ave_time
from ..scene import blocks
from ..scene.plan import RunPlan, cached_plan, read_plan
from ..scene.templates import render
from ..units import quantity
from . import compaction_speed
from .common import DATA_FILE, open_run_folder, overlap_summary, run_folder, scene_dict
from .driven import DrivenResult, shared_result
from .periodic import check_periodic_cell

#: above these the loading branch is not quasi-static: kinetic energy over the platen work,
#: and the two platens' pressures differing (the fabric still accelerating)
QUASI_STATIC_LIMITS = {"max_kinetic_to_work": 0.1, "max_platen_pressure_mismatch": 0.1}
#: pressures at which the thickness is always reported [Pa]
REPORT_PRESSURES_PA = (1e3, 1e4, 1e5)


def thickness_at(pressure_pa: np.ndarray, thickness_m: np.ndarray,
                 targets: tuple[float, ...]) -> dict[str, float | None]:
    """Thickness [m] where the loading branch first reaches each target pressure
    (linear interpolation; None when the curve never gets there or starts above it)."""
    out = {}
    for p in targets:
        above = np.nonzero(pressure_pa >= p)[0]
        if not above.size:
            out[f"{p:g}"] = None
            continue
        i = int(above[0])
        if i == 0:  # below the start of the curve: not measured
            out[f"{p:g}"] = float(thickness_m[0]) if pressure_pa[0] == p else None
            continue
        p0, p1 = pressure_pa[i - 1], pressure_pa[i]
        w = (p - p0) / (p1 - p0) if p1 != p0 else 1.0
        out[f"{p:g}"] = float(thickness_m[i - 1] + w * (thickness_m[i] - thickness_m[i - 1]))
    return out


@dataclass(frozen=True)
class Compaction:
    """Compaction of a periodic cell between two rigid platens (module docstring).

    Args:
        max_pressure_pa: pressure at which the platen turns back [Pa] (> 0; "200 kPa").
        datasheet_pressure_pa: a pressure at which the datasheet states the thickness
            [Pa]; reported too (None: none).
        speed_fraction: platen speed over the fibres' axial wave speed, (0, 0.01]; None
            (default): from the fabric's through-thickness wave speed, so that the predicted
            platen mismatch at the lowest reported pressure is ``mismatch_target``
            (:mod:`~fabmd.protocols.compaction_speed`; without a yarn compaction law in the
            contact: 5e-6 of the axial wave speed).
        speed_schedule: ``"pressure"`` (default): the platen goes faster as the pressure
            rises, v0·φ(p), which holds the predicted mismatch at its value at the lowest
            reported pressure (:func:`~fabmd.protocols.compaction_speed.pace_factor`; the
            speed above is then v0, its speed below that pressure); needs a yarn compaction
            law in the contact (without one the speed stays constant, and the summary says
            so). ``"constant"``: v0 throughout.
        mismatch_target: the predicted top/bottom platen mismatch at the lowest reported
            pressure that sets the default speed, (0, 0.1] (0.1 is the verdict's limit; the
            default 0.03 leaves room for a measured mismatch up to 3.3× the prediction:
            paced runs measured 1.2–2.4× it on the plain-weave example at 7 and 19 fibres
            per yarn and on a one-row Twintex cell, and failed at 0.1; where it fails,
            ``reruns`` slow the run).
        step_limit: the most steps (loading and unloading, estimated before the run) a run
            may need, >= 1000; above it the run is refused before LAMMPS starts.
        reruns: with the default speed, the most times a run whose reported thickness is
            not quasi-static runs again at the speed its mismatch asks for, >= 0.
        max_travel_fraction: the furthest the top platen may go down, as a fraction
            of the starting gap, (0, 0.95]; the loading stops there if the pressure
            is not reached (the summary says so).
        local_damping: Cundall local damping coefficient, [0, 1).
        settle_fraction: the fabric first settles between the platens at rest for this
            fraction of the longest loading time at 5e-6 of the fibres' axial wave speed,
            whatever the platen speed, [0, 1] (a whole number of intervals).
        contact: fibre–fibre contact.
        tool: platen contact (per unit length of fibre on the platen).
        time_step: time-step policy.
        samples: output intervals over the full loading travel (>= 10).
        unload: go back up after the turn (default); False ends the run at the
            pressure — once both platens carry it — (the calibration reads the thickness
            there and needs no unloading, which would cost as many steps again).
    """

    max_pressure_pa: float = 2e5
    datasheet_pressure_pa: float | None = None
    speed_fraction: float | None = None
    speed_schedule: str = "pressure"
    mismatch_target: float = 0.03
    step_limit: int = 50_000_000
    reruns: int = 2
    max_travel_fraction: float = 0.8
    local_damping: float = 0.7
    settle_fraction: float = 0.02
    contact: ContactModel = field(default_factory=ContactModel)
    tool: ToolContact = field(default_factory=lambda: ToolContact(friction=0.2))
    time_step: TimeStep = field(default_factory=TimeStep)
    samples: int = 2000
    unload: bool = True

    protocol: ClassVar[str] = "compaction"

    def __post_init__(self):
        object.__setattr__(self, "max_pressure_pa", inputs.positive(
            "compaction.max_pressure_pa",
            quantity(self.max_pressure_pa, "pressure", "compaction.max_pressure_pa")))
        if self.datasheet_pressure_pa is not None:
            object.__setattr__(self, "datasheet_pressure_pa", inputs.positive(
                "compaction.datasheet_pressure_pa",
                quantity(self.datasheet_pressure_pa, "pressure",
                         "compaction.datasheet_pressure_pa")))
        if self.speed_fraction is not None:
            inputs.in_range("compaction.speed_fraction", self.speed_fraction, 0, 0.01,
                            low_open=True)
        inputs.one_of("compaction.speed_schedule", self.speed_schedule,
                      ("pressure", "constant"))
        inputs.in_range("compaction.mismatch_target", self.mismatch_target, 0, 0.1,
                        low_open=True)
        inputs.positive_int("compaction.step_limit", self.step_limit, minimum=1000)
        inputs.positive_int("compaction.reruns", self.reruns, minimum=0)
        inputs.in_range("compaction.max_travel_fraction", self.max_travel_fraction, 0, 0.95,
                        low_open=True)
        inputs.in_range("compaction.local_damping", self.local_damping, 0, 1, high_open=True)
        inputs.in_range("compaction.settle_fraction", self.settle_fraction, 0, 1)
        inputs.positive_int("compaction.samples", self.samples, minimum=10)

    # -- geometry and time ---------------------------------------------------------------
    def platens(self, model: BeadModel) -> tuple[float, float]:
        """(z of the lowest, z of the highest bead surface) of ``model`` [m]. The run puts
        its platens on those of the fabric after its free settle (``platens.txt``,
        :func:`settled_platens`)."""
        r = 0.5 * model.diameters
        z = model.positions[:, 2]
        return float((z - r).min()), float((z + r).max())

    def area_m2(self, model: BeadModel) -> float:
        size = model.box_hi - model.box_lo
        return float(size[0] * size[1])

    def lowest_report_pressure_pa(self) -> float:
        """The lowest pressure whose thickness is reported [Pa] (at most the turn's)."""
        targets = REPORT_PRESSURES_PA + ((self.datasheet_pressure_pa,)
                                         if self.datasheet_pressure_pa is not None else ())
        return min(min(targets), self.max_pressure_pa)

    def speed(self, model: BeadModel) -> dict:
        """The platen speed ``platen_speed_m_s`` [m/s] and what it came from (JSON-able):
        ``speed_fraction`` of the axial wave speed if set, else from the fabric's
        through-thickness wave speed (:func:`~fabmd.protocols.compaction_speed.platen_speed`
        at :meth:`lowest_report_pressure_pa`, density over the starting gap)."""
        beads = model_bead_parameters(model)
        if self.speed_fraction is not None:
            c = compaction_speed.axial_wave_speed_m_s(beads)
            rerun = self.__dict__.get("_rerun_of")  # no field: see run()
            return {"platen_speed_m_s": self.speed_fraction * c,
                    "speed_basis": "rerun" if rerun else "set",
                    "speed_note": f"speed_fraction {self.speed_fraction:g} of the fibres' "
                                  f"axial wave speed {c:.4g} m/s"
                                  + (f": {RERUN_MARGIN:g} of what the mismatch at {rerun} "
                                     f"asked for" if rerun else ""),
                    "axial_wave_speed_m_s": c}
        lo, hi = self.platens(model)
        return compaction_speed.platen_speed(
            self.contact, model, beads, self.area_m2(model), hi - lo,
            self.lowest_report_pressure_pa(), self.mismatch_target)

    def speed_m_s(self, model: BeadModel) -> float:
        """The platen speed [m/s] (:meth:`speed`)."""
        return self.plan(model).speed_m_s

    def time_step_s(self, model: BeadModel) -> float:
        return self.plan(model).time_step_s

    def max_steps(self, model: BeadModel) -> int:
        return self.plan(model).steps

    def settle_steps(self, model: BeadModel) -> int:
        """Steps the fabric settles between the platens at rest before the loading."""
        return self.plan(model).extra["settle_steps"]

    def every(self, model: BeadModel) -> int:
        return self.plan(model).every

    def plan(self, model: BeadModel) -> RunPlan:
        """Time step, steps (the top platen's longest travel), output interval, platen
        speed and settling steps: derived once per model, kept in ``plan.json``."""
        return cached_plan(self, model, self.derive_plan)

    def schedule(self) -> dict:
        """How the platen speed follows the pressure (JSON-able): ``speed_schedule``
        as run, and for ``"pressure"`` the schedule's p0 (``pace_base_pressure_pa``), the
        law's T (``pace_law_pa``) and the largest pace (``pace_max``)
        (:func:`~fabmd.protocols.compaction_speed.pace_factor`)."""
        if self.speed_schedule == "constant":
            return {"speed_schedule": "constant"}
        law = compaction_speed.law_stiffness_pa(self.contact)
        if law is None:
            return {"speed_schedule": "constant",
                    "schedule_note": "no yarn compaction law in the contact: the platen "
                                     "speed stays constant"}
        return {"speed_schedule": "pressure",
                "pace_base_pressure_pa": self.lowest_report_pressure_pa(),
                "pace_law_pa": law[1], "pace_max": compaction_speed.MAX_PACE}

    def derive_plan(self, model: BeadModel) -> RunPlan:
        dt = stable_time_step_s(model, [self.contact, self.tool], self.time_step)
        lo, hi = self.platens(model)
        travel = self.max_travel_fraction * (hi - lo)
        how = self.speed(model)
        speed = how["platen_speed_m_s"]
        # at most: the whole travel at the base speed (the run ends at the pressure)
        steps = math.ceil(travel / speed / dt)
        schedule = self.schedule()
        estimate = compaction_speed.estimated_steps(
            self.contact, hi - lo, travel, self.max_pressure_pa, speed, dt, self.unload,
            schedule.get("pace_base_pressure_pa"))
        # about ``samples`` intervals over the loading the law expects
        every = max(1, min(steps, estimate["loading_steps"]) // self.samples)
        # the settle is the fabric's own time, not the platen's: as long as at the axial
        # fallback speed, whatever the platen speed
        reference = compaction_speed.FALLBACK_SPEED_FRACTION * how["axial_wave_speed_m_s"]
        settle = every * max(1, round(self.settle_fraction * travel / reference / dt / every))
        compaction_speed.check_steps(estimate["estimated_steps"] + settle, self.step_limit,
                                     how)
        return RunPlan(time_step_s=dt, steps=steps, every=every, duration_s=travel / speed,
                       speed_m_s=speed, extra={"settle_steps": settle,
                                               "estimated_steps": estimate["estimated_steps"]
                                               + settle,
                                               "estimated_travel_m":
                                                   estimate["estimated_travel_m"],
                                               **schedule, **how})

    def input_text(self, model: BeadModel) -> str:
        check_periodic_cell(model, self.protocol)
        if model.periodic[2]:
            raise InputError("compaction needs a cell that is not periodic in z (the "
                             "platens close on it), got periodic = "
                             f"{tuple(model.periodic)}")
        beads = model_bead_parameters(model)
        plan = self.plan(model)
        dt, every, steps = plan.time_step_s, plan.every, plan.steps
        settle = plan.extra["settle_steps"]
        lo, hi = self.platens(model)
        pace = ("0.0" if plan.extra["speed_schedule"] == "constant" else
                compaction_speed.pace_formula("v_pace_p", plan.extra["pace_base_pressure_pa"],
                                              plan.extra["pace_law_pa"]))
        text = render(
            "compaction", z_bottom=lo, z_top=hi, speed=plan.speed_m_s,
            max_pressure=self.max_pressure_pa, local_damping=self.local_damping,
            bottom_contact=blocks.tool_region(self.tool, beads, "bottom", fix_id="bottom"),
            top_contact=blocks.tool_region(self.tool, beads, "top", fix_id="top"),
            area=self.area_m2(model), every=every, thermo_every=max(every, steps // 20),
            overlap_monitor=blocks.overlap_monitor(model, self.contact, beads, every=every,
                                                   tool_fixes=("bottom", "top")),
            guards=blocks.guards(model, dt), max_steps=steps,
            settle_steps=settle, pace=pace,
            # the pace is set once per output interval and followed over two
            hold_alpha=1.0 / (every * dt), lag_alpha=1.0 / (2 * every * dt),
            # without unloading the run ends at the pressure, so both platens must carry
            # it (a platen striking one bead first reads it alone, for an interval)
            halt_pressure="f_means[1]" if self.unload else
            '"ternary(f_means[1]<f_means[2],f_means[1],f_means[2])"')
        if self.unload:
            text += render("compaction_unload", every=every, max_steps=steps,
                           unload_end=self.lowest_report_pressure_pa(),
                           settle_steps=settle)
        else:
            text += render("compaction_stop", settle_steps=settle)
        return "\n".join([
            blocks.setup(model, self.protocol, DATA_FILE, dt), blocks.bonds(model),
            blocks.contact(model, self.contact, beads), text,
            render("finish", final_data="final.data")])

    # -- run -----------------------------------------------------------------------------
    def run(self, model: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False, check_rate: bool = False,
            resume: bool = False) -> DrivenResult:
        """Compress ``model`` and release it; ``check_rate`` is not offered (say so).

        With the default speed (``speed_fraction`` None), a run whose reported thickness
        is not quasi-static runs again, up to ``reruns`` times, at the speed its own
        mismatch asks for (:func:`rerun_speed_fraction`: the fabric's through-thickness
        wave speed as measured, where the law's was wrong); the summary lists every run
        (``speed_runs``)."""
        if check_rate:
            raise InputError("compaction has no --check-rate; rerun with half "
                             "speed_fraction to check the rate")
        test, runs = self, []
        while True:
            result, caught, run_dir = test._run_once(model, out, engine,
                                                     overwrite or bool(runs),
                                                     resume and not runs)
            summary = mpi.bcast_json(result.summary if result else None)
            slower = rerun_speed_fraction(summary) if (
                self.speed_fraction is None and len(runs) < self.reruns) else None
            runs.append({k: summary.get(k) for k in (
                "speed_basis", "platen_speed_m_s", "wave_speed_fraction", "time_step_s",
                "quasi_static_at_pressure", "max_platen_pressure_mismatch", "steps_run",
                "wall_s")}
                | {"speed_fraction": summary["run_speed_fraction"]})
            if slower is None:
                break
            test = dataclasses.replace(self, speed_fraction=slower)
            # which pressures asked for it (kept off the fields: scene.json says the speed)
            object.__setattr__(test, "_rerun_of", ", ".join(
                [f"{float(k):g} Pa" for k, v in summary["quasi_static_at_pressure"].items()
                 if not v["ok"]] or ["the curve's largest"]))
            try:  # a rerun is refused like a first run: too many steps
                test.plan(model)
            except InputError as exc:
                runs[-1]["rerun_refused"] = str(exc)
                break
        if result is not None:
            for w in caught:  # the last run's warnings only (the others were rerun)
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
            result.summary["speed_runs"] = runs
            result.write()
        return shared_result(result, run_dir)

    def _run_once(self, model: BeadModel, out, engine, overwrite: bool, resume: bool):
        """One run at this speed: (rank 0's result, not yet written, or None; the warnings
        its reduction gave; the run folder)."""
        text = self.input_text(model)  # validates before anything is written
        run_dir = open_run_folder(out, self.protocol, model, text,
                                  {self.protocol: scene_dict(self)}, overwrite, resume,
                                  plan=self.plan(model), files=blocks.contact_files(
                                      self.contact, model_bead_parameters(model)))
        engine = engine or Engine()
        plan = self.plan(model)
        if engine.progress and mpi.is_root() and not resume:  # the speed and what it costs
            print(f"compaction: platen speed {plan.speed_m_s:.3g} m/s "
                  f"({plan.extra['speed_note']}); about "
                  f"{plan.extra['estimated_steps']:,} steps (estimate)", file=sys.stderr,
                  flush=True)
        run = run_folder(engine, run_dir, self.protocol, resume=resume)
        result, caught = None, []
        if mpi.is_root():
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                result = self.reduce(Path(run_dir), model)
            result.summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend)
        return result, caught, run_dir

    def reduce(self, run_dir: Path, model: BeadModel) -> DrivenResult:
        means = read_ave_time(run_dir / "means.dat")
        plan = read_plan(run_dir) or self.plan(model)  # what the run was written with
        dt = plan.time_step_s
        curve = _curve(means, plan.extra["settle_steps"], dt)
        p, h = curve["pressure_pa"], curve["thickness_m"]
        pb, ke = curve["bottom_pressure_pa"], curve["kinetic_energy_j"]
        loading = curve["phase"] > 0
        area = self.area_m2(model)
        model_lo, model_hi = self.platens(model)
        lo, hi = settled_platens(run_dir, (model_lo, model_hi))
        reached = int(float((run_dir / "turn.txt").read_text().split()[-1])) < plan.steps
        # work done on the fabric by the top platen, −∫F dz (trapezoid over the means)
        work = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * area
                                                * -np.diff(h))])
        pl, hl = p[loading], h[loading]
        peak = float(pl.max()) if pl.size else 0.0
        # the compaction curve: the loading branch from where the load goes through the
        # fabric for good (both platens carry it, within a factor 2), so that a loose fabric
        # rattling between the platens first is left out
        first = first_contact(pl, pb[loading])
        pc, hc = pl[first:], hl[first:]
        # judged from first contact on: before it the bottom platen carries nothing yet
        contact = np.zeros(p.size, dtype=bool)
        contact[np.nonzero(loading)[0][first:]] = True
        measures = quasi_static_measures(p, pb, ke, work, contact & (p > 0.1 * peak))
        # this run's platen speed over the fibres' axial wave speed
        run_fraction = plan.speed_m_s / compaction_speed.axial_wave_speed_m_s(
            model_bead_parameters(model))
        targets = tuple(REPORT_PRESSURES_PA)
        if self.datasheet_pressure_pa is not None:
            targets += (self.datasheet_pressure_pa,)
        summary = {
            "protocol": self.protocol,
            "n_beads": model.n_beads,
            "cell_m": [float(v) for v in (model.box_hi - model.box_lo)[:2]],
            "area_m2": area,
            "time_step_s": dt,
            "platen_speed_m_s": plan.speed_m_s,
            "run_speed_fraction": run_fraction,
            "steps_run": int(means["step"][-1]),
            **{k: v for k, v in plan.extra.items() if k != "settle_steps"},
            "starting_gap_m": hi - lo,
            # how far the free settle moved the outermost bead surfaces (bottom, top)
            "settle_shift_m": [lo - model_lo, hi - model_hi],
            "max_pressure_pa": self.max_pressure_pa,
            "max_pressure_reached_pa": peak,
            "pressure_reached": bool(reached),
            "contact_thickness_m": float(hc[0]) if hc.size else None,
            "contact_pressure_pa": float(pc[0]) if pc.size else None,
            "min_thickness_m": float(h.min()),
            "thickness_at_pressure_m": thickness_at(pc, hc, targets),
            "datasheet_pressure_pa": self.datasheet_pressure_pa,
            "final_thickness_m": float(h[-1]),
            "thickness_monotone": monotone_loading(
                pc, MONOTONE_FLOOR * self.lowest_report_pressure_pa()),
            "monotone_note": MONOTONE_NOTE,
            **measures,
            "quasi_static_note": QUASI_STATIC_NOTE,
            **overlap_summary(run_dir, self.contact),
        }
        summary["quasi_static_at_pressure"] = mismatch_at(
            pc, pb[loading][first:], targets, QUASI_STATIC_LIMITS["max_platen_pressure_mismatch"],
            run_fraction)
        problems = judge_quasi_static(summary, run_dir)
        if not reached:
            summary["pressure_note"] = (
                f"the top platen travelled {self.max_travel_fraction:g} of the starting gap "
                f"and reached {peak:.3g} Pa < {self.max_pressure_pa:.3g} Pa; raise "
                f"max_travel_fraction or lower max_pressure_pa")
        return DrivenResult(run_dir, curve, summary, [curve_plot(p, h, loading, summary,
                                                                 bool(problems))])


def _curve(means: dict, settle_steps: int, time_step_s: float) -> dict:
    """The run's curve columns after the free settle (those intervals are not part of it);
    phase +1 loading (an interval straddling the turn is counted with it), −1 unloading."""
    keep = means["step"] > settle_steps
    curve = {"time_s": (means["step"][keep] - settle_steps) * time_step_s,
             "pressure_pa": means["pressure_pa"][keep],
             "thickness_m": means["thickness_m"][keep],
             "phase": np.where(means["phase"][keep] > 0, 1, -1),
             "bottom_pressure_pa": means["bottom_pressure_pa"][keep],
             "kinetic_energy_j": means["kinetic_j"][keep]}
    if "speed_m_s" in means:  # the platen's speed, interval mean (folders since the pace)
        curve["platen_speed_m_s"] = means["speed_m_s"][keep]
    return curve


#: the monotone verdict starts at this fraction of the lowest reported pressure (below, the
#: load is still finding its way: no thickness is reported there)
MONOTONE_FLOOR = 0.5
#: a fall of the pressure, over the highest pressure so far, that the verdict lets pass
#: (interval means: sampling noise)
MONOTONE_TOLERANCE = 0.01
MONOTONE_NOTE = ("loading branch from where both platens carry the load (within a factor 2) "
                 f"and the pressure has reached {MONOTONE_FLOOR:g} of the lowest reported "
                 "one, to the turn: as the platen goes down the pressure never falls by more "
                 f"than {MONOTONE_TOLERANCE:.0%} of its highest so far, i.e. the thickness "
                 "falls monotonically with the pressure")


def monotone_loading(pressure_pa: np.ndarray, floor_pa: float,
                     tolerance: float = MONOTONE_TOLERANCE) -> bool:
    """Does the thickness fall monotonically with the pressure on a loading branch?

    ``pressure_pa``: the branch's pressures [Pa] in the order the platen went down (so
    the thickness falls along it). From the first sample at or above ``floor_pa`` [Pa] on,
    the pressure must never fall by more than ``tolerance`` of its highest value so far: a
    fall is the fabric giving way (a thinner fabric carrying less). Judged in the order of
    travel, not sorted by pressure: sorted, two samples a noise apart in pressure read as
    a rise of the thickness by their interval's travel (measured: 0.46 µm on a 19-fibre cell
    whose pressure never fell by 2 Pa)."""
    p = np.asarray(pressure_pa, dtype=float)
    start = np.nonzero(p >= floor_pa)[0]
    if not start.size:
        return True
    p = p[start[0]:]
    highest = np.maximum.accumulate(p)
    return bool(((highest - p) <= tolerance * highest).all())


QUASI_STATIC_NOTE = ("kinetic energy over the platen work done since the loading began, and "
                     "|bottom − top| / top pressure, on the loading branch from first contact "
                     "(both platens carry the load) above 10 % of the peak; None: not measured "
                     "(no such sample, or the platen had done no work yet); "
                     "quasi_static_at_pressure: the same mismatch at each reported pressure")

#: a rerun goes this much below the speed the failed run's mismatch asks for (the mismatch
#: is only about proportional to the speed)
RERUN_MARGIN = 0.7


def rerun_speed_fraction(summary: dict) -> float | None:
    """The speed fraction (of the axial wave speed) for a run again, or None: none needed.

    Where a reported thickness was not quasi-static, its mismatch m ≈ ρ_f·c_t·v/p measured
    the fabric's through-thickness impedance at that pressure, so the speed that brings the
    worst to the limit is ``speed_fraction_below`` (:func:`mismatch_at`); the same for the
    curve's largest mismatch (``max_platen_pressure_mismatch``: a curve whose first sample
    with both platens loaded is already above every reported pressure has no per-pressure
    verdict). The rerun takes :data:`RERUN_MARGIN` of the slowest of them."""
    late = [v["speed_fraction_below"] for v in summary.get("quasi_static_at_pressure",
                                                           {}).values() if not v["ok"]]
    limit = QUASI_STATIC_LIMITS["max_platen_pressure_mismatch"]
    worst = summary.get("max_platen_pressure_mismatch")
    if worst is not None and worst > limit and summary.get("run_speed_fraction"):
        late.append(summary["run_speed_fraction"] * limit / worst)
    return RERUN_MARGIN * min(late) if late else None


def first_contact(p: np.ndarray, pb: np.ndarray) -> int:
    """Index of the loading sample from which both platens carry the load for good (the
    bottom pressure within a factor 2 of the top's, ``p``/``pb`` [Pa])."""
    through = (p > 0.0) & (pb > 0.5 * p) & (pb < 2.0 * p)
    broken = np.nonzero(~through)[0]
    return int(broken[-1]) + 1 if broken.size else 0


def mismatch_at(p: np.ndarray, pb: np.ndarray, targets: tuple[float, ...], limit: float,
                speed_fraction: float) -> dict[str, dict]:
    """Is each reported thickness quasi-static? At each target pressure [Pa], the largest
    |bottom − top| / top platen pressure of the two loading samples around its first
    crossing (``p``/``pb``: top/bottom pressure on the loading branch from first contact).

    The mismatch is the pressure that only moves the fabric (about ρ·c·v for a
    through-thickness wave speed c and platen speed v), so it falls about in proportion
    to the speed: where it is above ``limit``, ``speed_fraction_below`` is the speed
    fraction that would bring it to the limit (``speed_fraction``: this run's). A target
    the curve does not cross is left out."""
    out = {}
    for target in targets:
        above = np.nonzero(p >= target)[0]
        if not above.size or above[0] == 0:
            continue
        i = int(above[0])
        m = float(max(abs(pb[j] - p[j]) / p[j] for j in (i - 1, i) if p[j] > 0))
        entry = {"platen_pressure_mismatch": m, "ok": m <= limit}
        if m > limit:
            entry["speed_fraction_below"] = float(speed_fraction * limit / m)
        out[f"{target:g}"] = entry
    return out


def settled_platens(run_dir: Path, model_platens: tuple[float, float]) -> tuple[float, float]:
    """(z of the bottom platen, z of the top platen at the start) [m] of a run: where the
    run put them, on the fabric's outermost bead surfaces after its free settle
    (``platens.txt``); a folder written before the settle was free has none: ``model_platens``."""
    path = Path(run_dir) / "platens.txt"
    if not path.exists():
        return model_platens
    lo, hi = (float(v) for v in path.read_text().split()[-2:])
    return lo, hi


def quasi_static_measures(p: np.ndarray, pb: np.ndarray, ke: np.ndarray, work: np.ndarray,
                          window: np.ndarray) -> dict[str, float | None]:
    """Largest kinetic energy over platen work [-] and largest |bottom − top| / top pressure
    [-] over the samples in ``window`` (bool mask over the curve).

    ``p``/``pb``: top/bottom platen pressure [Pa]; ``ke``: kinetic energy [J]; ``work``: the
    platen's work on the fabric since the loading began [J]. A sample where the platen has
    done no work yet has no ratio (a ratio there would be any size, not a measure); a
    measure with no sample is None (not measured)."""
    worked = window & (work > 0.0)
    ke_ratio = ke[worked] / work[worked]
    mismatch = np.abs(pb[window] - p[window]) / p[window]
    return {"max_kinetic_to_work": float(ke_ratio.max()) if ke_ratio.size else None,
            "max_platen_pressure_mismatch": float(mismatch.max()) if mismatch.size else None}


def judge_quasi_static(summary: dict, run_dir: Path) -> list[str]:
    """Judge the summary's measures against :data:`QUASI_STATIC_LIMITS` (verdict into the
    summary; a warning when one fails); returns the problems. ``ok``: no measure above its
    limit; ``not_measured``: the measures that had no sample (they judge nothing)."""
    problems = [f"{k} = {summary[k]:.2g} > {v:g}" for k, v in QUASI_STATIC_LIMITS.items()
                if summary[k] is not None and summary[k] > v]
    summary["quasi_static"] = {"ok": not problems, "limits": dict(QUASI_STATIC_LIMITS),
                               "problems": problems,
                               "not_measured": [k for k in QUASI_STATIC_LIMITS
                                                if summary[k] is None]}
    if problems:
        warnings.warn(f"compaction in {run_dir}: not quasi-static ({'; '.join(problems)}):"
                      f" lower speed_fraction", QuasiStaticWarning, stacklevel=3)
    late = {k: v for k, v in summary.get("quasi_static_at_pressure", {}).items() if not v["ok"]}
    if late:
        worst = min(v["speed_fraction_below"] for v in late.values())
        warnings.warn(
            f"compaction in {run_dir}: the thickness at "
            + ", ".join(f"{float(k):g} Pa (platens differ by {v['platen_pressure_mismatch']:.0%})"
                        for k, v in late.items())
            + f" is not quasi-static: the load had not crossed the fabric; lower "
            f"speed_fraction to about {worst:.2g} or below", QuasiStaticWarning, stacklevel=3)
    return problems


def curve_plot(p, h, loading, summary: dict, not_quasi_static: bool) -> dict:
    """Plot spec of thickness [mm] against pressure [kPa], loading and unloading."""
    return {"path": "curve.png",
            "series": [{"x": p[loading] / 1e3, "y": h[loading] * 1e3, "label": "loading"},
                       {"x": p[~loading] / 1e3, "y": h[~loading] * 1e3, "style": "--",
                        "label": "unloading"}],
            "xlabel": "pressure [kPa]", "ylabel": "thickness [mm]",
            "title": ("NOT QUASI-STATIC, do not use: " if not_quasi_static else "")
            + "Compaction between rigid platens",
            "notes": f"cell {1e3 * summary['cell_m'][0]:.2f} x "
                     f"{1e3 * summary['cell_m'][1]:.2f} mm\n{summary['n_beads']} beads"}
