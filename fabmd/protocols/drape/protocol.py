"""The :class:`Drape` protocol: its parameters and their validation, loading and time, and
the blank holder's force control; the blank, the input text and the reduction are delegated to
:mod:`.geometry`, :mod:`.input` and :mod:`.reduce` (package docstring: what a drape does).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ... import inputs
from ...errors import InputError
from ...model.bead_model import BeadModel
from ...model.beads import model_bead_parameters
from ...model.contact import ToolContact
from ...scene.adaptive import AdaptiveLoading, adaptive_plan
from ...scene.energy import MEAN_SAMPLE_EVERY, ContactPower
from ...scene.plan import RunPlan
from ...scene.quasi_static import QuasiStatic
from ..driven import DrivenResult, DrivenTest
from .geometry import (
    DrapeGeometry,
    centre_blank,
    check_orientation,
    cut_blank,
    tool_geometry,
    tool_reach,
)
from .input import SAMPLE_EVERY
from .input import input_text as drape_input_text
from .reduce import reduce as reduce_run

PROTOCOL = "drape"
SYMMETRIES = ("quarter", "full")


@dataclass(frozen=True, kw_only=True)
class Drape(DrivenTest):
    """Hemispherical-punch draping of a flat blank (warp along x, weft along y).

    The ``contact``, ``time_step``, ``samples`` and ``trajectory`` fields are those of
    :class:`~fabmd.protocols.driven.DrivenTest`; the time step is bounded by the stiffer of
    fibre–fibre and tool contact (:meth:`plan_contacts`).

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
        speed_fraction: punch speed over the fibres' axial wave speed (> 0, <= 0.05).
        ramp_fraction: share of the draw spent reaching full punch speed smoothly.
        clamp: when the clamping phase (holder closing, punch waiting, fabric relaxing
            under local damping) is over: quasi-static criterion and its step limit.
        damping_time_s: τ of the viscous damping γ = m/τ [s] (default: the draw's duration).
        shear_cell_m: cell of the shear-angle grid [m]; default two yarn spacings (one
            plain-weave unit cell, so the crimp cancels).
        report_depths_m: depths at which punch forces are reported [m].
        modulus_scale: factor on the fibres' axial (and bending) stiffness for this test,
            in (0, 1]. Draping loads fibres far below their strength and stiffness (the
            summary reports the largest bond strain); a softer fibre takes a longer stable
            time step (∝ 1/sqrt(scale)), so the same punch speed needs fewer steps. Contact
            stiffness follows (it is a fraction of the fibres' E·A/l0).
        tool_zones: give each tool's contact only to the beads that can reach it
            (default True); False gives punch and die contact to every bead, which changes
            nothing but the cost (``benchmarks/drape.py`` measures both).
        loading_speed: adaptive punch speed (opt-in, :mod:`fabmd.scene.adaptive`); the
            punch's travel is then the integral of its speed, and its kinetic measure the
            fabric's inertial force over the punch force (:func:`.input.adaptive_motion`).
    """

    protocol = PROTOCOL
    rate_curve = ("depth_m", "punch_force_n")
    rate_keys = {"max_punch_force_change": "max_punch_force_n",
                 "max_shear_angle_change": "max_shear_angle_deg"}
    # the fabric riding on the punch makes KE/W large in a slow draw (see ``inertia``): the
    # drape judges the inertial share of the punch force instead
    quasi_static_limits = {"mean_inertial_to_punch_force": 0.05, "damping_share": 0.5,
                           "energy_balance_error": 0.05}

    speed_fraction: float = 5e-4
    ramp_fraction: float = 0.05
    punch_radius_m: float = 0.05
    depth_m: float = 0.04
    die_clearance_m: float = 0.003
    holder_force_n: float = 100.0
    holder_inner_radius_m: float | None = None
    holder_gain_m_s_n: float | None = None
    symmetry: str = "quarter"
    tool: ToolContact = field(default_factory=lambda: ToolContact(friction=0.2))
    holder_damping_ratio: float = 0.03
    clamp: QuasiStatic = field(default_factory=lambda: QuasiStatic(max_steps=20_000))
    shear_cell_m: float | None = None
    report_depths_m: tuple[float, ...] = ()
    modulus_scale: float = 1.0
    tool_zones: bool = True
    loading_speed: AdaptiveLoading = field(default_factory=AdaptiveLoading)

    def check_fields(self) -> None:
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
        self.check_positive_or_none("holder_gain_m_s_n", "shear_cell_m")
        inputs.one_of("drape.symmetry", self.symmetry, SYMMETRIES)
        if not isinstance(self.tool, ToolContact):
            raise InputError(f"drape.tool must be a ToolContact, got {self.tool!r}")
        inputs.in_range("drape.holder_damping_ratio", self.holder_damping_ratio, 0.0, 1.0,
                        low_open=True)
        if not isinstance(self.clamp, QuasiStatic):
            raise InputError(f"drape.clamp must be a QuasiStatic, got {self.clamp!r}")
        for d in self.report_depths_m:
            inputs.positive("drape.report_depths_m", d)
        inputs.in_range("drape.modulus_scale", self.modulus_scale, 0, 1, low_open=True)
        if not isinstance(self.loading_speed, AdaptiveLoading):
            raise InputError(f"drape.loading_speed must be an AdaptiveLoading, got "
                             f"{self.loading_speed!r}")
        self.loading_speed.check_speed("drape", self.speed_fraction)

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
        check_orientation(model)

    def centred(self, model: BeadModel) -> tuple[BeadModel, float]:
        """The blank centred between yarns, and the yarn spacing [m]
        (:func:`~.geometry.centre_blank`)."""
        return centre_blank(model)

    def blank(self, model: BeadModel) -> BeadModel:
        """The model to run (:func:`~.geometry.cut_blank`): the blank centred, its x > 0,
        y > 0 quarter for ``symmetry="quarter"``; checked against the tools."""
        return cut_blank(self, model)

    def prepare(self, model: BeadModel) -> BeadModel:
        return self.blank(model)

    def geometry(self, model: BeadModel) -> DrapeGeometry:
        """Tools and zones on a model from :meth:`prepare`."""
        if "drape" not in model.info:
            raise InputError("drape.geometry needs a model from Drape.prepare")
        return tool_geometry(self, model)

    def reach(self, g: DrapeGeometry) -> dict[str, float]:
        """Radii of the punch, die and die-wall contact zones [m]
        (:func:`~.geometry.tool_reach`, with ``tool_zones``)."""
        return tool_reach(g, self.tool_zones)

    # -- loading and time -------------------------------------------------------------------
    def travel_m(self, model: BeadModel) -> float:
        """The punch travels the depth plus the small gap it starts above the fabric."""
        return self.travel_from(0.1 * float(model.diameters.max()))

    def travel_from(self, gap_m: float) -> float:
        return self.depth_m + gap_m

    def plan_loading(self, plan: RunPlan, model: BeadModel) -> RunPlan:
        """Adaptive loading (:func:`fabmd.scene.adaptive.adaptive_plan`) when asked; the
        wave transit is the blank's larger side over the fibres' wave speed, the output
        interval a multiple of :data:`SAMPLE_EVERY` and of the controller's
        ``MEAN_SAMPLE_EVERY`` (the means' sampling: every step would double the cost)."""
        size = float(np.ptp(model.positions[:, :2], axis=0).max())
        return adaptive_plan(plan, self.loading_speed, self.travel_m(model),
                             size / self.wave_speed_m_s(model),
                             every_multiple=math.lcm(SAMPLE_EVERY, MEAN_SAMPLE_EVERY))

    def plan_contacts(self) -> tuple:
        """The time step is bounded by the stiffer of fibre–fibre and tool contact."""
        return (self.contact, self.tool)

    def plan_every(self, duration_s: float, dt: float) -> int:
        """Output interval: a multiple of the sampling interval of the means."""
        raw = math.ceil(duration_s / dt)
        return SAMPLE_EVERY * max(1, raw // self.samples // SAMPLE_EVERY)

    def plan_damping_time_s(self, duration_s: float) -> float:
        """τ of the viscous damping γ = m/τ [s]; default the whole draw (a light drag: the
        fabric moves with the punch, and drag on it adds to the punch force)."""
        return self.damping_time_s or duration_s

    @property
    def holder_tool(self) -> ToolContact:
        """The tool contact of the holder: the tools' with its own damping."""
        return dataclasses.replace(self.tool, damping_ratio=self.holder_damping_ratio)

    def holder_share_n(self, geometry: DrapeGeometry) -> float:
        return self.holder_force_n * geometry.share

    def holder_control(self, model: BeadModel, geometry: DrapeGeometry,
                       dt: float | None = None) -> dict:
        """Force-control gain α [m/s/N], its integral time and what limits them, for the time
        step ``dt`` [s] (default: the plan's; ``reduce`` passes the one the run was planned
        with).

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
        dt = dt or self.time_step_s(model)
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

    # -- input and reduction --------------------------------------------------------------
    def input_text(self, model: BeadModel) -> str:
        """The LAMMPS input on a blank from :meth:`prepare` (:func:`~.input.input_text`)."""
        return drape_input_text(self, model)

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        """Curves, summary and the draped shape's files (:func:`~.reduce.reduce`)."""
        return reduce_run(run_dir, model, self, monitor)
