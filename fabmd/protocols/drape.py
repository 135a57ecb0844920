"""Draping with a hemispherical punch: how a fabric follows a double-curved tool.

The blank (warp along x, weft along y) lies flat on a die, a plane with a
circular opening of radius R + c (punch radius R, clearance c). A blank holder,
a plane pressing down on the fabric outside the opening, is force-controlled: it
moves down at a speed proportional to the difference between the set force and
the contact force it takes (``fix controller``), like a plate on a viscous guide
pressed by the set force. Once the holder has clamped the fabric, a rigid sphere
of radius R on the opening's axis moves down by the set depth (smooth start, then
constant speed) and draws the fabric into the opening. Tools touch fibres through
``fix wall/gran/region`` with their own friction (:class:`ToolContact`); only
beads that can reach a tool are given its contact (groups of the initial
positions: punch within the arc it can wrap plus a margin, die and holder outside
the opening).

Symmetry: the quarter model (default) keeps the blank's x > 0, y > 0 part; the
symmetry planes x = 0 and y = 0 are the blank's centre lines, placed between
yarns, and the fibre ends cut there are held in that plane's normal direction
(``fix setforce`` on that component, zero velocity; ``fix nve`` then never moves
them across). Forces are reported for the whole blank (4 × the quarter's).

Outputs (besides the driven-test evidence, see :mod:`fabmd.protocols.driven`):
punch force against depth, the holder force and its error after start-up, the
in-plane shear-angle field over the draped fabric from the local warp and weft
tangents (:func:`fabmd.analysis.surface_shear_angle_field`, grid over the initial
positions; CSV + NPZ + PNG map) and its largest value, a wrinkling indicator
(distance of the beads over the punch cap, where the fabric should lie on it, to
the sphere minus half the fabric thickness: max and RMS), the edge draw-in along
warp, weft and the diagonal, the final shape (``final.vtu``, ``shape.png``) and
the trajectory (``trajectory.h5``, ParaView files).

Energy: the external work of punch and holder = Δ strain energy + Δ kinetic
energy + viscous damping + fibre–fibre contact work (sampled by the in-process
engine) + the work the tool contacts absorb (exact, each step: force · (tool
velocity − bead velocity)); the closing error is reported.
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
from ..errors import InputError, SimulationFailed
from ..model.bead_model import BeadModel
from ..model.beads import TimeStep, model_bead_parameters
from ..model.contact import ContactModel, ToolContact
from ..model.transform import subset
from ..results.curves import values_at
from ..results.folder import read_print_file, write_csv, write_json
from ..results.plots import plot_field
from ..results.trajectory import finalise, salvage
from ..scene import blocks
from ..scene.energy import ContactPower
from ..scene.outputs import TrajectoryOutput
from ..scene.quasi_static import QuasiStatic
from ..scene.templates import render
from .common import DATA_FILE, overlap_summary
from .driven import (
    DrivenResult,
    DrivenTest,
    kinetic_to_work_ratio,
    read_outputs,
    started_mask,
)

PROTOCOL = "drape"
SYMMETRIES = ("quarter", "full")
#: tool wall fix ids (their contact arrays feed the forces and the overlap monitor)
TOOLS = ("punch", "die", "die_wall", "holder")
#: forces and powers are sampled every this many steps for the interval means
SAMPLE_EVERY = 5
#: overlap monitor interval, and its log of the clamping phase (overlap.dat: the draw)
OVERLAP_EVERY = 100
CLAMP_OVERLAP_FILE = "clamp_overlap.dat"


@dataclass(frozen=True)
class DrapeGeometry:
    """Tools and zones of a drape on a prepared (centred) blank; lengths in m."""

    quarter: bool
    radius_m: float
    die_radius_m: float
    holder_radius_m: float
    z_die_m: float
    z_holder_m: float
    punch_z_m: float
    gap_m: float
    thickness_m: float
    spacing_m: float
    half_size_m: tuple[float, float]
    punch_reach_m: float
    die_reach_m: float
    contact_angle_rad: float
    flange_reach_m: float
    face_radius_m: float
    diameter_m: float
    sym_x: tuple[int, ...]
    sym_y: tuple[int, ...]

    @property
    def share(self) -> float:
        """Part of the whole blank the model holds (1/4 for the quarter)."""
        return 0.25 if self.quarter else 1.0


def yarn_centres(model: BeadModel, family: str, axis: int) -> np.ndarray:
    """Sorted mean ``axis`` coordinate of every yarn of ``family`` [m]."""
    yid = model.yarn_ids
    pos = model.positions[:, axis]
    out = [float(pos[yid == k + 1].mean()) for k, y in enumerate(model.yarns)
           if y.family == family and np.any(yid == k + 1)]
    return np.sort(np.asarray(out))


def gap_line(centres: np.ndarray, near: float) -> float:
    """The mid-line between two neighbouring yarns closest to ``near``."""
    if len(centres) < 2:
        raise InputError("the blank needs at least two yarns of each family")
    mids = 0.5 * (centres[1:] + centres[:-1])
    return float(mids[np.argmin(np.abs(mids - near))])


def contact_angle_rad(radius: float, die_radius: float, centre_above_die: float,
                      thickness: float) -> float:
    """Polar angle (from the punch's lowest point) up to which a taut fabric wraps the punch:
    the tangent from the die edge (offset by half the fabric thickness) to the punch."""
    r = radius + 0.5 * thickness
    ex, ez = die_radius, 0.5 * thickness - centre_above_die  # die edge relative to the centre
    dist = math.hypot(ex, ez)
    if dist <= r:
        return math.pi / 2
    towards_edge = math.atan2(ex, -ez)  # angle of the edge from the downward axis
    return max(0.0, towards_edge - math.acos(r / dist))


@dataclass(frozen=True)
class Drape(DrivenTest):
    """Hemispherical-punch draping of a flat blank (warp along x, weft along y).

    Args:
        punch_radius_m: punch radius R [m] (> 0).
        depth_m: punch travel after touching the fabric [m], in (0, R].
        die_clearance_m: die opening radius minus R [m] (>= 0); the fabric must pass
            between punch and die edge at full depth.
        holder_force_n: blank-holder force for the whole blank [N] (> 0; the quarter
            model's holder takes a quarter).
        holder_inner_radius_m: radius of the holder's opening [m]; default the die's.
        holder_gain_m_s_n: force-control gain α [m/s/N] (> 0): holder speed = α·(F_set − F);
            default the largest that keeps the control smooth (see :meth:`holder_control`).
        symmetry: ``"quarter"`` (two symmetry planes) or ``"full"``.
        tool: fibre–tool contact (punch, die and holder), friction μ (default 0.2).
        holder_damping_ratio: normal damping of the holder's contacts, fraction of critical,
            in (0, 1] (default 0.03: enough to keep the tangential history, see the contact
            section of the README; the damper under the holder limits how fast its force
            control may act, so a lighter one lets it follow the fabric's thickness).
        contact: fibre–fibre contact.
        speed_fraction: punch speed over the fibres' axial wave speed (> 0, <= 0.05).
        ramp_fraction: share of the draw spent reaching full punch speed smoothly.
        clamp: when the clamping phase (holder closing, punch waiting, fabric relaxing
            under local damping) is over: quasi-static criterion and its step limit.
        damping_time_s: τ of the viscous damping γ = m/τ (default: the draw's duration).
        time_step: time-step policy.
        samples: curve points.
        shear_cell_m: cell of the shear-angle grid [m]; default two yarn spacings (one
            plain-weave unit cell, so the crimp cancels).
        trajectory: trajectory frames (``TrajectoryOutput(frames=0)`` writes none).
        report_depths_m: depths at which punch forces are reported [m].
        modulus_scale: factor on the fibres' axial (and bending) stiffness for this test,
            in (0, 1]. Draping loads fibres far below their strength and stiffness (the
            summary reports the largest bond strain); a softer fibre takes a longer stable
            time step (∝ 1/sqrt(scale)), so the same punch speed needs fewer steps. Contact
            stiffness follows (it is a fraction of the fibres' E·A/l0).
        tool_zones: give each tool's contact only to the beads that can reach it
            (default True); False gives punch and die contact to every bead, which changes
            nothing but the cost (``benchmarks/drape.py`` measures both).
    """

    punch_radius_m: float = 0.05
    depth_m: float = 0.04
    die_clearance_m: float = 0.003
    holder_force_n: float = 100.0
    holder_inner_radius_m: float | None = None
    holder_gain_m_s_n: float | None = None
    symmetry: str = "quarter"
    tool: ToolContact = field(default_factory=lambda: ToolContact(friction=0.2))
    holder_damping_ratio: float = 0.03
    contact: ContactModel = field(default_factory=ContactModel)
    speed_fraction: float = 5e-4
    ramp_fraction: float = 0.05
    clamp: QuasiStatic = field(default_factory=lambda: QuasiStatic(max_steps=20_000))
    damping_time_s: float | None = None
    time_step: TimeStep = field(default_factory=TimeStep)
    samples: int = 200
    shear_cell_m: float | None = None
    trajectory: TrajectoryOutput = field(default_factory=lambda: TrajectoryOutput(frames=20))
    report_depths_m: tuple[float, ...] = ()
    modulus_scale: float = 1.0
    tool_zones: bool = True

    protocol: ClassVar[str] = PROTOCOL
    rate_curve: ClassVar[tuple[str, str]] = ("depth_m", "punch_force_n")
    rate_keys: ClassVar[dict[str, str]] = {"max_punch_force_change": "max_punch_force_n",
                                           "max_shear_angle_change": "max_shear_angle_deg"}
    # the fabric riding on the punch makes KE/W large in a slow draw (see ``inertia``): the
    # drape judges the inertial share of the punch force instead
    quasi_static_limits: ClassVar[dict[str, float]] = {"mean_inertial_to_punch_force": 0.05,
                                                       "damping_share": 0.5,
                                                       "energy_balance_error": 0.05}

    def __post_init__(self):
        r = inputs.positive("drape.punch_radius_m", self.punch_radius_m)
        inputs.positive("drape.depth_m", self.depth_m)
        if self.depth_m > r:
            raise InputError(f"drape.depth_m must be <= punch_radius_m = {r:g} m (the punch "
                             f"is a hemisphere), got {self.depth_m:g}")
        inputs.non_negative("drape.die_clearance_m", self.die_clearance_m)
        inputs.positive("drape.holder_force_n", self.holder_force_n)
        if self.holder_inner_radius_m is not None:
            inputs.positive("drape.holder_inner_radius_m", self.holder_inner_radius_m)
            if self.holder_inner_radius_m < r + self.die_clearance_m:
                raise InputError(f"drape.holder_inner_radius_m must be >= the die opening "
                                 f"radius {r + self.die_clearance_m:g} m (the holder presses "
                                 f"the fabric on the die), got {self.holder_inner_radius_m:g}")
        if self.holder_gain_m_s_n is not None:
            inputs.positive("drape.holder_gain_m_s_n", self.holder_gain_m_s_n)
        inputs.one_of("drape.symmetry", self.symmetry, SYMMETRIES)
        if not isinstance(self.tool, ToolContact):
            raise InputError(f"drape.tool must be a ToolContact, got {self.tool!r}")
        inputs.in_range("drape.holder_damping_ratio", self.holder_damping_ratio, 0.0, 1.0,
                        low_open=True)
        inputs.in_range("drape.speed_fraction", self.speed_fraction, 0, 0.05, low_open=True)
        inputs.in_range("drape.ramp_fraction", self.ramp_fraction, 0, 0.9)
        if not isinstance(self.clamp, QuasiStatic):
            raise InputError(f"drape.clamp must be a QuasiStatic, got {self.clamp!r}")
        if self.damping_time_s is not None:
            inputs.positive("drape.damping_time_s", self.damping_time_s)
        inputs.positive_int("drape.samples", self.samples, minimum=10)
        if self.shear_cell_m is not None:
            inputs.positive("drape.shear_cell_m", self.shear_cell_m)
        if not isinstance(self.trajectory, TrajectoryOutput):
            raise InputError(f"drape.trajectory must be a TrajectoryOutput, "
                             f"got {self.trajectory!r}")
        for d in self.report_depths_m:
            inputs.positive("drape.report_depths_m", d)
        inputs.in_range("drape.modulus_scale", self.modulus_scale, 0, 1, low_open=True)

    # -- geometry -------------------------------------------------------------------------
    @property
    def die_radius_m(self) -> float:
        return self.punch_radius_m + self.die_clearance_m

    @property
    def holder_radius_m(self) -> float:
        """Inner radius of the holder: given, or the die's opening."""
        return self.holder_inner_radius_m or self.die_radius_m

    def check_orientation(self, model: BeadModel) -> None:
        """Warp along x and weft along y (within 15°), both present."""
        from ..analysis import FabricFrame, family_axes_deg

        axes = family_axes_deg(FabricFrame.from_model(model))
        for fam, want in (("warp", 0.0), ("weft", 90.0)):
            got = axes.get(fam)
            if got is None:
                raise InputError(f"drape needs warp and weft yarns; the blank has "
                                 f"{list(model.family_names)}")
            if abs(((got - want) + 90) % 180 - 90) > 15:
                raise InputError(f"drape needs {fam} along {'x' if want == 0 else 'y'}, but "
                                 f"its fibres run at {got:.0f} deg; cut the blank at "
                                 f"angle_deg = 0")

    def centred(self, model: BeadModel) -> tuple[BeadModel, float]:
        """The blank with its centre lines (between yarns) on x = 0, y = 0 and its mid-plane
        on z = 0; and the yarn spacing [m]."""
        if any(model.periodic):
            raise InputError("drape needs a finite blank, not a periodic cell; cut one with "
                             "Coupon(length_m=L, width_m=L) (fabmd test drape does)")
        self.check_orientation(model)
        p = model.unwrapped_positions
        lo, hi = p.min(axis=0), p.max(axis=0)
        centre = 0.5 * (lo + hi)
        weft_x = yarn_centres(model, "weft", 0)
        warp_y = yarn_centres(model, "warp", 1)
        x0 = gap_line(weft_x, centre[0])
        y0 = gap_line(warp_y, centre[1])
        spacing = float(max(np.median(np.diff(weft_x)), np.median(np.diff(warp_y))))
        shift = np.array([x0, y0, centre[2]])
        moved = dataclasses.replace(model, positions=p - shift, images=None,
                                    box_lo=model.box_lo - shift, box_hi=model.box_hi - shift,
                                    info=dict(model.info))
        d = float(model.diameters.max())
        for axis, fam in ((0, "weft"), (1, "warp")):
            on_plane = np.abs(moved.positions[:, axis]) < 0.5 * d
            if np.any(on_plane & (moved.families == fam)):
                raise InputError(f"a {fam} yarn lies on the symmetry plane "
                                 f"{'xy'[axis]} = 0 of the blank; the yarns are too wide "
                                 f"for their spacing")
        return moved, spacing

    def blank(self, model: BeadModel) -> BeadModel:
        """The model to run: the blank centred (:meth:`centred`), its x > 0, y > 0 quarter for
        ``symmetry="quarter"``; checked against the tools."""
        full, spacing = self.centred(model)
        p = full.positions
        half = (float(min(p[:, 0].max(), -p[:, 0].min())),
                float(min(p[:, 1].max(), -p[:, 1].min())))
        holder_radius = self.holder_radius_m
        need = holder_radius + spacing
        if min(half) < need:
            raise InputError(f"the blank ({2e3 * half[0]:.1f} x {2e3 * half[1]:.1f} mm) must "
                             f"reach past the holder's opening (radius "
                             f"{1e3 * holder_radius:.1f} mm) by a yarn spacing: use a "
                             f"blank at least {2e3 * need:.1f} mm wide")
        keep = (p[:, 0] > 0) & (p[:, 1] > 0) if self.symmetry == "quarter" else \
            np.ones(full.n_beads, bool)
        run = subset(full, keep)
        if self.modulus_scale != 1.0:
            k = self.modulus_scale
            run.bond_type_table = [dataclasses.replace(bt, coefficient=bt.coefficient * k,
                                                       axial_stiffness_n=bt.axial_stiffness_n * k)
                                   for bt in run.bond_type_table]
            run.angle_type_table = [dataclasses.replace(at, coefficient=at.coefficient * k)
                                    for at in run.angle_type_table]
        run.info = dict(run.info, drape={"modulus_scale": self.modulus_scale,
            "symmetry": self.symmetry, "spacing_m": spacing, "blank_half_size_m": list(half),
            "thickness_m": float(np.ptp(p[:, 2]) + full.diameters.max())})
        g = self._geometry_of(run)
        # the fabric must pass between the punch and the die edge at full depth
        edge_gap = math.hypot(g.die_radius_m, g.punch_z_m - self.travel_m(run) - g.z_die_m) \
            - g.radius_m
        if edge_gap < g.thickness_m:
            raise InputError(f"at depth {1e3 * self.depth_m:g} mm the punch passes "
                             f"{1e3 * edge_gap:.2f} mm from the die edge, less than the fabric "
                             f"thickness {1e3 * g.thickness_m:.2f} mm: raise "
                             f"drape.die_clearance_m (now {1e3 * self.die_clearance_m:g} mm) "
                             f"or lower drape.depth_m")
        return run

    def prepare(self, model: BeadModel) -> BeadModel:
        return self.blank(model)

    def geometry(self, model: BeadModel) -> DrapeGeometry:
        """Tools and zones on a model from :meth:`prepare`."""
        if "drape" not in model.info:
            raise InputError("drape.geometry needs a model from Drape.prepare")
        return self._geometry_of(model)

    def _geometry_of(self, model: BeadModel) -> DrapeGeometry:
        q = model.positions
        d = float(model.diameters.max())
        info = model.info["drape"]
        spacing = float(info["spacing_m"])
        half = tuple(float(h) for h in info["blank_half_size_m"])
        quarter = info["symmetry"] == "quarter"
        thickness = float(info["thickness_m"])
        r_xy = np.hypot(q[:, 0], q[:, 1])
        z_die = float(q[:, 2].min() - 0.5 * d)
        holder_radius = self.holder_radius_m
        z_holder = float(q[r_xy > holder_radius, 2].max() + 0.5 * d)
        cap = r_xy < self.die_radius_m + d
        gap = 0.1 * d
        punch_z = float((q[cap, 2].max() if cap.any() else q[:, 2].max()) + 0.5 * d + gap
                        + self.punch_radius_m)
        r = self.punch_radius_m
        # arc of the punch below the die face at full depth, plus a margin: fibres do not
        # stretch, so beads that start further out cannot wrap it
        wrap = r * math.acos(max(-1.0, 1.0 - self.depth_m / r))
        sym_x: tuple[int, ...] = ()
        sym_y: tuple[int, ...] = ()
        if quarter:  # fibre ends cut by the symmetry planes
            longest = max(bt.rest_length_m for bt in model.fibre_bond_types())
            ends = np.unique(model.fibre_ends().ravel())
            sym_x = tuple(int(i) for i in ends[q[ends, 0] < 1.01 * longest])
            sym_y = tuple(int(i) for i in ends[q[ends, 1] < 1.01 * longest])
        centre_above_die = punch_z - self.travel_from(gap) - z_die
        # fabric that ends up inside the opening: at most the punch arc below the die face
        # plus the way out to the die edge (fibres do not stretch), plus margins
        theta = math.acos(max(-1.0, 1.0 - self.depth_m / r))
        path = r * theta + max(0.0, self.die_radius_m - r * math.sin(theta))
        flange = max(1.1 * path + 2 * spacing + d, self.die_radius_m + 2 * spacing + d)
        return DrapeGeometry(
            quarter=quarter, radius_m=r, die_radius_m=self.die_radius_m,
            holder_radius_m=holder_radius, z_die_m=z_die, z_holder_m=z_holder,
            punch_z_m=punch_z, gap_m=gap, thickness_m=thickness, spacing_m=spacing,
            half_size_m=half, punch_reach_m=1.25 * wrap + 2 * spacing + d,
            die_reach_m=max(0.0, self.die_radius_m - 2 * spacing - d),
            contact_angle_rad=contact_angle_rad(r, self.die_radius_m, centre_above_die,
                                                thickness),
            flange_reach_m=flange, face_radius_m=2.0 * math.hypot(*half) + 10 * d,
            diameter_m=d, sym_x=sym_x, sym_y=sym_y)

    # -- loading and time -------------------------------------------------------------------
    def travel_m(self, model: BeadModel) -> float:
        """The punch travels the depth plus the small gap it starts above the fabric."""
        return self.travel_from(0.1 * float(model.diameters.max()))

    def travel_from(self, gap_m: float) -> float:
        return self.depth_m + gap_m

    def time_step_s(self, model: BeadModel) -> float:
        """Stable time step with the stiffer of fibre–fibre and tool contact."""
        beads = model_bead_parameters(model)
        kn = max(self.contact.stability_stiffness_n_per_m(beads),
                 self.tool.normal_stiffness_n_per_m(beads))
        return self.time_step.resolve(min(b.critical_time_step_s(kn) for b in beads))

    def gamma(self, model: BeadModel) -> float:
        """Viscous damping γ = m/τ [kg/s]; τ default: the whole draw (a light drag: the fabric
        moves with the punch, and drag on it adds to the punch force)."""
        tau = self.damping_time_s or self.duration_s(model)
        return float(np.median(model.masses)) / tau

    def every(self, model: BeadModel) -> int:
        """Output interval: a multiple of the sampling interval of the means."""
        raw = math.ceil(self.duration_s(model) / self.time_step_s(model))
        return SAMPLE_EVERY * max(1, raw // self.samples // SAMPLE_EVERY)

    def clamp_values(self, model: BeadModel, geometry: DrapeGeometry) -> dict:
        """Template values of the clamping phase: local damping and a light drag (as in
        :func:`fabmd.scene.blocks.relax`) until quasi-static with the holder force within
        5 % of its set value. Quasi-static reference force: the holder force per yarn
        crossing under it."""
        control = self.holder_control(model, geometry)
        ref = self.holder_share_n(geometry) / control["crossings_under_holder"]
        k = max(2 * bt.coefficient for bt in model.fibre_bond_types())
        dt = self.time_step_s(model)
        return {"clamp_damping": 0.7,
                "clamp_drag": float(np.median(model.masses)) / (200.0 * dt),
                "clamp_monitors": self.clamp.monitors("free", ref,
                                                      model.n_bonds * ref**2 / (2 * k)),
                "clamp_tolerance": 0.05, "clamp_check_every": self.clamp.check_every,
                "clamp_max_steps": self.clamp.max_steps}

    @property
    def holder_tool(self) -> ToolContact:
        """The tool contact of the holder: the tools' with its own damping."""
        return dataclasses.replace(self.tool, damping_ratio=self.holder_damping_ratio)

    def holder_share_n(self, geometry: DrapeGeometry) -> float:
        return self.holder_force_n * geometry.share

    def holder_control(self, model: BeadModel, geometry: DrapeGeometry) -> dict:
        """Force-control gain α [m/s/N], its integral time and what limits them.

        Holder speed = α·(F_set − F + ∫(F_set − F) dt / T_i) (the integral only after the
        clamping phase). The holder is a massless plate on a dashpot 1/α pressing on the
        contacts under it: springs of stiffness K and dampers C, all in parallel, so that its
        force is F = K·x + C·ẋ. Explicit steps ẋ ← α·(F_set − F) are stable while α·C < 1 and
        α·K·dt < 1; α is kept below a quarter and a tenth of those (nearer the limits the
        holder excites the contacts under it and its force chatters). K and C are estimated
        from the yarn crossings under the holder, two bead contacts each, every contact a
        holder–fibre, fibre–fibre and fibre–die spring in series and the holder contact's
        damper (``ToolContact.damping_ratio``).
        """
        beads = model_bead_parameters(model)
        wall = self.holder_tool.wall_coefficients(beads)
        k_pair = self.contact.normal_stiffness_n_per_m(beads)
        k_stack = 1.0 / (2.0 / wall["kn"] + 1.0 / k_pair)
        mass = min(b.mass_kg for b in beads)
        hx, hy = geometry.half_size_m
        area = 4 * hx * hy - math.pi * geometry.holder_radius_m**2
        crossings = max(1.0, geometry.share * area / geometry.spacing_m**2)
        contacts = 2.0 * crossings
        stiffness = contacts * k_stack
        damping = contacts * wall["gamman"] * mass
        force = self.holder_share_n(geometry)
        dt = self.time_step_s(model)
        limit = min(0.1 / (stiffness * dt), 0.25 / damping)
        gain = self.holder_gain_m_s_n or limit
        # integral action removes the offset a proportional control keeps while the fabric
        # under the holder thickens or thins; its time is 20 closed-loop response times
        response = (1.0 / gain + damping) / stiffness
        integral_time = max(20.0 * response, 200.0 * dt)
        return {"gain_m_s_n": gain, "smooth_limit_m_s_n": limit,
                "integral_time_s": integral_time, "response_time_s": response,
                "above_smooth_limit": gain > limit, "approach_speed_m_s": gain * force,
                "estimated_stiffness_n_m": stiffness, "estimated_damping_n_s_m": damping,
                "crossings_under_holder": crossings}

    # -- input ----------------------------------------------------------------------------
    def symmetry_fixes(self, g: DrapeGeometry) -> str:
        if not g.quarter:
            return "# full model: no symmetry planes"
        lines = ["# symmetry planes x = 0 and y = 0: the fibre ends cut there keep their normal",
                 "# coordinate (no force, no velocity in that direction; fix nve never moves it)"]
        for name, ids, comps in (("sym_x", g.sym_x, "0.0 NULL NULL"),
                                 ("sym_y", g.sym_y, "NULL 0.0 NULL")):
            if not ids:
                lines.append(f"# no fibre ends on the {name[-1]} = 0 plane")
                continue
            words = [str(i + 1) for i in ids]
            rows = [" ".join(words[k:k + 16]) for k in range(0, len(words), 16)]
            lines.append(f"group           {name} id " + " &\n    ".join(rows))
            lines.append(f"velocity        {name} set {comps}")
            lines.append(f"fix             {name} {name} setforce {comps}")
        return "\n".join(lines)

    def reach(self, g: DrapeGeometry) -> dict[str, float]:
        """Radii of the punch, die and die-wall contact zones [m]; without ``tool_zones``
        every bead gets punch, die and die-wall contact (the holder's zone stays: it also
        defines the beads whose force is the holder force)."""
        if self.tool_zones:
            return {"punch_reach": g.punch_reach_m, "die_reach": g.die_reach_m,
                    "flange_reach": g.flange_reach_m}
        return {"punch_reach": g.face_radius_m, "die_reach": 1e-3 * g.diameter_m,
                "flange_reach": g.face_radius_m}

    def input_text(self, model: BeadModel) -> str:
        g = self._geometry_of(model)
        dt = self.time_step_s(model)
        load = self.loading(model)
        beads = model_bead_parameters(model)
        steps = self.steps(model)
        control = self.holder_control(model, g)
        zones = {"punch": ("punch", "punch_zone"), "die": ("die", "die_zone"),
                 "die_wall": ("die_wall", "die_wall_zone"), "holder": ("holder", "holder_zone")}
        walls = "\n".join(blocks.tool_region(self.holder_tool if tool == "holder" else self.tool,
                                             beads, region, tool, group=group)
                          for tool, (region, group) in zones.items())
        text = render(
            "drape", symmetry=self.symmetry, radius=g.radius_m, punch_z=g.punch_z_m,
            z_die=g.z_die_m, die_radius=g.die_radius_m, holder_radius=g.holder_radius_m,
            die_wall_gap=0.5 * g.diameter_m,
            face_radius=g.face_radius_m, z_face_top=g.z_die_m + 1e-6 * g.face_radius_m,
            wall_lo=g.z_die_m - 2 * g.radius_m, wall_hi=g.z_die_m - 0.5 * g.diameter_m,
            holder_force=self.holder_share_n(g), z_holder=g.z_holder_m, walls=walls,
            **self.reach(g),
            holder_gain=control["gain_m_s_n"], symmetry_fixes=self.symmetry_fixes(g),
            holder_ki=1.0 / control["integral_time_s"],
            guards=blocks.guards(model, dt),
            overlap=blocks.overlap_monitor(model, self.contact, beads, every=OVERLAP_EVERY,
                                           tool_fixes=TOOLS, file=CLAMP_OVERLAP_FILE),
            overlap_every=OVERLAP_EVERY,
            clamp_every=max(1, self.clamp.check_every // 5),
            holder_integral_time=control["integral_time_s"],
            **self.clamp_values(model, g),
            displacement=load.lammps_displacement(), velocity=load.lammps_velocity(),
            gamma=self.gamma(model), sample_every=SAMPLE_EVERY,
            samples_per_interval=self.every(model) // SAMPLE_EVERY, every=self.every(model),
            strain_energy="ebond+eangle" if len(model.angles) else "ebond",
            thermo_every=max(self.every(model), steps // 20))
        # the drape's guards sit in its template (before the clamping phase)
        return self.scene_text(model, dt, text, after=(
            self.trajectory.commands(steps), render("run", steps=steps),
            self.trajectory.final_commands(), render("finish", final_data="final.data")))

    # -- run ------------------------------------------------------------------------------
    def run(self, model: BeadModel, out: Path | None = None, engine: Engine | None = None,
            overwrite: bool = False, check_rate: bool = False, resume: bool = False,
            monitor: ContactPower | None = None) -> DrivenResult:
        """Drape ``model`` (a flat blank, warp along x); see :class:`DrivenTest.run`.

        Writes the trajectory (``trajectory.h5`` + ParaView files) after the run; after a
        failure, the frames written so far.
        """
        try:
            result = super().run(model, out=out, engine=engine, overwrite=overwrite,
                                 check_rate=check_rate, resume=resume, monitor=monitor)
        except SimulationFailed:
            if out is not None and (Path(out) / DATA_FILE).exists():
                salvage(Path(out), paraview=self.trajectory.paraview)
            raise
        path = finalise(result.run_dir, paraview=self.trajectory.paraview)
        result.summary["trajectory"] = path.name if path else None
        if mpi.is_root():
            write_json(Path(result.run_dir) / "summary.json", result.summary)
        return result

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        return reduce(run_dir, model, self, monitor)


# -- analysis of the draped state ---------------------------------------------------------
def shear_grid(g: DrapeGeometry, cell: float) -> tuple[np.ndarray, np.ndarray]:
    """Cell edges anchored on the symmetry lines, covering the model's blank."""
    from ..analysis.surface import grid_edges

    hx, hy = g.half_size_m
    pad = 0.5 * g.spacing_m
    lo_x, lo_y = (0.0, 0.0) if g.quarter else (-hx - pad, -hy - pad)
    return (grid_edges(lo_x, hx + pad, cell), grid_edges(lo_y, hy + pad, cell))


def wrinkling(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry,
              travel: float) -> dict:
    """Out-of-surface deviation of the beads over the punch cap (where a taut fabric lies on
    the punch): distance to the sphere minus half the fabric thickness."""
    centre = np.array([0.0, 0.0, g.punch_z_m - travel])
    rel = final - centre
    dist = np.linalg.norm(rel, axis=1)
    polar = np.arccos(np.clip(-rel[:, 2] / np.maximum(dist, 1e-300), -1, 1))
    zone = polar < 0.9 * g.contact_angle_rad
    dev = dist - g.radius_m - 0.5 * g.thickness_m
    out = {"zone": "beads over the punch cap within 0.9 x the contact angle",
           "contact_angle_deg": math.degrees(g.contact_angle_rad),
           "beads": int(zone.sum()), "fabric_thickness_m": g.thickness_m,
           "lying_band_m": 0.5 * (g.thickness_m - g.diameter_m),
           "note": "deviation = distance to the punch sphere - R - t/2; a fabric lying on "
                   "the punch has |deviation| <= (t - d)/2 (its bead layers, lying_band_m); "
                   "wrinkle_height_m: how far the largest deviation exceeds that band"}
    if zone.any():
        out.update(max_deviation_m=float(dev[zone].max()),
                   rms_deviation_m=float(np.sqrt(np.mean(dev[zone] ** 2))),
                   min_deviation_m=float(dev[zone].min()),
                   wrinkle_height_m=max(0.0, float(dev[zone].max()) - out["lying_band_m"]))
    else:
        out.update(max_deviation_m=None, rms_deviation_m=None, min_deviation_m=None,
                   wrinkle_height_m=None)
    return out


def draw_in(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry) -> dict:
    """In-plane displacement of the blank's edge towards the centre [m] along warp (x),
    weft (y) and the diagonal; mean over the edge beads within a yarn spacing of where each
    direction meets the edge (symmetric directions averaged in the full model)."""
    hx, hy = g.half_size_m
    s = g.spacing_m
    x, y = reference[:, 0], reference[:, 1]
    u = final[:, :2] - reference[:, :2]
    signs = [(1, 1)] if g.quarter else [(1, 1), (-1, 1), (1, -1), (-1, -1)]
    result = {}
    for name in ("warp", "weft", "diagonal"):
        values = []
        for sx, sy in signs:
            if name == "warp":
                sel = (sx * x > hx - s) & (np.abs(y) < s) & (sy * y >= 0)
                e = np.array([sx, 0.0])
            elif name == "weft":
                sel = (sy * y > hy - s) & (np.abs(x) < s) & (sx * x >= 0)
                e = np.array([0.0, sy])
            else:
                sel = (sx * x > hx - s) & (sy * y > hy - s)
                e = np.array([sx, sy]) / math.sqrt(2)
            if sel.any():
                values.append(float(-(u[sel] @ e).mean()))
        result[f"{name}_m"] = float(np.mean(values)) if values else None
    result["note"] = ("in-plane displacement of the edge beads towards the centre, within a "
                      "yarn spacing of the edge point along x (warp), y (weft) and the corner "
                      "(diagonal)")
    result["blank_shear_deg"] = None if g.quarter else blank_shear_deg(reference, final, g)
    return result


def blank_shear_deg(reference: np.ndarray, final: np.ndarray, g: DrapeGeometry) -> float:
    """Engineering shear of the whole blank in its plane, from its edges [deg]:
    mean(sign(x)·u_y)/hx over the two edges across x plus mean(sign(y)·u_x)/hy over the two
    across y (corners left out). A rigid turn and a pure draw-in give 0. Zero by
    construction in the quarter model, whose mirror planes forbid it; non-zero in the full
    model, it is a mode the quarter model cannot show."""
    hx, hy = g.half_size_m
    s = g.spacing_m
    x, y = reference[:, 0], reference[:, 1]
    u = final[:, :2] - reference[:, :2]
    across_x = (np.abs(x) > hx - s) & (np.abs(y) < hy - s)
    across_y = (np.abs(y) > hy - s) & (np.abs(x) < hx - s)
    shear = (np.mean(np.sign(x[across_x]) * u[across_x, 1]) / hx
             + np.mean(np.sign(y[across_y]) * u[across_y, 0]) / hy)
    return float(np.degrees(shear))


def merged_overlap(run_dir: Path, contact: ContactModel) -> dict:
    """Largest overlaps of the clamping phase and of the draw together (each has its log:
    the step count restarts in between)."""
    draw = overlap_summary(run_dir, contact, warn=False)
    clamp = overlap_summary(run_dir, contact, file=CLAMP_OVERLAP_FILE, warn=False)
    if not draw or not clamp:
        return draw or clamp
    out = dict(draw)
    for key in ("max_overlap_ratio", "max_pair_overlap_ratio", "max_tool_overlap_ratio"):
        out[key] = max(draw[key], clamp[key])
    out["overlap_samples"] = draw["overlap_samples"] + clamp["overlap_samples"]
    out["warnings"] = [f"clamping: {w}" for w in clamp["warnings"]] + draw["warnings"]
    out["max_overlap_ratio_clamping"] = clamp["max_overlap_ratio"]
    if out["warnings"] and mpi.is_root():
        import warnings

        from ..errors import OverlapWarning

        warnings.warn(out["warnings"][0], OverlapWarning, stacklevel=2)
    return out


def clamp_steps(run_dir: Path) -> int | None:
    """Steps the clamping phase took (from ``clamp.dat``)."""
    path = Path(run_dir) / "clamp.dat"
    if not path.exists():
        return None
    steps = read_print_file(path)["step"]
    return int(steps[-1]) if len(steps) else 0


def reduce(run_dir: Path, model: BeadModel, test: Drape,
           monitor: ContactPower | None = None) -> DrivenResult:
    """Force curves, holder-force control, shear angles, wrinkling, draw-in, final shape."""
    run_dir = Path(run_dir)
    g = test._geometry_of(model)
    scale = 1.0 / g.share
    dt = test.time_step_s(model)
    out = read_outputs(run_dir, test.every(model), dt, monitor)
    travel = out["punch_travel_m"]
    depth = np.maximum(travel - g.gap_m, 0.0)
    punch = out["punch_force_n"] * scale
    holder = out["holder_force_n"] * scale
    tool_j = np.cumsum(out.means["tool_contact_power_w"] * test.every(model) * dt)
    tool_j = np.interp(out["step"], out.means["step"], tool_j, left=0.0)
    curve = {"time_s": out["time_s"], "punch_travel_m": travel, "depth_m": depth,
             "punch_force_n": punch, "holder_force_n": holder,
             "die_force_n": out["die_force_n"] * scale,
             "holder_displacement_m": out["holder_displacement_m"],
             "kinetic_energy_j": out["kinetic_j"] * scale,
             "strain_energy_j": out["strain_energy_j"] * scale,
             "external_work_j": out.external_work_j * scale,
             "damping_dissipation_j": out.damping_j * scale,
             "tool_contact_work_j": tool_j * scale}
    if out.contact_j is not None:
        curve["contact_work_j"] = out.contact_j * scale
    # inertia: the rate of change of the fabric's downward momentum is the part of the tool
    # forces that accelerates it rather than deforms it
    momentum = -out["momentum_z_kg_m_s"] * scale
    inertial = np.gradient(momentum, out["time_s"]) if len(momentum) > 2 else 0 * momentum
    curve["momentum_z_kg_m_s"] = -momentum
    curve["inertial_force_n"] = inertial
    load = test.loading(model)
    started = started_mask(out, load, travel / test.travel_m(model))
    # holder force: interval means over the draw (after the clamping phase)
    set_force = test.holder_force_n
    means = out.means
    after = means["step"] > 0
    hmean = means["holder_force_n"][after] * scale
    herr = (hmean - set_force) / set_force
    clamp = read_print_file(run_dir / "clamp.dat") if (run_dir / "clamp.dat").exists() else {}
    holder_summary = {
        "set_force_n": set_force,
        "mean_force_n": float(hmean.mean()) if hmean.size else None,
        "max_relative_error": float(np.abs(herr).max()) if herr.size else None,
        "rms_relative_error": float(np.sqrt(np.mean(herr**2))) if herr.size else None,
        "max_force_n": float(hmean.max()) if hmean.size else None,
        "min_force_n": float(hmean.min()) if hmean.size else None,
        "holder_travel_m": float(np.ptp(out["holder_displacement_m"])),
        "clamp_end_force_n": float(clamp["holder_force_n"][-1] * scale) if clamp else None,
        "control": test.holder_control(model, g),
        "note": "interval means over the draw (after the clamping phase), for the whole "
                "blank; error = (F - F_set)/F_set",
    }
    # energy balance: external work = dU + dKE + damping + fibre contact work + tool contacts
    w = float(out.external_work_j[-1])
    terms = {"external_work_j": w * scale,
             "strain_energy_change_j": float(out["strain_energy_j"][-1]
                                             - out["strain_energy_j"][0]) * scale,
             "kinetic_energy_change_j": float(out["kinetic_j"][-1] - out["kinetic_j"][0])
             * scale,
             "damping_dissipation_j": float(out.damping_j[-1]) * scale,
             "tool_contact_work_j": float(tool_j[-1]) * scale,
             "contact_work_j": None if out.contact_j is None else float(out.contact_j[-1])
             * scale}
    accounted = sum(v for k, v in terms.items() if k != "external_work_j" and v is not None)
    terms["relative_error"] = (abs(terms["external_work_j"] - accounted)
                               / abs(terms["external_work_j"])
                               if terms["external_work_j"] and out.contact_j is not None
                               else None)
    terms["note"] = ("tool contact work (friction, damping and springs of punch, die and "
                     "holder contacts) is measured every step; fibre-fibre contact work is "
                     "sampled by the in-process engine (None otherwise, then no closing error)")
    # final state
    final = BeadModel.load(run_dir / "final.data", run_dir / "model.json")
    ref = model.positions
    cur = final.positions
    from ..analysis.surface import surface_shear_angle_field

    cell = test.shear_cell_m or 2.0 * g.spacing_m
    xe, ye = shear_grid(g, cell)
    fld = surface_shear_angle_field(ref, cur, model.fibre_ids, model.families, xe, ye)
    # the largest shear angle over the cells clear of the blank's edges by a yarn spacing (at
    # a cut edge the free fibre ends turn without shearing the fabric)
    hx, hy = g.half_size_m
    xc, yc = np.meshgrid(fld.x_centres_m, fld.y_centres_m)
    interior = ((np.abs(xc) + 0.5 * cell <= hx - 0.5 * g.spacing_m)
                & (np.abs(yc) + 0.5 * cell <= hy - 0.5 * g.spacing_m))
    finite = np.isfinite(fld.values)
    inside = finite & interior
    absg = np.abs(fld.values[inside])
    where = np.where(inside, np.abs(np.nan_to_num(fld.values)), -1.0)
    jmax, imax = np.unravel_index(np.argmax(where), fld.values.shape)
    shear = {"cell_m": cell, "cells": int(inside.sum()),
             "max_abs_deg": float(absg.max()) if absg.size else None,
             "p95_abs_deg": float(np.percentile(absg, 95)) if absg.size else None,
             "max_at_m": [float(fld.x_centres_m[imax]), float(fld.y_centres_m[jmax])],
             "max_abs_all_cells_deg": float(np.abs(fld.values[finite]).max())
             if finite.any() else None,
             "method": "angle between the summed warp and weft bead tangents (3D) per cell of "
                       "a grid over the initial in-plane positions, gamma = 90 - angle; the "
                       "largest value over the cells clear of the blank's edges by a yarn "
                       "spacing (max_abs_all_cells_deg: all cells)"}
    wrinkle = wrinkling(ref, cur, g, float(travel[-1]))
    drawin = draw_in(ref, cur, g)
    dist = np.linalg.norm(cur - np.array([0.0, 0.0, g.punch_z_m - float(travel[-1])]), axis=1)
    touching = dist < g.radius_m + 0.75 * float(model.diameters.max())
    r0 = np.hypot(ref[:, 0], ref[:, 1])
    reach = {"punch_zone_radius_m": g.punch_reach_m,
             "furthest_touching_start_radius_m": float(r0[touching].max())
             if touching.any() else None}
    ke = kinetic_to_work_ratio(out, started)
    loaded = started & (punch > 0.1 * punch.max()) if punch.max() > 0 else started
    duration = float(out["time_s"][-1] - out["time_s"][0])
    inertia = {
        "mean_inertial_force_n": float((momentum[-1] - momentum[0]) / duration)
        if duration > 0 else None,
        "mean_punch_force_n": float(out.external_work_j[-1] * scale / max(depth[-1], 1e-300)),
        "max_inertial_to_punch_force": float(np.max(np.abs(inertial[loaded])
                                                    / punch[loaded])) if loaded.any() else None,
        "note": "inertial force = rate of change of the fabric's downward momentum (the part "
                "of the tool forces that accelerates the fabric); mean over the draw, and its "
                "largest ratio to the punch force where that exceeds a tenth of its maximum "
                "after the start-up. The kinetic energy is mostly the fabric moving with the "
                "punch, so KE/W overstates the dynamic part where the punch force is small"}
    rest = np.array([bt.rest_length_m for bt in model.bond_type_table])[model.bond_types - 1]
    strain = (final.bond_lengths() / rest - 1.0)[model.fibre_bond_mask()]
    ratio = (inertia["mean_inertial_force_n"] / inertia["mean_punch_force_n"]
             if inertia["mean_inertial_force_n"] is not None and inertia["mean_punch_force_n"]
             else None)
    reach = test.reach(g)
    summary = {
        "protocol": PROTOCOL,
        "symmetry": test.symmetry,
        "n_beads": model.n_beads,
        "n_beads_in_tool_zones": {
            "punch": int((r0 <= reach["punch_reach"]).sum()),
            "die": int((r0 >= reach["die_reach"]).sum()),
            "die_wall": int(((r0 >= reach["die_reach"])
                             & (r0 <= reach["flange_reach"])).sum()),
            "holder": int((r0 > g.holder_radius_m).sum())},
        "symmetry_held_beads": {"x": len(g.sym_x), "y": len(g.sym_y)},
        "punch_radius_m": g.radius_m,
        "die_opening_radius_m": g.die_radius_m,
        "holder_inner_radius_m": g.holder_radius_m,
        "depth_m": test.depth_m,
        "blank_size_m": [2 * g.half_size_m[0], 2 * g.half_size_m[1]],
        "fabric_thickness_m": g.thickness_m,
        "yarn_spacing_m": g.spacing_m,
        "modulus_scale": test.modulus_scale,
        "max_bond_strain": float(strain.max()),
        "tool_friction": test.tool.friction,
        "fibre_friction": test.contact.friction,
        "time_step_s": dt,
        "steps": test.steps(model),
        "clamp_steps": clamp_steps(run_dir),
        "punch_speed_m_s": load.speed_m_s,
        "max_punch_force_n": float(punch.max()),
        "final_punch_force_n": float(punch[depth >= 0.95 * depth[-1]].mean()),
        "final_punch_force_note": "mean over the last 5 % of the depth",
        "punch_force_at_depth_n": {f"{k:g}": v for k, v in values_at(
            depth, punch, test.report_depths_m).items()},
        "holder_force": holder_summary,
        "max_shear_angle_deg": shear["max_abs_deg"],
        "shear_angle": shear,
        "wrinkling": wrinkle,
        "draw_in": drawin,
        "punch_reach": reach,
        "max_kinetic_to_external_work": ke,
        "inertia": inertia,
        "mean_inertial_to_punch_force": ratio,
        "quasi_static_note": "kinetic energy of the fabric over the work done so far, after "
                             "the smooth start and the first tenth of the travel",
        "energy_balance": terms,
        "forces_note": "forces and energies are for the whole blank (the quarter model's x 4)"
                       if g.quarter else "forces and energies of the whole blank",
    }
    summary.update(merged_overlap(run_dir, test.contact))
    write_final(run_dir, model, final, fld, g, test, wrinkle, travel[-1])
    notes = (f"R = {1e3 * g.radius_m:g} mm, depth {1e3 * test.depth_m:g} mm, {test.symmetry}"
             f"\nholder {set_force:g} N, mu tool {test.tool.friction:g}"
             f"\nmean inertial / punch force {'-' if ratio is None else f'{ratio:.2g}'}"
             f"\n{model.n_beads} beads")
    plots = [
        {"path": "curve.png", "series": [{"x": 1e3 * depth, "y": punch, "label": "punch"}],
         "xlabel": "depth [mm]", "ylabel": "punch force [N]",
         "title": "Hemispherical punch drape", "notes": notes},
        {"path": "holder_force.png",
         "series": [{"x": 1e3 * depth, "y": holder, "label": "blank holder"},
                    {"x": [0.0, 1e3 * float(depth[-1])], "y": [set_force, set_force],
                     "style": "--", "label": "set force", "lw": 1.0}],
         "xlabel": "depth [mm]", "ylabel": "blank-holder force [N]",
         "title": "Blank-holder force (force control)",
         "notes": f"max error after clamping {holder_summary['max_relative_error']:.3g}"
         if holder_summary["max_relative_error"] is not None else ""},
    ]
    return DrivenResult(run_dir, curve, summary, plots)


def write_final(run_dir: Path, model: BeadModel, final: BeadModel, fld, g: DrapeGeometry,
                test: Drape, wrinkle: dict, travel: float) -> None:
    """Shear-angle data and map, the final shape (VTU + PNG); rank 0."""
    if not mpi.is_root():
        return
    import meshio

    from ..results.vtu import _legend, _open_bonds, _write

    xc, yc = np.meshgrid(fld.x_centres_m, fld.y_centres_m)
    write_csv(run_dir / "shear_angle.csv", {
        "x_m": xc.ravel(), "y_m": yc.ravel(), "shear_angle_deg": fld.values.ravel(),
        "warp_beads": fld.extra["warp_beads"].ravel(),
        "weft_beads": fld.extra["weft_beads"].ravel()})
    np.savez_compressed(run_dir / "shear_angle.npz", x_edges_m=fld.x_edges_m,
                        y_edges_m=fld.y_edges_m, shear_angle_deg=fld.values,
                        bead_shear_angle_deg=fld.extra["bead_shear_deg"],
                        reference_positions_m=model.positions, final_positions_m=final.positions)
    plot_field(run_dir / "shear_angle.png", fld.x_edges_m, fld.y_edges_m, fld.values,
               "shear angle γ [°]", symmetric=True, aspect="equal",
               xlabel="x (warp), initial", ylabel="y (weft), initial",
               title=f"Shear angle after {1e3 * test.depth_m:g} mm "
                     f"({'quarter' if g.quarter else 'full'} model)")
    # final shape: fibres with point data
    centre = np.array([0.0, 0.0, g.punch_z_m - travel])
    dev = np.linalg.norm(final.positions - centre, axis=1) - g.radius_m - 0.5 * g.thickness_m
    keep = _open_bonds(final)
    bonds = final.bonds[keep]
    mesh = meshio.Mesh(
        points=final.positions, cells=[("line", bonds.astype(np.int64))],
        point_data={"diameter_m": final.diameters, "family": final.atom_types.astype(np.int32),
                    "yarn_id": final.yarn_ids.astype(np.int32),
                    "displacement_m": final.positions - model.positions,
                    "shear_angle_deg": fld.extra["bead_shear_deg"],
                    "punch_distance_m": dev},
        cell_data={"fibre_id": [final.fibre_ids[bonds[:, 0]].astype(np.int32)]})
    _write(run_dir / "final.vtu", mesh, _legend(final))
    shape_png(run_dir / "shape.png", model, final, g, travel)


def shape_png(path: Path, model: BeadModel, final: BeadModel, g: DrapeGeometry,
              travel: float) -> None:
    """Top view of the draped blank coloured by height, and a section along the warp."""
    from ..results.plots import _pyplot

    plt = _pyplot()
    p0, p = model.positions, final.positions
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.8), layout="constrained")
    sc = ax.scatter(1e3 * p[:, 0], 1e3 * p[:, 1], c=1e3 * (p[:, 2] - p0[:, 2]), s=1.0,
                    cmap="viridis")
    fig.colorbar(sc, ax=ax, label="vertical displacement [mm]")
    hx, hy = g.half_size_m
    xs = [0, hx, hx, 0] if g.quarter else [-hx, hx, hx, -hx, -hx]
    ys = [hy, hy, 0, 0] if g.quarter else [-hy, -hy, hy, hy, -hy]
    ax.plot(1e3 * np.asarray(xs), 1e3 * np.asarray(ys), "k--", lw=0.8, label="blank before")
    t = np.linspace(0, np.pi / 2 if g.quarter else 2 * np.pi, 200)
    ax.plot(1e3 * g.die_radius_m * np.cos(t), 1e3 * g.die_radius_m * np.sin(t), "r-", lw=0.8,
            label="die opening")
    ax.set_aspect("equal")
    ax.set_xlabel("x (warp) [mm]")
    ax.set_ylabel("y (weft) [mm]")
    ax.set_title("Draped blank, top view", fontsize=10)
    band = np.abs(p0[:, 1]) < g.spacing_m
    bx.scatter(1e3 * p[band, 0], 1e3 * p[band, 2], s=1.0, c="tab:blue", label="fabric")
    zc = g.punch_z_m - travel
    # the punch over the modelled part only (x >= 0 for a quarter model)
    t = np.linspace(-np.pi / 2 if g.quarter else -np.pi / 2 - 1.2, -np.pi / 2 + 1.2, 200)
    bx.plot(1e3 * g.radius_m * np.cos(t), 1e3 * (zc + g.radius_m * np.sin(t)), "k-", lw=1.0,
            label="punch")
    lo = 0.0 if g.quarter else -hx
    for side in ((lo, -g.die_radius_m), (g.die_radius_m, hx)) if not g.quarter else \
            ((g.die_radius_m, hx),):
        bx.plot(1e3 * np.asarray(side), [1e3 * g.z_die_m] * 2, "r-", lw=1.5,
                label="die" if side[1] == hx else None)
    bx.set_aspect("equal")
    bx.set_xlabel("x (warp) [mm]")
    bx.set_ylabel("z [mm]")
    bx.set_title("Section along the warp\n(beads starting within one spacing of y = 0)",
                 fontsize=10)
    # one legend below both panels: never on the fibres
    handles, labels = [], []
    for a in (ax, bx):
        h, lab = a.get_legend_handles_labels()
        handles += h
        labels += lab
    fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), frameon=False,
               fontsize=8, markerscale=4)
    fig.savefig(path, dpi=150)
    plt.close(fig)
