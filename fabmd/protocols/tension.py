"""Uniaxial tension of a fabric coupon.

The coupon's length is along x. Both ends, ``clamp_length_m`` long, are clamped:
their beads move as rigid bodies along x in opposite directions (smooth start,
then constant speed), every other movement held. Force is the reaction on the
clamps (mean of both ends); elongation is the clamp separation change over the
gauge length (distance between the inner clamp edges). Quasi-static evidence:
kinetic/strain energy ratio over the run and an energy balance
(:mod:`fabmd.scene.energy`); ``check_rate`` reruns at half speed.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import inputs
from ..engine import Engine, mpi
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..model.beads import TimeStep, model_bead_parameters
from ..model.contact import ContactModel
from ..results.curves import bilinear_fit, curve_difference, values_at
from ..results.folder import read_ave_time, read_print_file, write_csv, write_json
from ..results.plots import plot_curves
from ..scene import blocks
from ..scene.energy import ContactPower, balance, cumulative
from ..scene.loading import SmoothStartSpeed
from ..scene.quasi_static import QuasiStatic
from ..scene.templates import render
from .common import DATA_FILE, input_name, resume_folder, scene_dict, write_run_folder

PROTOCOL = "tension"


@dataclass(frozen=True)
class Tension:
    """Uniaxial tension test of a coupon (length along x).

    Args:
        max_elongation_pct: elongation at the end of the test [%] (0, 50].
        clamp_length_m: clamped length at each end [m]; default 10 % of the coupon.
        speed_fraction: speed of each clamp over the fibres' axial wave speed
            (quasi-static when small; default 1e-4).
        ramp_fraction: share of the test spent reaching full speed smoothly.
        damping_time_s: τ of the viscous damping γ = m/τ (default: a tenth of the test).
        contact: fibre–fibre contact.
        time_step: time-step policy.
        samples: curve points.
        report_elongations_pct: elongations at which forces are reported.
    """

    max_elongation_pct: float = 3.0
    clamp_length_m: float | None = None
    speed_fraction: float = 1e-4
    ramp_fraction: float = 0.1
    damping_time_s: float | None = None
    contact: ContactModel = field(default_factory=ContactModel)
    time_step: TimeStep = field(default_factory=TimeStep)
    samples: int = 200
    report_elongations_pct: tuple[float, ...] = (0.5, 1.0, 2.0)
    relax: QuasiStatic = field(default_factory=lambda: QuasiStatic(max_steps=50_000))

    def __post_init__(self):
        inputs.in_range("tension.max_elongation_pct", self.max_elongation_pct, 0, 50,
                        low_open=True)
        if self.clamp_length_m is not None:
            inputs.positive("tension.clamp_length_m", self.clamp_length_m)
        inputs.in_range("tension.speed_fraction", self.speed_fraction, 0, 0.05, low_open=True)
        inputs.in_range("tension.ramp_fraction", self.ramp_fraction, 0, 0.9)
        if self.damping_time_s is not None:
            inputs.positive("tension.damping_time_s", self.damping_time_s)
        inputs.positive_int("tension.samples", self.samples, minimum=10)

    # -- geometry of the coupon --------------------------------------------------------
    def clamps(self, model: BeadModel) -> tuple[float, float, float]:
        """(x of the left clamp's inner edge, of the right one's, gauge length) [m].

        The gauge length is the free length between the innermost clamped beads.
        """
        x = model.positions[:, 0]
        length = float(x.max() - x.min())
        clamp = self.clamp_length_m if self.clamp_length_m is not None else 0.1 * length
        if 2 * clamp >= 0.8 * length:
            raise InputError(f"tension.clamp_length_m = {clamp:g} m leaves no gauge length on a "
                             f"{length:g} m coupon; use at most {0.4 * length:g} m per end")
        left, right = float(x.min() + clamp), float(x.max() - clamp)
        # put each clamp edge midway between beads, so LAMMPS's region test and this
        # one cannot disagree on a bead that sits on the edge
        left = 0.5 * (x[x <= left].max() + x[x > left].min())
        right = 0.5 * (x[x < right].max() + x[x >= right].min())
        gauge = float(x[x > right].min() - x[x < left].max())
        return float(left), float(right), gauge

    def wave_speed_m_s(self, model: BeadModel) -> float:
        return min(b.bond_length_m * math.sqrt(b.spring_n_per_m / b.mass_kg)
                   for b in model_bead_parameters(model))

    def loading(self, model: BeadModel) -> SmoothStartSpeed:
        v = self.speed_fraction * self.wave_speed_m_s(model)
        _, _, gauge = self.clamps(model)
        total = 0.5 * self.max_elongation_pct / 100 * gauge / v  # each clamp moves half
        return SmoothStartSpeed(v, self.ramp_fraction * total / (1 - self.ramp_fraction / 2))

    def duration_s(self, model: BeadModel) -> float:
        _, _, gauge = self.clamps(model)
        return self.loading(model).time_for(0.5 * self.max_elongation_pct / 100 * gauge)

    def time_step_s(self, model: BeadModel) -> float:
        beads = model_bead_parameters(model)
        kn = self.contact.normal_stiffness_n_per_m(beads)
        return self.time_step.resolve(min(b.critical_time_step_s(kn) for b in beads))

    def every(self, model: BeadModel) -> int:
        raw = math.ceil(self.duration_s(model) / self.time_step_s(model))
        return max(1, raw // self.samples)

    def steps(self, model: BeadModel) -> int:
        """Whole output intervals, so that the last sample is the end of the test."""
        every = self.every(model)
        return every * math.ceil(self.duration_s(model) / self.time_step_s(model) / every)

    def gamma(self, model: BeadModel) -> float:
        tau = self.damping_time_s or self.duration_s(model) / 10
        return float(np.median(model.masses)) / tau

    def input_text(self, model: BeadModel) -> str:
        left, right, _ = self.clamps(model)
        dt = self.time_step_s(model)
        load = self.loading(model)
        beads = model_bead_parameters(model)
        every = self.every(model)
        ref_force = max(2 * bt.coefficient * bt.rest_length_m for bt in model.bond_type_table)
        ref_force *= 1e-3 * self.max_elongation_pct
        k = max(2 * bt.coefficient for bt in model.bond_type_table)
        relax = blocks.relax(model, dt, "clamps", "free", self.relax, ref_force,
                             model.n_bonds * ref_force**2 / (2 * k))
        text = render("tension", x_left=left, x_right=right, relax=relax,
                      displacement=load.lammps_displacement(), velocity=load.lammps_velocity(),
                      gamma=self.gamma(model), every=every,
                      thermo_every=max(every, self.steps(model) // 20))
        return "\n".join([
            blocks.setup(model, PROTOCOL, DATA_FILE, dt),
            blocks.bonds(model),
            blocks.contact(model, self.contact, beads),
            text,
            ContactPower.commands(),
            blocks.guards(model, dt),
            render("run", steps=self.steps(model)),
            render("finish", final_data="final.data"),
        ])

    # -- run ------------------------------------------------------------------------
    def run(self, coupon: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False, check_rate: bool = False,
            resume: bool = False, monitor: ContactPower | None = None) -> TensionResult:
        """Run the test on ``coupon``.

        Args:
            check_rate: rerun at half speed and report the change of the curve.
            resume: continue an interrupted run in ``out`` from its last checkpoint
                (see ``Engine(checkpoint_every=...)``).
        """
        engine = engine or Engine()
        text = self.input_text(coupon)
        if resume:
            run_dir = resume_folder(out)
        else:
            run_dir = write_run_folder(out, PROTOCOL, coupon, text,
                                       {"tension": scene_dict(self)}, overwrite=overwrite)
        monitor = monitor or ContactPower()
        every = self.every(coupon)
        run = engine.run(run_dir, input_name(PROTOCOL), label=PROTOCOL, monitor=monitor,
                         monitor_every=every, resume=resume)
        result = None
        if mpi.is_root():
            result = reduce(run_dir, coupon, self, monitor)
            result.summary.update(wall_s=run.wall_s, ranks=run.ranks, backend=run.backend)
        if check_rate:
            slow = dataclasses.replace(self, speed_fraction=self.speed_fraction / 2)
            other = slow.run(coupon, out=Path(run_dir) / "half_speed", engine=engine)
            if mpi.is_root():
                diff = curve_difference(result.curve["elongation_pct"], result.curve["force_n"],
                                        other.curve["elongation_pct"], other.curve["force_n"])
                result.summary["rate_check"] = {
                    "half_speed_run": str(other.run_dir), "max_relative_force_change": diff,
                    "initial_stiffness_change": _rel(other.summary["initial_stiffness_n"],
                                                     result.summary["initial_stiffness_n"])}
        if mpi.is_root():
            result.write()
        summary = mpi.bcast_json(result.summary if result else None)
        if result is None:
            result = TensionResult(Path(run_dir), {}, summary)
        result.summary = summary
        return result


def _rel(a, b):
    return abs(a - b) / abs(b) if b else None


@dataclass
class TensionResult:
    """Curve and summary of a tension test."""

    run_dir: Path
    curve: dict[str, np.ndarray]
    summary: dict

    def write(self) -> None:
        write_csv(self.run_dir / "curve.csv", self.curve)
        write_json(self.run_dir / "summary.json", self.summary)
        c, s = self.curve, self.summary
        ke = s["max_kinetic_to_strain_energy"]
        plot_curves(self.run_dir / "curve.png", [
            {"x": c["elongation_pct"], "y": c["force_per_width_n_m"], "label": "fabric"},
        ], "elongation [%]", "force per width [N/m]",
            title="Uniaxial tension",
            notes="\n".join([
                f"gauge {1e3 * s['gauge_length_m']:.1f} mm, width {1e3 * s['width_m']:.1f} mm",
                f"KE/U after start-up <= {ke:.3f}" if ke is not None else "KE/U: no load",
                f"{s['n_beads']} beads"]))


def reduce(run_dir: Path, coupon: BeadModel, test: Tension,
           monitor: ContactPower | None = None) -> TensionResult:
    """Read ``curve.dat`` and build the curve, the summary and the energy balance."""
    raw = read_print_file(Path(run_dir) / "curve.dat")
    means = read_ave_time(Path(run_dir) / "means.dat")
    # interval means are reported at the interval's end step; the curve starts at step 0
    for name in ("force_left_n", "force_right_n", "external_power_w", "damping_power_w"):
        raw[name] = np.interp(raw["step"], means["step"], means[name], left=0.0)
    _, _, gauge = test.clamps(coupon)
    width = float(np.ptp(coupon.positions[:, 1]) + coupon.diameters.max())
    dt = test.time_step_s(coupon)
    every = test.every(coupon)
    elongation = 2 * raw["clamp_displacement_m"] / gauge
    force = 0.5 * (raw["force_left_n"] - raw["force_right_n"])
    external = np.interp(raw["step"], means["step"],
                         cumulative(means["external_power_w"], every, dt), left=0.0)
    damping = np.interp(raw["step"], means["step"],
                        cumulative(means["damping_power_w"], every, dt), left=0.0)
    contact = monitor.work_j(raw["step"], dt) if monitor is not None else None
    curve = {
        "time_s": raw["time_s"],
        "elongation_pct": 100 * elongation,
        "force_n": force,
        "force_per_width_n_m": force / width,
        "force_left_n": raw["force_left_n"],
        "force_right_n": -raw["force_right_n"],
        "kinetic_energy_j": raw["kinetic_j"],
        "strain_energy_j": raw["strain_energy_j"],
        "external_work_j": external,
        "damping_dissipation_j": damping,
    }
    if contact is not None:
        curve["contact_work_j"] = contact
    # start-up: the smooth start, and the slack toe where the fabric carries (almost) no
    # load yet (strain energy below 1 % of its final value)
    loaded = raw["strain_energy_j"] - raw["strain_energy_j"][0] > \
        0.01 * (raw["strain_energy_j"][-1] - raw["strain_energy_j"][0])
    started = (raw["time_s"] > test.loading(coupon).ramp_time_s) & loaded
    ke_ratio = raw["kinetic_j"][started] / np.maximum(raw["strain_energy_j"][started], 1e-300)
    fit = bilinear_fit(100 * elongation, force)
    summary = {
        "protocol": PROTOCOL,
        "n_beads": coupon.n_beads,
        "gauge_length_m": gauge,
        "width_m": width,
        "time_step_s": dt,
        "steps": test.steps(coupon),
        "clamp_speed_m_s": test.loading(coupon).speed_m_s,
        "initial_stiffness_n": fit["initial_slope"] * 100,  # N per unit strain
        "final_stiffness_n": fit["final_slope"] * 100,
        "initial_stiffness_n_m_per_width": fit["initial_slope"] * 100 / width,
        "final_stiffness_n_m_per_width": fit["final_slope"] * 100 / width,
        "transition_elongation_pct": fit["break_x"],
        "force_at_elongation_n": {f"{k:g}": v for k, v in
                                  values_at(100 * elongation, force,
                                            test.report_elongations_pct).items()},
        "max_force_n": float(force.max()),
        "max_kinetic_to_strain_energy": float(ke_ratio.max()) if ke_ratio.size else None,
        "quasi_static_note": "kinetic/strain energy after the smooth start, once the strain "
                             "energy exceeds 1 % of its final value",
        "clamp_force_mismatch": float(np.abs(raw["force_left_n"] + raw["force_right_n"])[-1]
                                      / max(abs(force[-1]), 1e-300)),
        "energy_balance": balance(external, raw["strain_energy_j"], raw["kinetic_j"], damping,
                                  contact),
    }
    return TensionResult(Path(run_dir), curve, summary)
