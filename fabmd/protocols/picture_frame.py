"""Picture-frame (trellis-frame) shear of a square coupon.

The coupon (warp along x, weft along y) sits centred in a rigid frame of four
arms of length L_frame pinned at the corners. Pin A is fixed; the opposite pin C
is pulled along the diagonal by d (smooth start, then constant speed). With
cos θ = (√2·L_frame + d)/(2·L_frame) the arms point along e1 = rot(u, −θ) and
e2 = rot(u, +θ) (u the diagonal), and the shear angle is γ = 90° − 2θ.

The beads of the clamped strips along the four edges move affinely with the
frame, x = A + ξ·e1 + η·e2 ((ξ, η) their position relative to A before the
test), and keep their z (``fix store/state`` + ``fix move variable`` with
displacement and velocity); the unclamped fabric inside is free. The frame force
follows from the power balance F·ḋ = −Σ_clamped f·v, integrated exactly over each
output interval, less the work that went into carrying the fabric with the frame:
F = (ΔW − ΔKE_c)/Δd, KE_c the fabric's kinetic energy less its part relative to the
frame's affine field. The fabric moves with the frame, whose arms turn faster as the shear
grows at a constant corner speed, so that kinetic energy grows throughout the test: the
work accelerates the fabric and is not its shear resistance (on the 3D study's 40 mm frame
it was 25–38 % of the frame's work; taking it off removed about two fifths of the
difference between plain-weave coupons at two speeds, and took the 3D frame's from
24–39 % to under 9 %: benchmarks/RESULTS.md "The frame's work into the fabric's motion").
Reported the standard way (Harrison et al. 2004):
F_s = F/(2 cos θ) and F_norm = F_s·L_frame/L_fabric², L_fabric the side of the
fabric in the frame (in this model the clamped strips shear with the frame, so
the whole coupon is the sheared area). With ``clamp_yarns`` the clamps hold whole yarns
(:func:`whole_yarn_edges`) and L_fabric is the free square's side: the clamped strips
move with the frame and store nothing (their mutual bonds and contacts are removed), so
the free square is the area that shears. The shear-locking angle
(:func:`fabmd.results.curves.locking_angle`): a line fitted to F_norm over a fixed
initial range past the start-up (10–20°), the departure where F_norm stays above
twice that line for 5°, and the tangent over those 5° meeting the initial line; it
does not depend on where the test stops.

``pretension_strain`` is a clamping preload: the rest length of the bonds of the
unclamped fibres shrinks by that strain (ramped, clamps held) before the free
relaxation, and stays shorter for the test. A negative one is mounting slack: the rest
length grows by its size, as for a fabric mounted slack in the frame (the frame's force
past 20° is mostly the clamped fibres' stretch as the fabric thickens, so a few tenths of
a per cent move it several-fold: benchmarks/RESULTS.md "What sets the picture-frame force
past 20°").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import inputs
from ..analysis import FabricFrame, family_axes_deg
from ..errors import InputError
from ..model.bead_model import BeadModel, BondType
from ..model.timestep import fibre_transit_s
from ..results.curves import locking_angle, values_at
from ..results.fibre_angles import fibre_shear_angles
from ..results.figure import report_marks
from ..results.zone_thickness import frame_zone_thickness, zone_summary
from ..scene import blocks
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
from .driven import ClampedTest, DrivenResult, clamp_power
from .driven_outputs import energy_columns, read_outputs

PROTOCOL = "picture_frame"


# -- frame kinematics and the standard normalisation (closed form) -----------------------
def frame_angle_rad(displacement_m, frame_length_m: float):
    """Half the angle between the arms at the pulled corner, θ [rad]:
    cos θ = (√2·L + d)/(2·L)."""
    return np.arccos((math.sqrt(2) * frame_length_m + np.asarray(displacement_m, float))
                     / (2 * frame_length_m))


def shear_angle_from_displacement_deg(displacement_m, frame_length_m: float):
    """Shear angle γ = 90° − 2θ of a picture frame [deg]."""
    return 90.0 - 2.0 * np.degrees(frame_angle_rad(displacement_m, frame_length_m))


def displacement_for_shear_angle_m(shear_angle_deg, frame_length_m: float):
    """Corner displacement d that gives shear angle γ: d = 2·L·cos(45° − γ/2) − √2·L [m]."""
    theta = np.radians(45.0 - np.asarray(shear_angle_deg, float) / 2)
    return 2 * frame_length_m * np.cos(theta) - math.sqrt(2) * frame_length_m


def shear_force_n(frame_force_n, displacement_m, frame_length_m: float):
    """Shear force along the arms, F_s = F/(2 cos θ) [N]."""
    return np.asarray(frame_force_n, float) / (
        2 * np.cos(frame_angle_rad(displacement_m, frame_length_m)))


def normalised_shear_force_n_m(shear_force, frame_length_m: float, fabric_length_m: float):
    """F_norm = F_s·L_frame/L_fabric² [N/m] (Harrison et al. 2004): frames of any size compare."""
    return np.asarray(shear_force, float) * frame_length_m / fabric_length_m**2


@dataclass(frozen=True)
class FrameGeometry:
    """Where the frame and its clamps are on a coupon (all in m)."""

    pin_a: tuple[float, float]
    frame_length_m: float
    fabric_length_m: float
    clamp_width_m: float
    inner: tuple[float, float, float, float]  # x_lo, x_hi, y_lo, y_hi of the free fabric
    centre: tuple[float, float]
    free_side_m: float
    clamp_yarns: int | None = None  # whole yarns each clamp holds (None: a strip width)

    @property
    def sheared_side_m(self) -> float:
        """Side of the square F_norm is normalised by [m]: the fabric's side, or with
        whole-yarn clamps the free square's (the area that shears)."""
        return self.free_side_m if self.clamp_yarns else self.fabric_length_m


def whole_yarn_edges(model: BeadModel, axis: int, n_yarns: int) -> tuple[float, float]:
    """Clamp edges along ``axis`` (0: x, 1: y) [m] that hold ``n_yarns`` whole yarns on
    each side: the yarns that run across ``axis`` (along the clamp's edge), sorted by
    their position on it; each edge lies midway in the gap between the last held yarn's
    outermost bead centre and the first free yarn's, so the free square spans a whole
    number of yarn spacings (gap centre to gap centre) at every coupon size."""
    p, yid = model.positions, model.yarn_ids
    spans, centres = [], []
    for y in np.unique(yid):
        q = p[yid == y]
        if np.ptp(q[:, 1 - axis]) > np.ptp(q[:, axis]):  # runs along the edge
            spans.append((q[:, axis].min(), q[:, axis].max()))
            centres.append(q[:, axis].mean())
    spans = [spans[k] for k in np.argsort(centres)]
    name = "xy"[axis]
    if len(spans) < 2 * n_yarns + 2:
        raise InputError(f"picture_frame.clamp_yarns = {n_yarns} holds {2 * n_yarns} of the "
                         f"{len(spans)} yarns across {name} and leaves fewer than 2 free; use "
                         f"at most {max(len(spans) // 2 - 1, 0)} or a larger coupon")
    (_, low_held), (low_free, _) = spans[n_yarns - 1], spans[n_yarns]
    (_, high_free), (high_held, _) = spans[-n_yarns - 1], spans[-n_yarns]
    if low_free <= low_held or high_held <= high_free:
        raise InputError(f"picture_frame.clamp_yarns: the yarns across {name} touch (no gap "
                         f"between held and free yarns to put a clamp edge in); use "
                         f"clamp_width_m")
    return 0.5 * (low_held + low_free), 0.5 * (high_free + high_held)


@dataclass(frozen=True, kw_only=True)
class PictureFrame(ClampedTest):
    """Picture-frame shear test of a square coupon (warp along x, weft along y).

    The loading, contact, output, ``relax`` and ``drag`` fields are those of
    :class:`~fabmd.protocols.driven.ClampedTest`: ``speed_fraction`` is the pulled
    corner's (default 1e-3: on the example coupon halving it changes the curve by
    < 0.1 %); the affine drag field is the frame's, so the drag does not add to the frame
    force (``"absolute"``, the old ``fix viscous``, does); the fibre shear angle of the
    central zone, and the thickness of that zone and of the band next to the clamps
    (``zone_thickness``, :mod:`fabmd.results.zone_thickness`), are measured on the
    trajectory frames (``TrajectoryOutput(frames=0)``: none written, none measured).

    Args:
        max_shear_angle_deg: shear angle at the end of the test [deg], (0, 80].
        max_displacement_m: corner displacement at the end [m]; overrides the angle.
        frame_length_m: arm length pin to pin [m]; default 5 % longer than the fabric side.
        clamp_width_m: width of the clamped strip along each edge [m]; default a tenth
            of the fabric side.
        clamp_yarns: each clamp holds this many whole yarns (those along its edge), its
            edge midway in the gap to the first free yarn, so the free square is a whole
            number of yarn spacings at every coupon size; F_norm is then per area of the
            free square (the area that shears). Overrides ``clamp_width_m``; None
            (default): the strip of ``clamp_width_m``.
        pretension_strain: clamping preload: rest-length shrink of the unclamped fibres,
            in (-0.05, 0.05); negative: mounting slack, their rest length grows by its
            size.
        pretension_transits: duration of the preload ramp in axial wave transits of the
            longest fibre.
        report_angles_deg: shear angles at which forces are reported.
        locking_initial_deg: shear-angle range [deg] of the initial branch of the
            locking-angle method (:func:`fabmd.results.curves.locking_angle`).
        locking_factor: the force over the initial line that marks the departure
            from it (> 1).
        loading_speed: adaptive corner speed (opt-in, :mod:`fabmd.scene.adaptive`); the
            speed history is the curve's ``corner_speed_m_s``.
    """

    protocol = PROTOCOL
    affine_start_supported = True
    interval_axis = ("shear_angle_deg", 5.0)
    rate_curve = ("shear_angle_deg", "normalised_force_n_m")
    rate_keys = {
        "initial_stiffness_change": "initial_shear_stiffness_n_m_per_rad",
        "locking_angle_change": "locking_angle_deg"}

    max_shear_angle_deg: float = 60.0
    max_displacement_m: float | None = None
    frame_length_m: float | None = None
    clamp_width_m: float | None = None
    clamp_yarns: int | None = None
    pretension_strain: float = 0.0
    pretension_transits: float = 20.0
    report_angles_deg: tuple[float, ...] = (10.0, 20.0, 30.0, 40.0)
    locking_initial_deg: tuple[float, float] = (10.0, 20.0)
    locking_factor: float = 2.0
    speed_fraction: float = 1e-3
    loading_speed: AdaptiveLoading = field(default_factory=AdaptiveLoading)

    def check_fields(self) -> None:
        inputs.in_range("picture_frame.max_shear_angle_deg", self.max_shear_angle_deg, 0, 80,
                        low_open=True)
        self.check_positive_or_none("max_displacement_m", "frame_length_m", "clamp_width_m")
        if self.clamp_yarns is not None:
            inputs.positive_int("picture_frame.clamp_yarns", self.clamp_yarns)
        inputs.in_range("picture_frame.pretension_strain", self.pretension_strain, -0.05, 0.05,
                        low_open=True, high_open=True)
        inputs.positive("picture_frame.pretension_transits", self.pretension_transits)
        for a in self.report_angles_deg:
            inputs.finite("picture_frame.report_angles_deg", a)
        inputs.locking_method("picture_frame", self.locking_initial_deg, self.locking_factor, 80)
        if not isinstance(self.loading_speed, AdaptiveLoading):
            raise InputError(f"picture_frame.loading_speed must be an AdaptiveLoading, got "
                             f"{self.loading_speed!r}")
        self.loading_speed.check_speed("picture_frame", self.speed_fraction)

    def plan_loading(self, plan: RunPlan, model: BeadModel) -> RunPlan:
        length = float(np.ptp(model.positions[:, :2], axis=0).max())  # the longest fibre
        return adaptive_plan(plan, self.loading_speed, self.travel_m(model),
                             length / self.wave_speed_m_s(model))

    # -- geometry ---------------------------------------------------------------------
    def frame(self, model: BeadModel) -> FrameGeometry:
        """Frame and clamps on ``model``; refuses coupons that are not square."""
        p = model.positions
        lo, hi = p[:, :2].min(axis=0), p[:, :2].max(axis=0)
        d = float(model.diameters.max())
        sides = hi - lo + d
        if abs(sides[0] - sides[1]) > 0.1 * sides.max():
            raise InputError(f"picture_frame needs a square coupon, got {1e3 * sides[0]:.2f} x "
                             f"{1e3 * sides[1]:.2f} mm; cut one with "
                             f"Coupon(length_m=L, width_m=L)")
        side = float(sides.mean())
        frame = self.frame_length_m if self.frame_length_m is not None else 1.05 * side
        if frame < side * (1 - 1e-9):
            raise InputError(f"picture_frame.frame_length_m = {frame:g} m is shorter than the "
                             f"fabric side {side:g} m; the arms must hold the whole fabric")
        clamp = self.clamp_width_m if self.clamp_width_m is not None else 0.1 * side
        if clamp >= 0.35 * side:
            raise InputError(f"picture_frame.clamp_width_m = {clamp:g} m leaves too little free "
                             f"fabric on a {side:g} m coupon; use at most {0.35 * side:g} m")
        held = None if self.clamp_yarns is None else int(self.clamp_yarns)  # 1.0 from --set
        if held is not None:
            ends = [whole_yarn_edges(model, k, held) for k in range(2)]
            clamp = float(np.mean([ends[k][0] - p[:, k].min() + d / 2 for k in range(2)]))
        else:
            ends = [(p[:, k].min() + clamp, p[:, k].max() - clamp) for k in range(2)]
        edges = [e for k in range(2) for e in self.clamp_edges(p[:, k], *ends[k])]
        centre = (lo + hi) / 2
        pin = centre - frame / 2
        return FrameGeometry(pin_a=(float(pin[0]), float(pin[1])), frame_length_m=float(frame),
                             fabric_length_m=side, clamp_width_m=float(clamp),
                             inner=tuple(edges), centre=(float(centre[0]), float(centre[1])),
                             free_side_m=float(np.mean([edges[1] - edges[0],
                                                        edges[3] - edges[2]])),
                             clamp_yarns=held)

    def clamped(self, model: BeadModel) -> np.ndarray:
        """Mask of the clamped beads (outside the free square)."""
        x_lo, x_hi, y_lo, y_hi = self.frame(model).inner
        p = model.positions
        free = (p[:, 0] >= x_lo) & (p[:, 0] <= x_hi) & (p[:, 1] >= y_lo) & (p[:, 1] <= y_hi)
        return ~free

    def max_displacement(self, model: BeadModel) -> float:
        if self.max_displacement_m is not None:
            return self.max_displacement_m
        return float(displacement_for_shear_angle_m(self.max_shear_angle_deg,
                                                    self.frame(model).frame_length_m))

    def travel_m(self, model: BeadModel) -> float:
        return self.max_displacement(model)

    def check_orientation(self, model: BeadModel) -> None:
        """Warp must run along x and weft along y (within 15°)."""
        axes = family_axes_deg(FabricFrame.from_model(model))
        for fam, want in (("warp", 0.0), ("weft", 90.0)):
            got = axes.get(fam)
            if got is not None and abs(((got - want) + 90) % 180 - 90) > 15:
                raise InputError(f"picture_frame needs {fam} along {'x' if want == 0 else 'y'}, "
                                 f"but its fibres run at {got:.0f} deg; cut the coupon at "
                                 f"angle_deg = 0")

    # -- preload ----------------------------------------------------------------------
    def prepare(self, model: BeadModel) -> BeadModel:
        """Validate; with a preload, give the unclamped fibres' bonds their own types."""
        geometry = self.frame(model)
        self.check_orientation(model)
        dmax = self.max_displacement(model)
        limit = float(displacement_for_shear_angle_m(80.0, geometry.frame_length_m))
        if dmax > limit:
            raise InputError(f"picture_frame.max_displacement_m = {dmax:g} m shears the frame "
                             f"beyond 80 deg; use at most {limit:g} m")
        if self.pretension_strain == 0:
            return model
        clamped = self.clamped(model)
        preloaded = (~(clamped[model.bonds[:, 0]] & clamped[model.bonds[:, 1]])
                     & model.fibre_bond_mask())  # the fibres, not yarn cohesion links
        table = list(model.bond_type_table)
        types = model.bond_types.copy()
        new_type = {}
        for t in np.unique(model.bond_types[preloaded]):
            bt = table[t - 1]
            table.append(BondType(bt.coefficient, bt.rest_length_m, bt.family,
                                  bt.axial_stiffness_n))
            new_type[int(t)] = len(table)
        types[preloaded] = [new_type[int(t)] for t in model.bond_types[preloaded]]
        info = dict(model.info, picture_frame_preload={
            "strain": self.pretension_strain, "bond_types": sorted(new_type.values())})
        return BeadModel(**{**model.__dict__, "bond_type_table": table, "bond_types": types,
                            "info": info})

    def preload_types(self, model: BeadModel) -> list[int]:
        return list(model.info.get("picture_frame_preload", {}).get("bond_types", []))

    def pretension_block(self, model: BeadModel) -> str:
        types = self.preload_types(model)
        if not types or self.pretension_strain == 0:
            return "# no clamping preload"
        s = self.pretension_strain
        slack = s < 0  # mounting slack: the rest length grows
        steps = max(1000, int(self.pretension_transits * fibre_transit_s(model)
                              / self.time_step_s(model)))
        return render("pretension", strain=abs(s), held="clamps", free="free",
                      what="mounting slack" if slack else "clamping preload",
                      change="grows" if slack else "shrinks",
                      kept="longer" if slack else "shorter",
                      ramp=blocks.bond_ramp(model, "pretension", dict.fromkeys(types, abs(s)),
                                            shrink=not slack),
                      steps=steps, ramp_end=blocks.bond_ramp_end(
                          model, "pretension", dict.fromkeys(types, 1 - s), types,
                          note=", slack" if slack else ", preloaded"))

    # -- input ------------------------------------------------------------------------
    def input_text(self, model: BeadModel) -> str:
        g = self.frame(model)
        dt = self.time_step_s(model)
        load = self.loading(model)
        ea = max(bt.bond_axial_stiffness_n for bt in model.fibre_bond_types())
        ref_force = max(self.pretension_strain, 1e-3) * ea
        power, power_ref = clamp_power("clamps")
        field = AffineField(
            origin_m=(float(g.pin_a[0]), float(g.pin_a[1])), xx="v_frame_lxx",
            xy="v_frame_lxy", yx="v_frame_lxy", yy="v_frame_lxx", tools="frame")
        damping, damping_power = self.drag_block(model, field)
        adaptive = self.loading_speed.adaptive
        outputs = self.outputs_block(
            model, power, power_ref,
            print_values="${d} ${shear_deg} ${dd}" if adaptive else "${d} ${shear_deg}",
            print_names="displacement_m shear_angle_lammps_deg corner_speed_m_s" if adaptive
            else "displacement_m shear_angle_lammps_deg",
            thermo_values="v_d v_shear_deg c_p_ext", damping_power=damping_power,
            affine=field)
        motion = {"displacement": load.lammps_displacement(),
                  "velocity": load.lammps_velocity(),
                  "displacement_next": load.lammps_displacement("t_next"),
                  "velocity_next": load.lammps_velocity("t_next")}
        if adaptive:  # the corner moves on by the adapted speed, from where the frame is
            k = max(bt.spring_n_per_m for bt in model.fibre_bond_types())
            n = int(model.fibre_bond_mask().sum())
            plan = self.plan(model)
            outputs += "\n" + speed_commands(plan, power_ref, n * ref_force**2 / (2 * k),
                                             ref_force * plan.speed_m_s, displacement="d")
            motion = {"displacement": self.corner_travel(model),
                      "velocity": f"({motion['velocity']})*v_adapt_factor",
                      "displacement_next": "v_d+dt*v_dd_next",
                      "velocity_next": f"({motion['velocity_next']})*v_adapt_factor"}
        text = render("picture_frame", frame_length=g.frame_length_m, ax=g.pin_a[0],
                      ay=g.pin_a[1], x_lo=g.inner[0], x_hi=g.inner[1], y_lo=g.inner[2],
                      y_hi=g.inner[3], pretension=self.pretension_block(model),
                      relax=self.relax_block(model, "clamps", "free", ref_force),
                      **motion, damping=damping,
                      start=self.start_block(self.start_field(model)), outputs=outputs)
        return self.scene_text(model, dt, text)

    def start_field(self, model: BeadModel) -> AffineField:
        """The frame's affine velocity field at the start, v = L0·(r − A), in numbers (the
        drag's field reads fixes not yet computed before the run): at 0° the gradient is
        L0 = [[0, p0], [p0, 0]], p0 = ḋ/(√2·L) (ḋ the corner's speed, L the arm)."""
        g = self.frame(model)
        p0 = fmt(self.loading(model).speed_m_s / (math.sqrt(2) * g.frame_length_m))
        return AffineField(origin_m=(float(g.pin_a[0]), float(g.pin_a[1])), xy=p0, yx=p0,
                           tools="frame")

    def corner_travel(self, model: BeadModel) -> str:
        """LAMMPS formula of the pulled corner's travel d [m], read back from the clamps'
        centre of mass (adaptive loading: the travel is the integral of the speed, and a
        resumed run finds it there too).

        A clamped bead sits at A + xi e1 + eta e2, so the clamps' centre relative to pin A
        sums to S = (mean xi + mean eta)(cos phi + sin phi) = S0 sqrt(2) cos(theta), and
        d = 2 L cos(theta) - sqrt(2) L = sqrt(2) L (S / S0 - 1), S0 its value at the start
        (the clamps are held while relaxing)."""
        g = self.frame(model)
        sel = self.clamped(model)
        m, p = model.masses[sel], model.positions[sel]
        s0 = float(np.sum(m * ((p[:, 0] - g.pin_a[0]) + (p[:, 1] - g.pin_a[1]))) / np.sum(m))
        ax, ay, length = fmt(g.pin_a[0]), fmt(g.pin_a[1]), fmt(g.frame_length_m)
        return (f"sqrt(2)*{length}*(((xcm(clamps,x)-({ax}))+(xcm(clamps,y)-({ay})))"
                f"/{fmt(s0)}-1)")

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        return reduce(run_dir, model, self, monitor)


def interval_force(displacement: np.ndarray, work: np.ndarray) -> np.ndarray:
    """Force from the power balance: work over displacement in each interval (0 at the first
    sample; an interval without displacement keeps the previous value)."""
    dd = np.diff(displacement)
    dw = np.diff(work)
    force = np.zeros_like(displacement)
    for k in range(len(dd)):
        force[k + 1] = dw[k] / dd[k] if abs(dd[k]) > 0 else force[k]
    return force


def frame_force_n(d: np.ndarray, out, window: float | None) -> np.ndarray:
    """Frame force [N] per output interval from the work the frame did over its travel
    ``d`` [m], less the work that sped the fabric's carriage up or was given back as it
    slowed (the fabric moves with the frame, its arms turn faster as the shear grows, and
    an adaptive run changes the speed: that kinetic energy follows the speed squared).
    The carriage's kinetic energy is the fabric's less the part relative to the frame's
    affine field (``kinetic_relative_j``): a crossing that snaps through turns strain
    energy into motion of its own, which the frame did not pay for (taking the whole
    kinetic energy off read −418 N there on the test square, where the work gives 76 N).
    Adaptive loading (``window``: the fixed run's interval travel [m]): averaged over that
    travel."""
    carriage = out["kinetic_j"] - out.columns.get("kinetic_relative_j", 0.0)
    force = interval_force(d, out.external_work_j - carriage)
    return force if window is None else window_mean(d, force, window)


def reduce(run_dir: Path, model: BeadModel, test: PictureFrame,
           monitor: ContactPower | None = None) -> DrivenResult:
    """Curve (shear angle, frame force, F_s, F_norm), locking angle and the evidence."""
    g = test.frame(model)
    plan = test.read_plan(run_dir, model)  # what the run was written with
    out = read_outputs(run_dir, plan.every, plan.time_step_s, monitor)
    d = out["displacement_m"]
    gamma = shear_angle_from_displacement_deg(d, g.frame_length_m)
    force = frame_force_n(d, out, window_width_m(plan))
    fs = shear_force_n(force, d, g.frame_length_m)
    fnorm = normalised_shear_force_n_m(fs, g.frame_length_m, g.sheared_side_m)
    curve = {"time_s": out["time_s"], "displacement_m": d, "shear_angle_deg": gamma,
             "frame_angle_deg": np.degrees(frame_angle_rad(d, g.frame_length_m)),
             "frame_force_n": force, "shear_force_n": fs, "normalised_force_n_m": fnorm,
             **energy_columns(out)}
    if "corner_speed_m_s" in out.columns:  # adaptive loading: the speed history
        curve["corner_speed_m_s"] = out["corner_speed_m_s"]
    dmax = test.max_displacement(model)
    # by a method that reads the curve only up to a little past locking (not the last part)
    lock = locking_angle(gamma, fnorm, initial_deg=test.locking_initial_deg,
                         factor=test.locking_factor)
    # the initial branch's slope, per radian
    initial = (None if lock["initial_slope"] is None
               else float(np.degrees(lock["initial_slope"])))
    steps, fibre_gamma = fibre_shear_angles(run_dir, g.centre,
                                            (g.free_side_m / 4, g.free_side_m / 4))
    kinematic = np.interp(steps, out["step"], gamma) if len(steps) else np.zeros(0)
    # the clamps compact the yarns next to them: the band there thickens beyond the centre
    zones = frame_zone_thickness(run_dir, g.inner, g.centre)
    zone_block = (zone_summary(np.interp(zones["step"], out["step"], gamma),
                               zones["centre_m"], zones["edge_m"])
                  if len(zones["step"]) else None)
    summary = {
        "protocol": PROTOCOL,
        "n_beads": model.n_beads,
        "n_clamped_beads": int(test.clamped(model).sum()),
        "fabric_length_m": g.fabric_length_m,
        "frame_length_m": g.frame_length_m,
        "clamp_width_m": g.clamp_width_m,
        "free_side_m": g.free_side_m,
        "clamp_yarns": g.clamp_yarns,
        "normalised_by_side_m": g.sheared_side_m,
        "pretension_strain": test.pretension_strain,
        "time_step_s": plan.time_step_s,
        "steps": plan.steps,
        "corner_speed_m_s": plan.loading.speed_m_s,
        "start": test.start_kind(),
        **adaptive_summary(plan, out["step"], out["time_s"],
                           out.columns.get("corner_speed_m_s")),
        "max_displacement_m": dmax,
        "max_shear_angle_deg": float(gamma.max()),
        "initial_shear_stiffness_n_m_per_rad": initial,
        "locking_angle_deg": lock["x"] if lock["found"] else None,
        "locking": lock,
        "normalised_force_at_angle_n_m": {f"{k:g}": v for k, v in values_at(
            gamma, fnorm, test.report_angles_deg).items()},
        "frame_force_at_angle_n": {f"{k:g}": v for k, v in values_at(
            gamma, force, test.report_angles_deg).items()},
        "max_frame_force_n": float(force.max()),
        "mean_frame_force_n": float(out.external_work_j[-1] / dmax),
        "max_normalised_force_n_m": float(fnorm.max()),
        "fibre_shear_angle": {
            "zone": "central square, half the free side wide",
            "steps": steps.tolist(), "kinematic_deg": kinematic.tolist(),
            "fibres_deg": fibre_gamma.tolist(),
            "max_difference_deg": float(np.abs(fibre_gamma - kinematic).max())
            if len(steps) else None},
        "zone_thickness": zone_block,
        **test.quasi_static_evidence(out, model, d / dmax),
    }
    per = "L_free²" if g.clamp_yarns else "L_fabric²"  # whole-yarn clamps: the free square
    series = [{"x": gamma, "y": fnorm, "label": f"F_norm = F_s L_frame / {per}"}]
    if lock["found"]:
        series.append({"x": [lock["x"], lock["x"]], "y": [0.0, float(fnorm.max())],
                       "style": "--", "label": f"locking {lock['x']:.1f}°", "lw": 1.0})
    ke = summary["max_kinetic_to_strain_energy"]
    plot = {"path": "curve.png", "series": series, "xlabel": "shear angle γ [deg]",
            "ylabel": "normalised shear force [N/m]", "title": "Picture-frame shear",
            "marks": report_marks(summary["normalised_force_at_angle_n_m"]),
            "notes": f"fabric {1e3 * g.fabric_length_m:.1f} mm, frame "
                     f"{1e3 * g.frame_length_m:.1f} mm, preload {test.pretension_strain:g}"
                     f"\nKE/U after start-up <= {'n/a' if ke is None else f'{ke:.3g}'}"
                     f"\n{model.n_beads} beads"}
    return DrivenResult(Path(run_dir), curve, summary, [plot])
