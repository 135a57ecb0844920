"""Uniaxial tension of a fabric coupon.

The coupon's length is along x. Both ends, ``clamp_length_m`` long, are clamped:
their beads move as rigid bodies along x in opposite directions (smooth start,
then constant speed), every other movement held. Force is the reaction on the
clamps (mean of both ends); elongation is the clamp separation change over the
gauge length (distance between the inner clamp edges). An optical gauge (video
extensometer) reports the strain between two cross-sections away from the clamps as
well (``gauge_strain_pct``; the summary's ``optical_gauge``). Quasi-static evidence:
kinetic/strain energy ratio over the run and an energy balance
(:mod:`fabmd.scene.energy`); ``check_rate`` reruns at half speed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import inputs
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..results.curves import bilinear_fit, values_at
from ..scene.adaptive import (
    AdaptiveLoading,
    adaptive_plan,
    adaptive_summary,
    speed_commands,
    window_mean,
    window_width_m,
)
from ..scene.drag import AffineField
from ..scene.energy import ContactPower
from ..scene.plan import RunPlan
from ..scene.templates import fmt, render
from .driven import DrivenResult, rigid_clamp_power
from .driven_outputs import energy_columns, read_outputs
from .end_clamps import EndClampedTest
from .verdict import mark_fitted_stiffness

PROTOCOL = "tension"


@dataclass(frozen=True, kw_only=True)
class Tension(EndClampedTest):
    """Uniaxial tension test of a coupon (length along x).

    The loading, contact, output, ``relax`` and ``drag`` fields are those of
    :class:`~fabmd.protocols.driven.ClampedTest` (the affine drag field: the clamps'
    stretch along x), ``clamp_length_m`` and :meth:`clamps` those of
    :class:`~fabmd.protocols.end_clamps.EndClampedTest`; the clamp length defaults to 10 %
    of the coupon but at least one weave repeat (:meth:`default_clamp_length_m`).

    Args:
        max_elongation_pct: elongation at the end of the test [%] (0, 50].
        report_elongations_pct: elongations at which forces are reported.
        loading_speed: adaptive loading speed (opt-in, :mod:`fabmd.scene.adaptive`); the
            speed history is the curve's ``clamp_speed_m_s``.
        gauge_fraction: optical gauge length over the free length between the clamps, in
            (0, 0.9]: two cross-sections centred on the coupon, each the beads that start
            within a bead diameter of its mark (default 0.5: the marks a quarter of the free
            length from each clamp); None: no optical gauge.
    """

    protocol = PROTOCOL
    #: the fabric may start with the clamps' uniform stretch (``start = "affine"``, asked
    #: for): not the default, since a slack coupon straightens rather than stretches
    affine_start_supported = True
    affine_start_default = False
    interval_axis = ("elongation_pct", 0.25)
    rate_curve = ("elongation_pct", "force_n")
    rate_keys = {"initial_stiffness_change": "initial_stiffness_n"}

    max_elongation_pct: float = 3.0
    report_elongations_pct: tuple[float, ...] = (0.5, 1.0, 2.0)
    loading_speed: AdaptiveLoading = field(default_factory=AdaptiveLoading)
    gauge_fraction: float | None = 0.5

    def check_fields(self) -> None:
        inputs.in_range("tension.max_elongation_pct", self.max_elongation_pct, 0, 50,
                        low_open=True)
        if self.gauge_fraction is not None:
            inputs.in_range("tension.gauge_fraction", self.gauge_fraction, 0, 0.9,
                            low_open=True)
        if not isinstance(self.loading_speed, AdaptiveLoading):
            raise InputError(f"tension.loading_speed must be an AdaptiveLoading, got "
                             f"{self.loading_speed!r}")
        self.loading_speed.check_speed("tension", self.speed_fraction)
        super().check_fields()

    def plan_loading(self, plan: RunPlan, model: BeadModel) -> RunPlan:
        length = float(np.ptp(model.positions[:, :2], axis=0).max())  # the longest fibre
        return adaptive_plan(plan, self.loading_speed, self.travel_m(model),
                             length / self.wave_speed_m_s(model))

    def travel_m(self, model: BeadModel) -> float:
        """Each clamp moves half the elongation of the gauge length."""
        _, _, gauge = self.clamps(model)
        return 0.5 * self.max_elongation_pct / 100 * gauge

    def default_clamp_length_m(self, model: BeadModel, length_m: float) -> float:
        """10 % of the coupon, but at least one weave repeat along the load (the larger side
        of the model's unit cell, where it knows it; at most 35 % of the coupon) [m]: the
        crimp at a cut end relaxes differently over about a repeat, and a clamp that holds
        that zone keeps it out of the free length (measured on the plain weave, 1 fibre per
        yarn, relieved coupons 4 and 6 cells long to 8 %: the force at 6 % moved 13.8 %
        with 10 % clamps, 2.5 % with one-cell clamps)."""
        cell = model.info.get("unit_cell_m")
        repeat = float(max(cell)) if cell else 0.0
        return max(0.1 * length_m, min(repeat, 0.35 * length_m))

    def gauge_marks(self, model: BeadModel) -> tuple[float, float, float]:
        """(x of the left gauge mark, of the right one, half the width of the band of beads
        each mark follows) [m]: centred between the clamps, ``gauge_fraction`` of the free
        length apart; the band is a bead diameter wide."""
        left, right, _ = self.clamps(model)
        centre, half = 0.5 * (left + right), 0.5 * self.gauge_fraction * (right - left)
        return centre - half, centre + half, 0.5 * float(model.diameters.max())

    def gauge_block(self, model: BeadModel) -> str:
        """The optical gauge's LAMMPS text (groups and ``v_gauge_distance``); empty without
        one."""
        if self.gauge_fraction is None:
            return ""
        a, b, band = self.gauge_marks(model)
        return render("tension_gauge", left_lo=a - band, left_hi=a + band, right_lo=b - band,
                      right_hi=b + band)

    def input_text(self, model: BeadModel, extra: str = "", header: str | None = None) -> str:
        """The LAMMPS input; ``extra`` (e.g. a dump) goes in before the run; ``header``
        names the test in its first comment line (default: tension)."""
        left, right, _ = self.clamps(model)
        dt = self.time_step_s(model)
        load = self.loading(model)
        ref_force = max(bt.bond_axial_stiffness_n for bt in model.fibre_bond_types())
        ref_force *= 1e-3 * self.max_elongation_pct
        power, power_ref = rigid_clamp_power()
        # the clamps' inner edges at x_left - u and x_right + u move at -v and +v: the
        # fabric between them stretches affinely along x (the drag's field, and the start's
        # with start = "affine": v = 2·v0·(x − x0)/(x_right − x_left))
        field = AffineField(origin_m=(0.5 * (left + right), 0.0),
                            xx=f"2*v_v/({fmt(right - left)}+2*v_u)", tools="clamps")
        damping, damping_power = self.drag_block(model, field)
        adaptive = self.loading_speed.adaptive
        gauge = self.gauge_fraction is not None
        outputs = self.outputs_block(
            model, power, power_ref, mean_values="c_f_left c_f_right",
            mean_names="force_left_n force_right_n",
            print_values=("${u} ${v}" if adaptive else "${u}")
            + (" ${gauge_distance}" if gauge else ""),
            print_names=("clamp_displacement_m clamp_speed_m_s" if adaptive
                         else "clamp_displacement_m") + (" gauge_distance_m" if gauge else ""),
            thermo_values="v_u v_v c_f_left c_f_right" if adaptive
            else "v_u c_f_left c_f_right", damping_power=damping_power, affine=field)
        displacement, velocity = load.lammps_displacement(), load.lammps_velocity()
        moves = ("v_u", "v_u_neg")
        if adaptive:  # the clamps integrate the speed; u is read back from them
            outputs += "\n" + self.adaptive_block(model, power_ref, ref_force)
            displacement, velocity = self.clamp_travel(model), f"({velocity})*v_adapt_factor"
            moves = ("NULL", "NULL")
        text = render("tension", x_left=left, x_right=right,
                      relax=self.gauge_block(model)
                      + self.relax_block(model, "clamps", "free", ref_force),
                      displacement=displacement, velocity=velocity,
                      right_displacement=moves[0], left_displacement=moves[1],
                      damping=damping, start=self.start_block(field), outputs=outputs)
        return self.scene_text(model, dt, text, extra, header=header)

    def clamp_travel(self, model: BeadModel) -> str:
        """LAMMPS formula of the clamps' mean travel [m] from their centres of mass (each
        clamp's starting centre from the model: the clamps are held while relaxing)."""
        left, right, _ = self.clamps(model)
        x, m = model.positions[:, 0], model.masses
        x0 = [float(np.sum(m[sel] * x[sel]) / np.sum(m[sel])) for sel in (x < left, x > right)]
        return (f"0.5*((xcm(clamp_right,x)-({fmt(x0[1])}))"
                f"-(xcm(clamp_left,x)-({fmt(x0[0])})))")

    def adaptive_block(self, model: BeadModel, external_ref: str, ref_force: float) -> str:
        """The adaptive speed's LAMMPS text (:func:`fabmd.scene.adaptive.speed_commands`);
        floors: every fibre bond at ``ref_force`` (strain energy), one fibre pulled with
        it at the base speed (power)."""
        k = max(bt.spring_n_per_m for bt in model.fibre_bond_types())
        n = int(model.fibre_bond_mask().sum())
        plan = self.plan(model)
        return speed_commands(plan, external_ref, n * ref_force**2 / (2 * k),
                              ref_force * plan.speed_m_s)

    def after_verdict(self, result: DrivenResult) -> None:
        """The initial stiffness is fitted over the toe (0 to the bilinear transition); where
        the verdict flags part of it, the toe's force is drag and inertia, not the fabric's
        (the example's released toe at 0.5-0.75 %: 2.64 / 0.53 / 0.08 N at 2e-4 / 1e-4 /
        5e-5, benchmarks/RESULTS.md "The tension toe is drag")."""
        summary = result.summary
        mark_fitted_stiffness(summary, 0.0, summary.get("transition_elongation_pct"), "%")
        optical = summary.get("optical_gauge")
        gauge = result.curve.get("gauge_strain_pct")
        if optical and gauge is not None and optical.get("transition_strain_pct") is not None:
            # the gauge's toe, 0 to its own transition, in the clamp elongation the
            # intervals are judged in: where the gauge strain first reaches it
            reach = np.nonzero(np.asarray(gauge) >= optical["transition_strain_pct"])[0]
            if len(reach):
                high = float(np.asarray(result.curve["elongation_pct"])[reach[0]])
                mark_fitted_stiffness(summary, 0.0, high, "%", into=optical,
                                      fitted_on="gauge strain 0-"
                                      f"{optical['transition_strain_pct']:.3g} %: clamp "
                                      "elongation ")

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> TensionResult:
        return reduce(run_dir, model, self, monitor)


class TensionResult(DrivenResult):
    """Curve, summary and plot of a tension test."""


def reduce(run_dir: Path, coupon: BeadModel, test: Tension,
           monitor: ContactPower | None = None) -> TensionResult:
    """Read the run back and build the curve, the summary and the energy balance."""
    plan = test.read_plan(run_dir, coupon)  # what the run was written with
    out = read_outputs(run_dir, plan.every, plan.time_step_s, monitor)
    _, _, gauge = test.clamps(coupon)
    width = float(np.ptp(coupon.positions[:, 1]) + coupon.diameters.max())
    elongation = 2 * out["clamp_displacement_m"] / gauge
    window = window_width_m(plan)
    if window is not None:  # adaptive: the clamp forces over the fixed run's interval travel
        for name in ("force_left_n", "force_right_n"):
            out.columns[name] = window_mean(out["clamp_displacement_m"], out[name], window)
    force = 0.5 * (out["force_left_n"] - out["force_right_n"])
    curve = {
        "time_s": out["time_s"],
        "elongation_pct": 100 * elongation,
        "force_n": force,
        "force_per_width_n_m": force / width,
        "force_left_n": out["force_left_n"],
        "force_right_n": -out["force_right_n"],
        **energy_columns(out),
    }
    if "clamp_speed_m_s" in out.columns:  # adaptive loading: the speed history
        curve["clamp_speed_m_s"] = out["clamp_speed_m_s"]
    optical = None
    if "gauge_distance_m" in out.columns:  # the optical gauge (older runs have none)
        distance = out["gauge_distance_m"]
        curve["gauge_strain_pct"] = 100 * (distance / distance[0] - 1)
        optical = optical_gauge(curve["gauge_strain_pct"], force, width, float(distance[0]),
                              test, float(100 * elongation[-1]))
    fit = bilinear_fit(100 * elongation, force)
    summary = {
        "protocol": PROTOCOL,
        "n_beads": coupon.n_beads,
        "gauge_length_m": gauge,
        "width_m": width,
        "time_step_s": plan.time_step_s,
        "steps": plan.steps,
        "clamp_speed_m_s": plan.loading.speed_m_s,
        "start": test.start_kind(),
        **adaptive_summary(plan, out["step"], out["time_s"], out.columns.get("clamp_speed_m_s")),
        "initial_stiffness_n": fit["initial_slope"] * 100,  # N per unit strain
        "final_stiffness_n": fit["final_slope"] * 100,
        "initial_stiffness_n_m_per_width": fit["initial_slope"] * 100 / width,
        "final_stiffness_n_m_per_width": fit["final_slope"] * 100 / width,
        "transition_elongation_pct": fit["break_x"],
        "force_at_elongation_n": {f"{k:g}": v for k, v in
                                  values_at(100 * elongation, force,
                                            test.report_elongations_pct).items()},
        "max_force_n": float(force.max()),
        **({"optical_gauge": optical} if optical is not None else {}),
        "clamp_force_mismatch": float(np.abs(out["force_left_n"] + out["force_right_n"])[-1]
                                      / max(abs(force[-1]), 1e-300)),
        # start-up: the smooth start, the first tenth of the elongation and the slack toe
        **test.quasi_static_evidence(out, coupon, elongation / (test.max_elongation_pct / 100),
                                     work_ratio=False),
    }
    ke = summary["max_kinetic_to_strain_energy"]
    plot = {"path": "curve.png",
            "series": [{"x": curve["elongation_pct"], "y": curve["force_per_width_n_m"],
                        "label": "fabric, clamp strain"}]
            + ([{"x": curve["gauge_strain_pct"], "y": curve["force_per_width_n_m"],
                 "label": "fabric, optical gauge strain"}] if optical is not None else []),
            "xlabel": "elongation [%]", "ylabel": "force per width [N/m]",
            "title": "Uniaxial tension",
            "notes": f"gauge {1e3 * gauge:.1f} mm, width {1e3 * width:.1f} mm"
                     f"\nKE/U after start-up <= {'n/a' if ke is None else f'{ke:.3g}'}"
                     f"\n{coupon.n_beads:,} beads",
            "marks": tension_marks(fit, width, summary["force_at_elongation_n"],
                                   float(100 * elongation.max()))}
    return TensionResult(Path(run_dir), curve, summary, [plot])


def optical_gauge(strain_pct: np.ndarray, force_n: np.ndarray, width_m: float,
                  length_m: float, test: Tension, clamp_strain_pct: float) -> dict:
    """The summary's ``optical_gauge``: forces at the report strains and the bilinear
    stiffnesses against the gauge strain, and the gauge strain at the end over the clamp
    strain there (1 where the coupon strains evenly)."""
    fit = bilinear_fit(strain_pct, force_n)
    forces = values_at(strain_pct, force_n, test.report_elongations_pct)
    return {
        "length_m": length_m,
        "gauge_fraction": test.gauge_fraction,
        "marks": "two cross-sections centred on the coupon, gauge_fraction of the free "
                 "length apart: the beads within a bead diameter of each mark at the start",
        "final_strain_pct": float(strain_pct[-1]),
        "strain_ratio_to_clamp": float(strain_pct[-1] / clamp_strain_pct)
        if clamp_strain_pct else None,
        "initial_stiffness_n_m_per_width": fit["initial_slope"] * 100 / width_m,
        "final_stiffness_n_m_per_width": fit["final_slope"] * 100 / width_m,
        "transition_strain_pct": fit["break_x"],
        "force_at_strain_n": {f"{k:g}": v for k, v in forces.items()},
    }


def tension_marks(fit: dict, width_m: float, report: dict, max_pct: float) -> list[dict]:
    """The summary's quantities on the force-per-width curve: the fitted tangents, the
    transition between them and the report points."""
    marks = []
    xb, yb = fit["break_x"], fit["break_y"]
    if xb is not None and np.isfinite(xb) and 0 < xb < max_pct:
        yb /= width_m
        for name, slope, x_end in (("initial", fit["initial_slope"], 0.0),
                                   ("final", fit["final_slope"], max_pct)):
            k = slope / width_m  # N/m per % elongation
            marks.append({"kind": "line", "x": [x_end, xb], "y": [yb + k * (x_end - xb), yb],
                          "label": f"{name} tangent {100 * k:.3g} N/m per unit strain"})
        marks.append({"kind": "vline", "x": xb, "label": f"transition {xb:.3g} %"})
    points = [(float(x), v / width_m) for x, v in report.items() if v is not None]
    if points:
        marks.append({"kind": "point", "x": [p[0] for p in points],
                      "y": [p[1] for p in points], "label": "report points"})
    return marks
