"""What every displacement-driven quasi-static test shares.

A driven test (tension, picture frame, bias extension, periodic cells) moves a
boundary — clamps or the periodic box — at a constant speed reached by a smooth
start (:class:`~fabmd.scene.loading.SmoothStartSpeed`), damps the free beads with a
drag γ = m/τ on their motion relative to the tools' affine velocity field
(:mod:`fabmd.scene.drag`; protocols without ``drag`` damp the absolute velocity) and
writes, through ``lammps_templates/driven_outputs.lmp``:

* ``means.dat`` — forces and powers averaged over each output interval (exact
  integrals of the external and the damping power);
* ``curve.dat`` — clock, boundary displacement(s) and energies at the output steps;
* the trajectory (``trajectory.h5``, ParaView files; :mod:`fabmd.scene.outputs`)
  with frames on output steps and the last step as the last frame.

:class:`DrivenTest` is a mixin for the protocols' frozen dataclasses: it turns
their ``speed_fraction``, ``ramp_fraction``, ``damping_time_s``, ``contact``,
``time_step``, ``samples`` and ``trajectory`` fields plus the protocol's travel into
the loading, the time step, the output interval and the step count, and its :meth:`run`
writes the run folder, runs it with the contact-power monitor, converts the
trajectory (after a failed run too: the frames up to the failure), reduces it, and
with ``check_rate`` reruns at half speed and reports how much the curve moved.
:func:`read_outputs`, :func:`energy_columns`, :func:`kinetic_ratio` assemble the
quasi-static evidence the same way for every protocol.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import inputs
from ..engine import Engine, mpi
from ..errors import QuasiStaticWarning, SimulationFailed
from ..model.bead_model import BeadModel
from ..model.beads import model_bead_parameters
from ..model.timestep import stable_time_step_s
from ..results.curves import curve_difference
from ..results.folder import read_ave_time, read_print_file
from ..results.plots import plot_curves
from ..results.trajectory import finalise, salvage
from ..scene import blocks
from ..scene.drag import DRAG_KINDS, AffineField, drag_commands
from ..scene.energy import ContactPower, balance, cumulative
from ..scene.loading import SmoothStartSpeed
from ..scene.outputs import check_trajectory
from ..scene.plan import RunPlan, cached_plan, read_plan
from ..scene.quasi_static import interval_columns, interval_verdict, relaxation_settled
from ..scene.templates import render
from .common import DATA_FILE, RunResult, input_name, resume_folder, scene_dict, write_run_folder

#: above these a driven test's curve is not quasi-static (after start-up): kinetic over
#: strain energy and over the work done (inertia; KE/U = 0.1 moved the tension force at 1 %
#: by about 1 %, benchmarks/stability.py "Loading speed"), and the share of the work the
#: viscous drag took (a force that grows with the loading speed); and the energy balance's
#: closing error (work that went somewhere no term accounts for)
QUASI_STATIC_LIMITS = {"max_kinetic_to_strain_energy": 0.1,
                       "max_kinetic_to_external_work": 0.1, "damping_share": 0.5,
                       "energy_balance_error": 0.05, "start_spike_ratio": 1.0}


@dataclass
class DrivenResult(RunResult):
    """Curve, summary and plots of a driven test.

    ``plots`` holds keyword sets for :func:`fabmd.results.plots.plot_curves`
    (``path`` relative to the run folder).
    """

    plots: list[dict] = field(default_factory=list)

    def plot(self) -> None:
        for spec in self.plots:
            spec = dict(spec)
            spec.pop("x_column", None), spec.pop("x_scale", None)  # for mark_plots only
            plot_curves(self.run_dir / spec.pop("path"), **spec)


class DrivenTest:
    """Mixin of the displacement-driven protocols (see the module docstring).

    A subclass is a frozen dataclass with the fields named above and defines
    ``protocol``, ``rate_curve`` (x and y columns compared by ``check_rate``),
    ``rate_keys`` (summary keys compared by ``check_rate``: {report name: key}),
    :meth:`travel_m`, :meth:`input_text` and :meth:`reduce`.
    """

    protocol: ClassVar[str] = ""
    rate_curve: ClassVar[tuple[str, str]] = ("", "")
    rate_keys: ClassVar[dict[str, str]] = {}
    #: the quasi-static measures judged after the run (summary key -> largest allowed)
    quasi_static_limits: ClassVar[dict[str, float]] = QUASI_STATIC_LIMITS
    #: (curve column, interval width) of the per-interval quasi-static verdict (None: none)
    interval_axis: ClassVar[tuple[str, float] | None] = None

    # -- to be defined by the protocol ---------------------------------------------
    def travel_m(self, model: BeadModel) -> float:
        """Distance the driven boundary moves at the loading speed [m]."""
        raise NotImplementedError

    def input_text(self, model: BeadModel) -> str:
        raise NotImplementedError

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        raise NotImplementedError

    def prepare(self, model: BeadModel) -> BeadModel:
        """The model the run starts from (validated; a protocol may add bond types)."""
        return model

    def make_monitor(self) -> ContactPower:
        return ContactPower()

    # -- loading and time ------------------------------------------------------------
    def wave_speed_m_s(self, model: BeadModel) -> float:
        """Slowest axial wave speed of the fibres, c = l0·sqrt(k/m) [m/s]."""
        return min(b.wave_speed_m_s for b in model_bead_parameters(model))

    def nominal_loading(self, model: BeadModel) -> SmoothStartSpeed:
        """Boundary speed ``speed_fraction``·c, reached smoothly over ``ramp_fraction``."""
        v = self.speed_fraction * self.wave_speed_m_s(model)
        total = self.travel_m(model) / v
        return SmoothStartSpeed(v, self.ramp_fraction * total / (1 - self.ramp_fraction / 2))

    def loading(self, model: BeadModel) -> SmoothStartSpeed:
        """The nominal loading, a hair slower (less than one output interval over the test)
        so that the travel ends exactly on the last step, the last sample."""
        return self.plan(model).loading

    def duration_s(self, model: BeadModel) -> float:
        """Nominal duration of the loading [s]."""
        return self.nominal_loading(model).time_for(self.travel_m(model))

    def time_step_s(self, model: BeadModel) -> float:
        return self.plan(model).time_step_s

    def every(self, model: BeadModel) -> int:
        return self.plan(model).every

    def steps(self, model: BeadModel) -> int:
        """Whole output intervals, so that the last sample is the end of the test."""
        return self.plan(model).steps

    def gamma(self, model: BeadModel) -> float:
        """Viscous damping coefficient γ = m/τ [kg/s] (τ default: a tenth of the test)."""
        return self.plan(model).gamma_kg_s

    # -- the plan: derived once per model, kept in the run folder -------------------------
    def plan_contacts(self) -> tuple:
        """The contacts whose stiffness bounds the time step (a protocol with tools adds
        them)."""
        return (self.contact,)

    def plan(self, model: BeadModel) -> RunPlan:
        """Time step, steps, output interval, loading and damping of a run on ``model``:
        derived once (:meth:`derive_plan`) and kept until asked for another model."""
        return cached_plan(self, model, self.derive_plan)

    def derive_plan(self, model: BeadModel) -> RunPlan:
        """The one place the plan is derived (see :meth:`plan`)."""
        cls = type(self)
        duration = self.duration_s(model)
        # a subclass that still overrides time_step_s/every/gamma (drape, until it
        # moves to plan_contacts) keeps its own values
        if cls.time_step_s is not DrivenTest.time_step_s:
            dt = self.time_step_s(model)
        else:
            dt = stable_time_step_s(model, self.plan_contacts(), self.time_step)
        if cls.every is not DrivenTest.every:
            every = self.every(model)
        else:
            every = max(1, math.ceil(duration / dt) // self.samples)
        steps = every * math.ceil(duration / dt / every)
        k = duration / (steps * dt)
        nominal = self.nominal_loading(model)
        mass = float(np.median(model.masses))
        tau = self.damping_time_s or duration / 10
        gamma = mass / tau
        if cls.gamma is not DrivenTest.gamma:
            gamma = self.gamma(model)
            tau = mass / gamma
        return RunPlan(time_step_s=dt, steps=steps, every=every, duration_s=duration,
                       speed_m_s=nominal.speed_m_s * k, ramp_time_s=nominal.ramp_time_s / k,
                       damping_time_s=tau, gamma_kg_s=gamma)

    def read_plan(self, run_dir: Path, model: BeadModel) -> RunPlan:
        """The plan ``run_dir`` was run with (``plan.json``); derived again for a folder
        written before plans were kept."""
        return read_plan(run_dir) or self.plan(model)

    def drag_block(self, model: BeadModel, field: AffineField) -> tuple[str, str]:
        """(LAMMPS text, per-bead damping power) of the drag on the free beads: relative to
        the tools' affine velocity ``field`` (``drag = "affine"``) or on the absolute
        velocity (``"absolute"``); :mod:`fabmd.scene.drag`."""
        return drag_commands(getattr(self, "drag", "absolute"), "free", self.gamma(model), field)

    def check_loading(self) -> None:
        """Validate the fields every driven test has (speed, ramp, damping time, samples,
        trajectory); errors name ``<protocol>.<field>``."""
        name = self.protocol
        inputs.in_range(f"{name}.speed_fraction", self.speed_fraction, 0, 0.05, low_open=True)
        inputs.in_range(f"{name}.ramp_fraction", self.ramp_fraction, 0, 0.9)
        if self.damping_time_s is not None:
            inputs.positive(f"{name}.damping_time_s", self.damping_time_s)
        inputs.positive_int(f"{name}.samples", self.samples, minimum=10)
        check_trajectory(f"{name}.trajectory", self.trajectory)
        if hasattr(self, "drag"):
            inputs.one_of(f"{name}.drag", self.drag, DRAG_KINDS)

    def scene_text(self, model: BeadModel, dt: float, protocol_text: str, *extra: str,
                   after: tuple[str, ...] | None = None) -> str:
        """The whole input: set-up, bonds, contact, the test's own text and the contact-power
        sampling (energy balance), then ``after``; by default the trajectory outputs,
        ``extra``, the guards, the run and the final data file."""
        beads = model_bead_parameters(model)
        if after is None:
            after = (self.trajectory_block(model), *extra, blocks.guards(model, dt),
                     render("run", steps=self.steps(model)),
                     self.trajectory.final_commands(),
                     render("finish", final_data="final.data"))
        return "\n".join([
            blocks.setup(model, self.protocol, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            protocol_text,
            ContactPower.commands(),
            *after,
        ])

    def trajectory_block(self, model: BeadModel) -> str:
        """Outputs block of the trajectory (``self.trajectory``): about ``frames`` frames
        over the test, on output steps (the interval a multiple of :meth:`every`). Put
        ``self.trajectory.final_commands()`` after the run."""
        return self.trajectory.commands(self.steps(model), multiple_of=self.every(model))

    def relax_block(self, model: BeadModel, held: str, free: str,
                    reference_force_n: float) -> str:
        """Free relaxation with ``held`` fixed until quasi-static (``self.relax``)."""
        k = max(bt.spring_n_per_m for bt in model.fibre_bond_types())
        n = int(model.fibre_bond_mask().sum())
        return blocks.relax(model, self.time_step_s(model), held, free, self.relax,
                            reference_force_n, n * reference_force_n**2 / (2 * k))

    def outputs_block(self, model: BeadModel, external_power: str, external_ref: str,
                      mean_values: str = "", mean_names: str = "", print_values: str = "",
                      print_names: str = "", thermo_values: str = "",
                      damping_power: str | None = None) -> str:
        """Interval means, printed curve and thermo (``driven_outputs.lmp``);
        ``damping_power``: the drag's power per free bead (default: that of a drag
        γ·v on the absolute velocity)."""
        every = self.every(model)
        strain = "ebond+eangle" if len(model.angles) else "ebond"
        if damping_power is None:
            damping_power = f"{self.gamma(model):.10g}*(vx*vx+vy*vy+vz*vz)"
        return render("driven_outputs", external_power=external_power, strain_energy=strain,
                      external_ref=external_ref, damping_power=damping_power, every=every,
                      mean_values=mean_values, mean_names=mean_names,
                      print_values=print_values, print_names=print_names,
                      thermo_values=thermo_values,
                      thermo_every=max(every, self.steps(model) // 20))

    # -- run ------------------------------------------------------------------------
    def run(self, model: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False, check_rate: bool = False, resume: bool = False,
            monitor: ContactPower | None = None) -> DrivenResult:
        """Run the test on ``model``.

        Args:
            check_rate: rerun at half speed and report how much the curve moved.
            resume: continue an interrupted run in ``out`` from its last checkpoint
                (``Engine(checkpoint_every=...)`` writes them).
            monitor: the contact-power monitor (default: a new one).
        """
        engine = engine or Engine()
        start = self.prepare(model)
        text = self.input_text(start)  # validates before anything is written
        if resume:
            run_dir = resume_folder(out)
        else:
            run_dir = write_run_folder(out, self.protocol, start, text,
                                       {self.protocol: scene_dict(self)}, overwrite=overwrite)
            if mpi.is_root():
                self.plan(start).write(run_dir)
        monitor = monitor or self.make_monitor()
        paraview = self.trajectory.paraview
        try:
            run = engine.run(run_dir, input_name(self.protocol), label=self.protocol,
                             monitor=monitor, monitor_every=self.every(start), resume=resume)
        except SimulationFailed:
            salvage(run_dir, paraview=paraview, model=start)  # the frames up to the failure
            raise
        trajectory = finalise(run_dir, paraview=paraview, model=start)
        result = None
        if mpi.is_root():
            result = self.reduce(run_dir, start, monitor)
            result.summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend,
                                  trajectory=trajectory.name if trajectory else None)
            if getattr(self, "relax", None) is not None and not resume:  # starts relaxing
                result.summary["start_settled"] = relaxation_settled(run_dir / "log.lammps")
            spike = start_spike_ratio(result.curve.get(self.rate_curve[1]))
            if spike is not None:
                result.summary["start_spike_ratio"] = spike
            if self.interval_axis is not None:
                add_interval_verdict(result, *self.interval_axis)
            verdict = quasi_static_verdict(result.summary, self.quasi_static_limits)
            result.summary["quasi_static"] = verdict
            if not verdict["ok"]:
                mark_plots(result, verdict, self.interval_axis)
                where = ("; trust only " + ", ".join(f"{a:g}-{b:g}" for a, b in
                                                     verdict["trusted"])
                         if verdict.get("partly") else ": do not use the curve")
                warnings.warn(f"{self.protocol} in {run_dir}: not quasi-static "
                              f"({'; '.join(verdict['problems'])}){where}; "
                              f"{'; '.join(verdict['remedies'])}", QuasiStaticWarning,
                              stacklevel=2)
        if check_rate:
            slow = dataclasses.replace(self, speed_fraction=self.speed_fraction / 2)
            other = slow.run(model, out=Path(run_dir) / "half_speed", engine=engine)
            if mpi.is_root():
                result.summary["rate_check"] = self.compare_rates(result, other)
        if mpi.is_root():
            result.write()
        return shared_result(result, run_dir)

    def compare_rates(self, fast: DrivenResult, slow: DrivenResult) -> dict:
        """How much the curve and the named summary values moved at half speed."""
        x, y = self.rate_curve
        report = {"half_speed_run": str(slow.run_dir),
                  "max_relative_force_change": curve_difference(
                      fast.curve[x], fast.curve[y], slow.curve[x], slow.curve[y]),
                  "compared": f"{y} against {x}, above a fifth of the common range"}
        for name, key in self.rate_keys.items():
            report[name] = relative_change(slow.summary.get(key), fast.summary.get(key))
        if "wall_s" in slow.summary:
            report["half_speed_wall_s"] = slow.summary["wall_s"]
        return report


def damping_share(summary: dict) -> float | None:
    """Share of the external work the viscous drag dissipated."""
    balance_ = summary.get("energy_balance") or {}
    work, drag = balance_.get("external_work_j"), balance_.get("damping_dissipation_j")
    return drag / work if work and drag is not None and work > 0 else None


def quasi_static_verdict(summary: dict, limits: dict[str, float] | None = None) -> dict:
    """Is the curve quasi-static, and does its energy balance close? Each measure in
    ``limits`` (default
    :data:`QUASI_STATIC_LIMITS`) is read from the summary (``damping_share`` computed from
    its energy balance); a measure the test does not report is not judged. A summary whose
    ``start_settled`` is False (the relaxation before the loading did not settle) fails.
    With a per-interval verdict (``quasi_static_intervals``, :func:`add_interval_verdict`)
    every failed interval is a problem too; ``partly`` is True when only intervals failed
    and some passed (``trusted``: their ranges), so the rest of the curve can be used."""
    limits = QUASI_STATIC_LIMITS if limits is None else limits
    derived = {"damping_share": lambda: damping_share(summary),
               "energy_balance_error": lambda: (summary.get("energy_balance") or {}).get(
                   "relative_error")}
    values = {name: derived[name]() if name in derived else summary.get(name)
              for name in limits}
    problems = [f"{name} = {v:.2g} > {limits[name]:g}" for name, v in values.items()
                if v is not None and v > limits[name]]
    failed = [name for name, v in values.items() if v is not None and v > limits[name]]
    if summary.get("start_settled") is False:
        problems.append("the specimen was still moving when the loading started (its "
                        "relaxation did not settle within relax.max_steps)")
        failed.append("start_settled")
    intervals = summary.get("quasi_static_intervals")
    whole_run_ok = not problems
    trusted = flagged = []
    if intervals:
        trusted, flagged = intervals["trusted"], intervals["flagged"]
        interval_problems = [p for i in intervals["intervals"] for p in i["problems"]]
        problems += interval_problems
        if interval_problems:
            failed.append("interval")
    remedies = list(dict.fromkeys(f"{name}: {QUASI_STATIC_REMEDIES.get(name, GENERIC_REMEDY)}"
                                  for name in failed))
    return {"ok": not problems, "values": values, "limits": dict(limits),
            "problems": problems, "remedies": remedies, "flagged": flagged,
            "trusted": trusted, "partly": bool(whole_run_ok and flagged and trusted)}


GENERIC_REMEDY = "lower speed_fraction, or check the specimen holds together"
#: what to change when a quasi-static measure fails (scene-file fields of the test table)
QUASI_STATIC_REMEDIES = {
    "max_kinetic_to_strain_energy": "inertia: lower speed_fraction",
    "max_kinetic_to_external_work": "inertia: lower speed_fraction",
    "mean_inertial_to_punch_force": "inertia: lower speed_fraction",
    "damping_share": "the drag takes the work: raise damping_time_s (less drag), or "
                     "lower speed_fraction",
    "energy_balance_error": "the energy does not balance (time step or contact): lower "
                            "time_step.factor, or raise the contact stiffness_factor; a "
                            "lower speed_fraction does not cure it",
    "start_spike_ratio": "the force jumps when the loading starts, before the clamps have "
                         "moved (strain energy stored in the start state is released; a "
                         "fibre far stiffer than the rest makes this likely): relax the start "
                         "state further (lower relax.force_ratio and relax.kinetic_ratio, "
                         "raise relax.max_steps); a lower speed_fraction does not cure it",
    "start_settled": "the specimen was not at rest when the loading started: raise "
                     "relax.max_steps (or lower relax.kinetic_ratio); a lower speed_fraction "
                     "does not cure it",
    "interval": "part of the curve is not quasi-static (the flagged intervals): lower "
                "speed_fraction, or use only the trusted ranges",
}


def start_spike_ratio(force, fraction: float = 0.05) -> float | None:
    """Largest |force| in the first ``fraction`` of the samples (the first excluded: it is
    printed before any force) over the largest after them; above 1 the force jumps when
    the loading starts, before the clamps have moved: the start state was not in
    equilibrium. None for curves too short to tell."""
    if force is None:
        return None
    f = np.abs(np.asarray(force, float))
    head = max(2, int(round(fraction * len(f))) + 1)
    if len(f) < head + 2:
        return None
    later = float(f[head:].max())
    early = float(f[1:head].max())
    return early / max(later, 1e-300) if early > 0 else 0.0


def add_interval_verdict(result: DrivenResult, column: str, width: float) -> dict:
    """Judge ``result``'s curve per interval of ``column`` (:func:`~fabmd.scene.
    quasi_static.interval_verdict`): the verdict goes into the summary
    (``quasi_static_intervals``), its per-sample columns into the curve."""
    c = result.curve
    verdict = interval_verdict(c[column], c["external_work_j"], c["damping_dissipation_j"],
                               c["kinetic_energy_j"], c["strain_energy_j"], width,
                               name=column)
    result.summary["quasi_static_intervals"] = verdict
    result.curve.update(interval_columns(c[column], verdict))
    return verdict


def mark_plots(result: DrivenResult, verdict: dict,
               interval_axis: tuple[str, float] | None) -> None:
    """Say on every plot that the curve is not (or only partly) quasi-static: a
    whole-run failure in the title, failed intervals shaded (a plot spec whose x is not
    the interval column names its own: ``x_column``, ``x_scale``)."""
    for spec in getattr(result, "plots", []):
        if verdict.get("partly") and interval_axis is not None:
            column = spec.get("x_column", interval_axis[0])
            scale = spec.get("x_scale", 1.0)
            axis = result.curve[interval_axis[0]]
            spec["spans"] = [[scale * float(np.interp(v, axis, result.curve[column]))
                              for v in ab] for ab in verdict["flagged"]]
            spec["title"] = "PARTLY NOT QUASI-STATIC (shaded): " + spec.get("title", "")
        else:  # no plot that looks valid
            spec["title"] = "NOT QUASI-STATIC, do not use: " + spec.get("title", "")
        spec["notes"] = "\n".join([spec.get("notes", ""), *verdict["problems"][:4]])


def shared_result(result: DrivenResult | None, run_dir: Path) -> DrivenResult:
    """Rank 0's result on every rank: its summary broadcast (other ranks get a result
    with that summary and no curve)."""
    summary = mpi.bcast_json(result.summary if result else None)
    if result is None:
        result = DrivenResult(Path(run_dir), {}, summary)
    result.summary = summary
    return result


def relative_change(a, b) -> float | None:
    """|a − b| / |b| (None when either is missing or b is 0)."""
    if a is None or b is None or not b:
        return None
    return abs(a - b) / abs(b)


# -- reading a driven run back ----------------------------------------------------------
@dataclass
class Outputs:
    """``curve.dat`` columns, with the interval means of ``means.dat`` put on its steps
    (a mean is reported at its interval's end; 0 at step 0) and the cumulative works."""

    columns: dict[str, np.ndarray]
    means: dict[str, np.ndarray]
    external_work_j: np.ndarray
    damping_j: np.ndarray
    contact_j: np.ndarray | None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]


def read_outputs(run_dir: Path, every: int, dt: float,
                 monitor: ContactPower | None = None) -> Outputs:
    """Read ``curve.dat`` and ``means.dat`` of a driven run."""
    raw = read_print_file(Path(run_dir) / "curve.dat")
    means = read_ave_time(Path(run_dir) / "means.dat")
    for name in means:
        if name != "step":
            raw[name] = np.interp(raw["step"], means["step"], means[name], left=0.0)
    external = np.interp(raw["step"], means["step"],
                         cumulative(means["external_power_w"], every, dt), left=0.0)
    damping = np.interp(raw["step"], means["step"],
                        cumulative(means["damping_power_w"], every, dt), left=0.0)
    contact = monitor.work_j(raw["step"], dt) if monitor is not None else None
    return Outputs(raw, means, external, damping, contact)


def energy_columns(out: Outputs) -> dict[str, np.ndarray]:
    """The energy columns every driven curve carries."""
    cols = {"kinetic_energy_j": out["kinetic_j"], "strain_energy_j": out["strain_energy_j"],
            "external_work_j": out.external_work_j, "damping_dissipation_j": out.damping_j}
    if out.contact_j is not None:
        cols["contact_work_j"] = out.contact_j
    return cols


def energy_balance(out: Outputs) -> dict:
    """External work = Δ strain + Δ kinetic + damping + contact work, closing error."""
    return balance(out.external_work_j, out["strain_energy_j"], out["kinetic_j"],
                   out.damping_j, out.contact_j)


def kinetic_ratio(out: Outputs, started: np.ndarray) -> float | None:
    """Largest kinetic / strain energy after start-up (None when nothing is started)."""
    ratio = out["kinetic_j"][started] / np.maximum(out["strain_energy_j"][started], 1e-300)
    return float(ratio.max()) if ratio.size else None


def kinetic_to_work_ratio(out: Outputs, started: np.ndarray) -> float | None:
    """Largest kinetic energy / external work done so far, after start-up."""
    ratio = out["kinetic_j"][started] / np.maximum(np.abs(out.external_work_j[started]), 1e-300)
    return float(ratio.max()) if ratio.size else None


STARTED_NOTE = ("kinetic/strain energy after start-up: after the smooth start, the first "
                "tenth of the test, and once the strain energy gained exceeds 1 % of its final "
                "gain (a slack fabric carries no load at first)")


def started_mask(out: Outputs, loading: SmoothStartSpeed, progress: np.ndarray,
                 fraction: float = 0.1) -> np.ndarray:
    """After start-up (see :data:`STARTED_NOTE`); ``progress`` of the test in [0, 1]."""
    u = out["strain_energy_j"]
    loaded = (u - u[0]) > 0.01 * (u[-1] - u[0])
    return (out["time_s"] > loading.ramp_time_s) & (np.asarray(progress) > fraction) & loaded


def clamp_power(group: str = "clamps") -> tuple[str, str]:
    """(LAMMPS text, reference) of the power put in through the beads of ``group``."""
    return render("clamp_power", group=group), "c_p_ext"

