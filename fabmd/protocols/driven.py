"""What every displacement-driven quasi-static test shares.

A driven test (tension, picture frame, bias extension, periodic cells) moves a
boundary — clamps or the periodic box — at a constant speed reached by a smooth
start (:class:`~fabmd.scene.loading.SmoothStartSpeed`), damps the free beads with a
drag γ = m/τ on their motion relative to the tools' affine velocity field
(:mod:`fabmd.scene.drag`; protocols without ``drag`` damp the absolute velocity) and
writes, through ``lammps_templates/driven_outputs.lmp``:

* ``means.dat`` — forces and powers averaged over each output interval (integrals of
  the external and the damping power, sampled every :data:`MEAN_SAMPLE_EVERY` steps
  when the interval is long: :func:`mean_sample_every`);
* ``curve.dat`` — clock, boundary displacement(s) and energies at the output steps;
* the trajectory (``trajectory.h5``, ParaView files; :mod:`fabmd.scene.outputs`)
  with frames on output steps and the last step as the last frame.

:class:`DrivenTest` is the keyword-only frozen dataclass the protocols derive from: it
declares the fields every driven test has (``speed_fraction``, ``ramp_fraction``,
``damping_time_s``, ``contact``, ``time_step``, ``samples``, ``trajectory``; a protocol
only redeclares the ones whose default differs) and turns them plus the protocol's travel
into the loading, the time step, the output interval and the step count; its :meth:`run`
writes the run folder, runs it with the contact-power monitor, converts the
trajectory (after a failed run too: the frames up to the failure), reduces it, judges it
(:mod:`fabmd.protocols.verdict`), and with ``check_rate`` reruns at half speed and
reports how much the curve moved. :class:`RelaxedDrivenTest` adds the free relaxation
before the loading (``relax``), :class:`ClampedTest` the drag choice of the coupon tests
(``drag``). :mod:`fabmd.protocols.driven_outputs` reads a run back (its
:func:`~fabmd.protocols.driven_outputs.read_outputs`, ``energy_columns``) and
:meth:`DrivenTest.quasi_static_evidence` assembles the quasi-static evidence the same way
for every protocol.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import inputs
from ..engine import Engine, mpi
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..model.beads import TimeStep, model_bead_parameters
from ..model.contact import ContactModel
from ..model.timestep import stable_time_step_s
from ..results.curves import curve_difference
from ..results.plots import plot_curves
from ..scene import blocks
from ..scene.drag import DRAG_KINDS, AffineField, drag_commands
from ..scene.drag import damping_power as drag_power
from ..scene.energy import (
    MEAN_SAMPLE_EVERY,
    MEAN_SAMPLING_FROM,
    ContactEnergy,
    ContactPower,
    mean_sample_every,
)
from ..scene.loading import SmoothStartSpeed
from ..scene.outputs import TrajectoryOutput, check_trajectory
from ..scene.plan import RunPlan, cached_plan, read_plan
from ..scene.quasi_static import QuasiStatic, relaxation_settled
from ..scene.start import START_KINDS, affine_start
from ..scene.templates import render
from .common import DATA_FILE, RunResult, open_run_folder, run_with_trajectory, scene_dict
from .driven_outputs import (
    STARTED_NOTE,
    Outputs,
    energy_balance,
    kinetic_ratio,
    kinetic_to_work_ratio,
    started_mask,
)
from .verdict import QUASI_STATIC_LIMITS, judge
from .verdict import quasi_static_verdict as quasi_static_verdict  # its old home
from .verdict import start_spike_ratio as start_spike_ratio  # its old home

#: what U of the KE/U measures counts (summary ``elastic_energy``): with the contacts'
#: elastic energy sampled (in-process) or not (standalone)
ELASTIC_NOTE = {True: "U = bond strain energy + the contacts' elastic energy (normal springs "
                      "and the within-family law; tangential springs left out)",
                False: "U = bond strain energy only (the contacts' elastic energy is sampled "
                       "by the in-process back end only, or a sample's pairs did not line "
                       "up)"}

#: which kinetic energy KE/U and KE/work count (summary ``kinetic_energy``; the inertia share
#: keeps the absolute one): relative to the tools' affine field where the test has one
KINETIC_NOTE = {True: "KE of KE/U and KE/work relative to the tools' affine velocity field "
                      "(what they carry along is not counted); the per-interval inertia "
                      "share |dKE|/dW: absolute KE",
                False: "KE of KE/U: absolute (the test has no affine field)"}


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


@dataclass(frozen=True, kw_only=True)
class DrivenTest:
    """Base of the displacement-driven protocols (see the module docstring).

    A subclass is a frozen dataclass with its own fields, then the fields below whose
    default it changes (redeclared); it sets the class constants ``protocol``,
    ``rate_curve`` (x and y columns compared by ``check_rate``), ``rate_keys`` (summary
    keys compared by ``check_rate``: {report name: key}) and others declared here (plain
    assignments: the ``ClassVar`` declarations here keep them out of the fields), and
    defines :meth:`travel_m`, :meth:`input_text` and :meth:`reduce`;
    :meth:`check_fields` validates its own fields when it is built; ``plan_*`` adapt its plan.

    Args:
        speed_fraction: speed of the driven boundary (clamp, corner, box face, punch)
            over the fibres' axial wave speed, in (0, 0.05] (quasi-static when small;
            check with ``check_rate``).
        ramp_fraction: share of the test spent reaching full speed smoothly, in [0, 0.9]
            (``start = "smooth"``).
        start: how the loading starts (:mod:`fabmd.scene.start`): ``"smooth"`` (the
            tools reach full speed over ``ramp_fraction`` of the test, from a fabric at
            rest) or ``"affine"`` (the free fabric starts with the tools' affine velocity
            and the tools at full speed: they need not accelerate the fabric they carry;
            protocols with an affine field and a fixed speed). None (default):
            ``"affine"`` where the protocol can (picture frame, periodic cells) at a fixed
            speed, else ``"smooth"`` (:meth:`start_kind`; the tension takes ``"affine"``
            when asked).
        damping_time_s: τ of the drag γ = m/τ on the free beads [s] (default: a tenth
            of the test).
        contact: fibre–fibre contact.
        time_step: time-step policy.
        samples: curve points (>= 10).
        trajectory: trajectory frames over the test (``trajectory.h5``, ParaView files;
            ``TrajectoryOutput(frames=0)`` writes none).
    """

    speed_fraction: float = 1e-4
    ramp_fraction: float = 0.1
    start: str | None = None
    damping_time_s: float | None = None
    contact: ContactModel = field(default_factory=ContactModel)
    time_step: TimeStep = field(default_factory=TimeStep)
    samples: int = 200
    trajectory: TrajectoryOutput = field(default_factory=lambda: TrajectoryOutput(frames=20))

    protocol: ClassVar[str] = ""
    rate_curve: ClassVar[tuple[str, str]] = ("", "")
    rate_keys: ClassVar[dict[str, str]] = {}
    #: the quasi-static measures judged after the run (summary key -> largest allowed)
    quasi_static_limits: ClassVar[dict[str, float]] = QUASI_STATIC_LIMITS
    #: (curve column, interval width) of the per-interval quasi-static verdict (None: none)
    interval_axis: ClassVar[tuple[str, float] | None] = None
    #: whether the protocol can start the fabric with its tools' affine field (``start``)
    affine_start_supported: ClassVar[bool] = False
    #: whether ``start = None`` means ``"affine"`` where it is supported (at a fixed speed)
    affine_start_default: ClassVar[bool] = True
    #: what the kinetic-energy measures of the summary cover (:meth:`quasi_static_evidence`)
    quasi_static_note: ClassVar[str] = ("kinetic energy over the elastic energy (bonds and "
                                        "contacts: elastic_energy) and over the work done "
                                        "so far, after the smooth start (if any) and the "
                                        "first tenth of the test")

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

    def make_monitor(self, model: BeadModel | None = None) -> ContactPower:
        """The contact-power monitor; on ``model`` it samples the contacts' elastic energy
        too (:class:`~fabmd.scene.energy.ContactEnergy`)."""
        energy = None if model is None else ContactEnergy.for_contact(
            self.contact, model_bead_parameters(model), model.family_names)
        return ContactPower(self.contact.pair_style(), energy)

    def quasi_static_evidence(self, out: Outputs, model: BeadModel, progress: np.ndarray,
                              work_ratio: bool = True) -> dict:
        """The summary's quasi-static evidence: the largest kinetic / strain energy and
        (``work_ratio``) kinetic energy / work done after start-up (:func:`started_mask`;
        ``progress`` of the test in [0, 1]), what they cover (``quasi_static_note``;
        :data:`STARTED_NOTE` without ``work_ratio``) and the energy balance."""
        started = started_mask(out, self.loading(model), progress)
        evidence = {"max_kinetic_to_strain_energy": kinetic_ratio(out, started)}
        if work_ratio:
            evidence["max_kinetic_to_external_work"] = kinetic_to_work_ratio(out, started)
        note = self.quasi_static_note if work_ratio else STARTED_NOTE
        evidence.update(quasi_static_note=note, energy_balance=energy_balance(out),
                        elastic_energy=ELASTIC_NOTE[out.contact_energy_measured],
                        kinetic_energy=KINETIC_NOTE["kinetic_relative_j" in out.columns])
        return evidence

    # -- loading and time ------------------------------------------------------------
    def wave_speed_m_s(self, model: BeadModel) -> float:
        """Slowest axial wave speed of the fibres, c = l0·sqrt(k/m) [m/s]."""
        return min(b.wave_speed_m_s for b in model_bead_parameters(model))

    def nominal_loading(self, model: BeadModel) -> SmoothStartSpeed:
        """Boundary speed ``speed_fraction``·c, reached smoothly over ``ramp_fraction``
        (at once where the fabric starts moving with the tools, ``start = "affine"``)."""
        v = self.speed_fraction * self.wave_speed_m_s(model)
        total = self.travel_m(model) / v
        if self.start_kind() == "affine":
            return SmoothStartSpeed(v, 0.0)
        return SmoothStartSpeed(v, self.ramp_fraction * total / (1 - self.ramp_fraction / 2))

    def adaptive_loading(self) -> bool:
        """Whether the speed is adapted as the test goes (``loading_speed.adaptive``)."""
        return bool(getattr(getattr(self, "loading_speed", None), "adaptive", False))

    def start_kind(self) -> str:
        """``start``, or where None: ``"affine"`` if the protocol can start the fabric with
        its tools at a fixed speed, else ``"smooth"``."""
        if self.start is not None:
            return self.start
        return ("affine" if self.affine_start_supported and self.affine_start_default
                and not self.adaptive_loading() else "smooth")

    def start_block(self, field: AffineField) -> str:
        """LAMMPS text of the free fabric's start (``start``): at rest (a comment), or
        with the tools' affine velocity ``field`` at the start (:mod:`fabmd.scene.start`;
        its gradient must be valid before the run)."""
        if self.start_kind() != "affine":
            return f"# the fabric starts at rest: the {field.tools}' speed ramps up smoothly"
        return affine_start("free", field)

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
        """Viscous damping coefficient γ = m/τ [kg/s] (τ: :meth:`plan_damping_time_s`)."""
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

    def plan_every(self, duration_s: float, dt: float) -> int:
        """Output interval [steps]: about ``samples`` curve points over ``duration_s``; a
        multiple of :data:`MEAN_SAMPLE_EVERY` when long enough to sample the means."""
        raw = max(1, math.ceil(duration_s / dt) // self.samples)
        if raw < MEAN_SAMPLING_FROM:
            return raw
        return MEAN_SAMPLE_EVERY * (raw // MEAN_SAMPLE_EVERY)

    def plan_damping_time_s(self, duration_s: float) -> float:
        """τ of the drag [s]: ``damping_time_s``, default a tenth of the test."""
        return self.damping_time_s or duration_s / 10

    def derive_plan(self, model: BeadModel) -> RunPlan:
        """The one place the plan is derived (see :meth:`plan`)."""
        duration = self.duration_s(model)
        dt = stable_time_step_s(model, self.plan_contacts(), self.time_step)
        every = self.plan_every(duration, dt)
        steps = every * math.ceil(duration / dt / every)
        k = duration / (steps * dt)
        nominal = self.nominal_loading(model)
        tau = self.plan_damping_time_s(duration)
        gamma = float(np.median(model.masses)) / tau
        plan = RunPlan(time_step_s=dt, steps=steps, every=every, duration_s=duration,
                       speed_m_s=nominal.speed_m_s * k, ramp_time_s=nominal.ramp_time_s / k,
                       damping_time_s=tau, gamma_kg_s=gamma)
        return self.plan_loading(plan, model)

    def plan_loading(self, plan: RunPlan, model: BeadModel) -> RunPlan:
        """The fixed-speed ``plan`` adapted to the test's loading (a protocol with
        adaptive loading: :func:`fabmd.scene.adaptive.adaptive_plan`); unchanged here."""
        return plan

    def read_plan(self, run_dir: Path, model: BeadModel) -> RunPlan:
        """The plan ``run_dir`` was run with (``plan.json``); derived again for a folder
        written before plans were kept."""
        return read_plan(run_dir) or self.plan(model)

    def after_verdict(self, result: DrivenResult) -> None:
        """Mark what the summary reports from flagged intervals (default: nothing)."""

    def drag_block(self, model: BeadModel, field: AffineField) -> tuple[str, str]:
        """(LAMMPS text, per-bead damping power) of the drag on the free beads: relative to
        the tools' affine velocity ``field`` (``drag = "affine"``) or on the absolute
        velocity (``"absolute"``); :mod:`fabmd.scene.drag`."""
        return drag_commands(getattr(self, "drag", "absolute"), "free", self.gamma(model), field)

    def __post_init__(self):
        self.check_fields()
        self.check_loading()

    def check_fields(self) -> None:
        """Validate the protocol's own fields (errors name ``<protocol>.<field>``)."""

    def check_positive_or_none(self, *names: str) -> None:
        """Each field in ``names`` None (the default is derived) or > 0."""
        for name in names:
            if getattr(self, name) is not None:
                inputs.positive(f"{self.protocol}.{name}", getattr(self, name))

    def check_loading(self) -> None:
        """Validate the fields every driven test has (speed, ramp, damping time, samples,
        trajectory); errors name ``<protocol>.<field>``."""
        name = self.protocol
        inputs.in_range(f"{name}.speed_fraction", self.speed_fraction, 0, 0.05, low_open=True)
        inputs.in_range(f"{name}.ramp_fraction", self.ramp_fraction, 0, 0.9)
        if self.start is not None:
            inputs.one_of(f"{name}.start", self.start, START_KINDS)
        if self.start == "affine" and not self.affine_start_supported:
            raise InputError(f"{name}.start = \"affine\" is built for the picture frame, "
                             f"the periodic cells and the tension only; use \"smooth\"")
        if self.start == "affine" and self.adaptive_loading():
            raise InputError(f"{name}.start = \"affine\" starts at the full fixed speed; "
                             f"adaptive loading (loading_speed.adaptive = true) starts "
                             f"smoothly: use start = \"smooth\"")
        self.check_positive_or_none("damping_time_s")
        inputs.positive_int(f"{name}.samples", self.samples, minimum=10)
        check_trajectory(f"{name}.trajectory", self.trajectory)
        if hasattr(self, "drag"):
            inputs.one_of(f"{name}.drag", self.drag, DRAG_KINDS)

    def scene_text(self, model: BeadModel, dt: float, protocol_text: str, *extra: str,
                   after: tuple[str, ...] | None = None, header: str | None = None) -> str:
        """The whole input: set-up, bonds, contact, the test's own text and the contact-power
        sampling (energy balance), then ``after``; by default the trajectory outputs,
        ``extra``, the guards, the run and the final data file. ``header`` names the test
        in the first comment line (default: the protocol)."""
        beads = model_bead_parameters(model)
        if after is None:
            after = (self.trajectory_block(model), *extra, blocks.guards(model, dt),
                     render("run", steps=self.steps(model)),
                     self.trajectory.final_commands(),
                     render("finish", final_data="final.data"))
        return "\n".join([
            blocks.setup(model, header or self.protocol, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            protocol_text,
            ContactPower.commands(self.contact.pair_style()),
            ContactEnergy.commands(),
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
                      damping_power: str | None = None,
                      affine: AffineField | None = None) -> str:
        """Interval means, printed curve and thermo (``driven_outputs.lmp``);
        ``damping_power``: LAMMPS text defining ``v_p_damp``, the drag's power on the free
        beads (:func:`fabmd.scene.drag.damping_power`; default: that of a drag γ·v on the
        absolute velocity); ``affine``: the tools' affine velocity field, whose relative
        kinetic energy the curve then prints too (``kinetic_relative_j``,
        ``kinetic_relative.lmp``)."""
        block = ""
        if affine is not None:
            block = render("kinetic_relative", tools=affine.tools, affine_vx=affine.vx,
                           affine_vy=affine.vy)
            print_values = f"{print_values} ${{ke_rel}}".strip()
            print_names = f"{print_names} kinetic_relative_j".strip()
        every = self.every(model)
        sample_every = mean_sample_every(every)
        strain = "ebond+eangle" if len(model.angles) else "ebond"
        if damping_power is None:
            damping_power = drag_power("free", self.gamma(model))
        return block + render(
            "driven_outputs", external_power=external_power, strain_energy=strain,
            external_ref=external_ref, damping_power=damping_power, every=every,
            sample_every=sample_every, samples=every // sample_every,
            mean_values=mean_values, mean_names=mean_names, print_values=print_values,
            print_names=print_names, thermo_values=thermo_values,
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
        run_dir = open_run_folder(out, self.protocol, start, text,
                                  {self.protocol: scene_dict(self)}, overwrite, resume,
                                  plan=self.plan(start), files=blocks.contact_files(
                                      self.contact, model_bead_parameters(start)))
        monitor = monitor or self.make_monitor(start)
        run, trajectory = run_with_trajectory(engine, run_dir, self.protocol, self.trajectory,
                                              start, resume, monitor=monitor,
                                              monitor_every=self.every(start))
        result = None
        if mpi.is_root():
            result = self.reduce(run_dir, start, monitor)
            result.summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend,
                                  trajectory=trajectory.name if trajectory else None)
            if getattr(self, "relax", None) is not None and not resume:  # starts relaxing
                result.summary["start_settled"] = relaxation_settled(run_dir / "log.lammps")
            judge(result, self.protocol, run_dir, self.quasi_static_limits,
                  self.interval_axis, self.rate_curve[1])
            self.after_verdict(result)
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


@dataclass(frozen=True, kw_only=True)
class RelaxedDrivenTest(DrivenTest):
    """A driven test whose specimen first relaxes free, the driven boundary held.

    Args:
        relax: stop criterion of the free relaxation before the test (clamps held).
        drag: ``"affine"`` (default): the drag acts on the motion relative to the affine
            velocity field the clamps, frame or box impose (what the protocol's docstring
            says it holds), so it does not add to their force; ``"absolute"``: on the
            absolute velocity (on the plain-weave example's periodic cell it was half the
            shear work below 20°, ``benchmarks/RESULTS.md`` "Periodic shear: drag and the
            yarns' stretch"). :mod:`fabmd.scene.drag`.
    """

    relax: QuasiStatic = field(default_factory=lambda: QuasiStatic(max_steps=50_000))
    drag: str = "affine"


@dataclass(frozen=True, kw_only=True)
class ClampedTest(RelaxedDrivenTest):
    """A coupon held by moving clamps (tension, bias extension, picture frame); its
    ``drag`` (:class:`RelaxedDrivenTest`) is relative to the clamps' affine field."""

    quasi_static_note = (
        "kinetic energy of the free fabric (relative to the clamps' or frame's affine field: "
        "kinetic_energy) over the elastic energy (bonds and contacts: elastic_energy) and "
        "over the work done so far, after the smooth start (if any) and the first tenth of "
        "the displacement")

    @staticmethod
    def clamp_edges(x: np.ndarray, low_m: float, high_m: float) -> tuple[float, float]:
        """The clamp edges ``low_m`` (beads at or below it clamped) and ``high_m`` (at or
        above) along the bead coordinates ``x``, each moved midway between two beads, so
        that LAMMPS's region test and Python's cannot disagree on a bead on an edge [m]."""
        low = 0.5 * (x[x <= low_m].max() + x[x > low_m].min())
        high = 0.5 * (x[x < high_m].max() + x[x >= high_m].min())
        return float(low), float(high)


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


def clamp_power(group: str = "clamps") -> tuple[str, str]:
    """(LAMMPS text, reference) of the power put in through the beads of ``group``."""
    return render("clamp_power", group=group), "c_p_ext"


def rigid_clamp_power(left: str = "clamp_left", right: str = "clamp_right",
                      left_force: str = "f_left", right_force: str = "f_right"
                      ) -> tuple[str, str]:
    """(LAMMPS text, reference) of the power put in by two clamps that move as rigid
    bodies along x only, from their x forces (computes ``left_force``, ``right_force``)
    and velocities: −Σ f·v over the clamped beads without a formula per bead."""
    return (render("clamp_power_rigid", left=left, right=right, left_force=left_force,
                   right_force=right_force), "v_p_ext")

