"""Bias-extension test: a coupon with its yarns at ±45° to the load, pulled at its ends.

The coupon (cut with ``Coupon(angle_deg=45)``, length along x) is clamped at both
ends exactly like the tension test (:class:`fabmd.protocols.tension.Tension`: the
clamps move apart along x, smooth start then constant speed) and must have a free
length H (between the clamps) of at least twice its width W. With L0 = H − W
the central zone is in pure shear (TEXTILE-PRIMER):

    γ = 90° − 2·acos((L0 + d)/(√2·L0)),   d the clamp separation change.

The shear angle of the central zone is also measured from the fibres: the mean
in-plane axes of the warp and the weft bonds of the beads that start in a central
square (half-size ``central_zone_fraction`` × W) are taken from the trajectory
frames (``trajectory.h5``; :mod:`fabmd.results.fibre_angles`), γ = 90° minus the
angle between them.
Force is the mean of the two clamp reactions, against d.

The test needs yarns that stay yarns once cut free: bundles of loose bead chains without
tension let the clamped fibres slide out, and the centre does not shear (seen on the
tests' tiny single-fibre plain weaves and, before yarn cohesion, on the example coupon).
The pipeline's bias coupon therefore links the fibres of each yarn
(``Coupon.cohesion_factor``, :mod:`fabmd.model.cohesion`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import inputs
from ..analysis import FabricFrame, family_axes_deg
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..results.curves import bilinear_fit, values_at
from ..results.fibre_angles import fibre_shear_angles
from ..scene.adaptive import AdaptiveLoading, adaptive_summary, window_mean, window_width_m
from ..scene.energy import ContactPower
from ..scene.plan import RunPlan
from .driven import ClampedTest, DrivenResult
from .driven_outputs import energy_columns, read_outputs
from .end_clamps import EndClampedTest
from .tension import Tension
from .verdict import mark_fitted_stiffness

PROTOCOL = "bias_extension"


def bias_shear_angle_deg(displacement_m, free_length_m: float, width_m: float):
    """Central-zone shear angle γ = 90° − 2·acos((L0 + d)/(√2·L0)), L0 = H − W [deg]."""
    l0 = free_length_m - width_m
    ratio = np.clip((l0 + np.asarray(displacement_m, float)) / (math.sqrt(2) * l0), -1, 1)
    return 90.0 - 2.0 * np.degrees(np.arccos(ratio))


def bias_displacement_m(shear_angle_deg, free_length_m: float, width_m: float):
    """Clamp separation change d that gives central shear angle γ [m]."""
    l0 = free_length_m - width_m
    return l0 * (math.sqrt(2) * np.cos(np.radians(45.0 - np.asarray(shear_angle_deg) / 2)) - 1)


@dataclass(frozen=True, kw_only=True)
class BiasExtension(EndClampedTest):
    """Bias-extension test of a 45° coupon (length along x, H ≥ 2 W).

    The loading, contact, output, ``relax`` and ``drag`` fields are those of
    :class:`~fabmd.protocols.driven.ClampedTest`, ``clamp_length_m`` that of
    :class:`~fabmd.protocols.end_clamps.EndClampedTest`: the affine drag field is the clamps'
    stretch along x, which does not hold the central zone's shear, so some drag remains
    (see the summary's damping share); the fibre angles are measured on the trajectory
    frames (``TrajectoryOutput(frames=0)``: none written, none measured).

    Args:
        max_shear_angle_deg: central-zone shear angle (closed form) at the end [deg], (0, 80].
        max_displacement_m: clamp separation change at the end [m]; overrides the angle.
        central_zone_fraction: half-size of the central square where fibre angles are
            measured, over the width W, in (0, 0.5].
        report_angles_deg: central shear angles at which forces are reported.
        loading_speed: adaptive clamp speed (opt-in, :mod:`fabmd.scene.adaptive`; run as the
            tension protocol runs it); the speed history is the curve's ``clamp_speed_m_s``.

    The default ``speed_fraction`` (1e-4) suits it: a mechanism with small forces needs a
    slower pull than a tension test; on the example coupon 1e-3, 5e-4 and 2e-4 fail the
    kinetic-energy check early in the test (KE/strain energy 1.2, 1.5, 0.19 > 0.1), 1e-4
    passes it (0.047), and the forces at 2e-4 are within 3 % of those at 1e-4.
    """

    protocol = PROTOCOL
    interval_axis = ("shear_angle_deg", 5.0)
    rate_curve = ("displacement_m", "force_n")
    rate_keys = {"initial_stiffness_change": "initial_stiffness_n_m"}

    max_shear_angle_deg: float = 40.0
    max_displacement_m: float | None = None
    central_zone_fraction: float = 0.2
    report_angles_deg: tuple[float, ...] = (10.0, 20.0, 30.0)
    loading_speed: AdaptiveLoading = field(default_factory=AdaptiveLoading)

    def check_fields(self) -> None:
        inputs.in_range("bias_extension.max_shear_angle_deg", self.max_shear_angle_deg, 0, 80,
                        low_open=True)
        self.check_positive_or_none("max_displacement_m")
        if not isinstance(self.loading_speed, AdaptiveLoading):
            raise InputError(f"bias_extension.loading_speed must be an AdaptiveLoading, got "
                             f"{self.loading_speed!r}")
        self.loading_speed.check_speed("bias_extension", self.speed_fraction)
        super().check_fields()
        inputs.in_range("bias_extension.central_zone_fraction", self.central_zone_fraction,
                        0, 0.5, low_open=True)

    # -- geometry ---------------------------------------------------------------------
    def width_m(self, model: BeadModel) -> float:
        return float(np.ptp(model.positions[:, 1]) + model.diameters.max())

    def free_length_m(self, model: BeadModel) -> float:
        """H: the free length between the clamps [m]."""
        return self.clamps(model)[2]

    def max_displacement(self, model: BeadModel) -> float:
        if self.max_displacement_m is not None:
            return self.max_displacement_m
        return float(bias_displacement_m(self.max_shear_angle_deg, self.free_length_m(model),
                                         self.width_m(model)))

    def travel_m(self, model: BeadModel) -> float:
        """Each clamp moves half the separation change."""
        return 0.5 * self.max_displacement(model)

    def tension(self, model: BeadModel) -> Tension:
        """The clamping and loading of this test, as the tension protocol runs them."""
        shared = {f.name: getattr(self, f.name) for f in dataclasses.fields(ClampedTest)}
        shared["damping_time_s"] = self.damping_time_s or self.duration_s(model) / 10
        # this test's clamps (10 % of the coupon by default), not the tension test's default
        x = model.positions[:, 0]
        clamp = self.clamp_length_m if self.clamp_length_m is not None else \
            self.default_clamp_length_m(model, float(x.max() - x.min()))
        return Tension(max_elongation_pct=100 * self.max_displacement(model)
                       / self.free_length_m(model), clamp_length_m=clamp,
                       gauge_fraction=None, loading_speed=self.loading_speed, **shared)

    def plan_loading(self, plan: RunPlan, model: BeadModel) -> RunPlan:
        """Adaptive loading as the tension protocol plans it (same travel and coupon)."""
        return self.tension(model).plan_loading(plan, model)

    def prepare(self, model: BeadModel) -> BeadModel:
        """Check the coupon: H ≥ 2 W, yarns at ±45° to x, shear angle reachable."""
        h, w = self.free_length_m(model), self.width_m(model)
        if h < 2 * w * (1 - 1e-9):
            raise InputError(
                f"bias_extension needs a free length H between the clamps of at least twice the "
                f"width W; got H = {1e3 * h:.2f} mm, W = {1e3 * w:.2f} mm; cut a longer coupon "
                f"(length >= 2 W + both clamps) or shorten clamp_length_m")
        for fam, axis in family_axes_deg(FabricFrame.from_model(model)).items():
            if axis is not None and abs(abs(axis) - 45.0) > 10.0:
                raise InputError(f"bias_extension needs the yarns at +-45 deg to the load (x), "
                                 f"but the {fam} runs at {axis:.0f} deg; cut the coupon with "
                                 f"Coupon(angle_deg=45)")
        dmax = self.max_displacement(model)
        limit = float(bias_displacement_m(80.0, h, w))
        if dmax > limit:
            raise InputError(f"bias_extension.max_displacement_m = {dmax:g} m is beyond an 80 deg "
                             f"central shear angle; use at most {limit:g} m")
        return model

    # -- input ------------------------------------------------------------------------
    def input_text(self, model: BeadModel) -> str:
        tension = self.tension(model)
        if tension.steps(model) != self.steps(model):  # one loading, two descriptions
            raise RuntimeError("bias_extension and its tension clamping disagree on the steps")
        return tension.input_text(model,
                                  header=f"{PROTOCOL} (clamping and loading of tension)")

    def after_verdict(self, result: DrivenResult) -> None:
        """The initial stiffness is fitted against the displacement, 0 to the bilinear
        transition; the intervals are in shear angle: marked where the verdict flags part
        of 0 to the angle at that displacement (as the tension's toe)."""
        d_break = result.summary.get("transition_displacement_m")
        if d_break is None:
            return
        angle = float(np.interp(d_break, result.curve["displacement_m"],
                                result.curve["shear_angle_deg"]))
        mark_fitted_stiffness(result.summary, 0.0, angle, "deg",
                              fitted_on=f"displacement 0-{1e3 * d_break:.3g} mm: shear angle ")

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        return reduce(run_dir, model, self, monitor)


def reduce(run_dir: Path, model: BeadModel, test: BiasExtension,
           monitor: ContactPower | None = None) -> DrivenResult:
    """Force against displacement, central shear angle (closed form and fibres), evidence."""
    plan = test.read_plan(run_dir, model)  # what the run was written with
    out = read_outputs(run_dir, plan.every, plan.time_step_s, monitor)
    h, w = test.free_length_m(model), test.width_m(model)
    d = 2 * out["clamp_displacement_m"]
    window = window_width_m(plan)
    if window is not None:  # adaptive: the clamp forces over the fixed run's interval travel
        for name in ("force_left_n", "force_right_n"):
            out.columns[name] = window_mean(out["clamp_displacement_m"], out[name], window)
    force = 0.5 * (out["force_left_n"] - out["force_right_n"])
    gamma = bias_shear_angle_deg(d, h, w)
    curve = {"time_s": out["time_s"], "displacement_m": d, "force_n": force,
             "force_per_width_n_m": force / w, "shear_angle_deg": gamma,
             **energy_columns(out)}
    if "clamp_speed_m_s" in out.columns:  # adaptive loading: the speed history
        curve["clamp_speed_m_s"] = out["clamp_speed_m_s"]
    dmax = test.max_displacement(model)
    fit = bilinear_fit(d, force)
    p = model.positions
    centre = (p[:, :2].min(axis=0) + p[:, :2].max(axis=0)) / 2
    half = test.central_zone_fraction * w
    steps, fibre_gamma = fibre_shear_angles(run_dir, centre, (half, half), reference_deg=0.0)
    kinematic = np.interp(steps, out["step"], gamma) if len(steps) else np.zeros(0)
    diff = np.abs(fibre_gamma - kinematic)
    summary = {
        "protocol": PROTOCOL,
        "n_beads": model.n_beads,
        "free_length_m": h,
        "width_m": w,
        "l0_m": h - w,
        "time_step_s": plan.time_step_s,
        "steps": plan.steps,
        "clamp_speed_m_s": plan.loading.speed_m_s,
        **adaptive_summary(plan, out["step"], out["time_s"], out.columns.get("clamp_speed_m_s")),
        "max_displacement_m": dmax,
        "max_shear_angle_deg": float(gamma.max()),
        "initial_stiffness_n_m": fit["initial_slope"],  # force per displacement
        "final_stiffness_n_m": fit["final_slope"],
        "transition_displacement_m": fit["break_x"],
        "force_at_angle_n": {f"{k:g}": v for k, v in values_at(
            gamma, force, test.report_angles_deg).items()},
        "max_force_n": float(force.max()),
        "fibre_shear_angle": {
            "zone": f"beads starting in the central square of half-size "
                    f"{test.central_zone_fraction:g} W",
            "steps": steps.tolist(), "kinematic_deg": kinematic.tolist(),
            "fibres_deg": fibre_gamma.tolist(),
            "max_difference_deg": float(diff.max()) if len(diff) else None},
        **test.quasi_static_evidence(out, model, d / dmax),
    }
    ke = summary["max_kinetic_to_strain_energy"]
    plots = [
        {"path": "curve.png",
         "series": [{"x": 1e3 * d, "y": force, "label": "clamp force"}],
         "xlabel": "displacement d [mm]", "ylabel": "force [N]", "title": "Bias extension",
         "x_column": "displacement_m", "x_scale": 1e3,
         "notes": f"H {1e3 * h:.1f} mm, W {1e3 * w:.1f} mm"
                  f"\nKE/U after start-up <= {'n/a' if ke is None else f'{ke:.3g}'}"
                  f"\n{model.n_beads} beads"},
        {"path": "shear_angle.png",
         "series": [{"x": 1e3 * d, "y": gamma, "label": "closed form (L0 = H - W)"},
                    {"x": 1e3 * np.interp(steps, out["step"], d), "y": fibre_gamma,
                     "style": "o", "label": "fibres, central zone"}],
         "xlabel": "displacement d [mm]", "ylabel": "central shear angle γ [deg]",
         "x_column": "displacement_m", "x_scale": 1e3,
         "title": "Bias extension: central-zone shear angle"},
    ]
    return DrivenResult(Path(run_dir), curve, summary, plots)
