"""Periodic unit cell tests: tension and trellis (pure) shear by box deformation.

A fabric cell periodic in x and y (e.g. ``Crimp().run(plain_weave_cell()).model``)
is loaded by deforming its box (``fix deform``, ``remap v``): no clamps and no
edges. The beads are not remapped; the box drags them through the fibres and
contacts that cross its faces, and every relative motion the contacts see is a
real one (with ``remap x`` the tangential springs would miss the affine slip).

* :class:`PeriodicTension` stretches the box along x (warp); the transverse size
  is held (default) or left free (``transverse="free"``: ``fix press/berendsen``
  drives the transverse membrane force to zero).
* :class:`PeriodicShear` is the picture frame of an infinite fabric: both fibre
  families keep their length — the cell edge along x stays, the other edge
  (length b) turns by γ (ly = b·cos γ, xy = b·sin γ) — so the shear angle between
  the families is γ.

Membrane forces per unit length come from the virial, N = −P·V/(lx·ly) = −P·lz,
so the arbitrary z size of the box cancels. The power of the box deformation,
−V·P:L + Σ F_i·(L·x_i) (L = ḣ·h⁻¹), is integrated exactly per output interval for
the energy balance; for the shear cell it gives the same normalised shear force
as the picture frame, F_norm = ΔW/(A0·Δ sin γ) (power per initial area over cos γ·γ̇).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import numpy as np

from .. import inputs
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..model.timestep import berendsen_modulus_pa
from ..results.curves import bilinear_fit, locking_angle, tangent_intersection, values_at
from ..results.figure import report_marks
from ..scene.drag import AffineField, affine_force_names
from ..scene.energy import ContactPower
from ..scene.outputs import TrajectoryOutput
from ..scene.plan import RunPlan
from ..scene.templates import fmt, render, render_inline
from .driven import DrivenResult, RelaxedDrivenTest
from .driven_outputs import energy_columns, read_outputs
from .picture_frame import interval_force
from .verdict import mark_fitted_stiffness

TRANSVERSE = ("held", "free")


def check_periodic_cell(model: BeadModel, who: str) -> None:
    if not (model.periodic[0] and model.periodic[1]):
        raise InputError(f"{who} needs a cell periodic in x and y (a unit cell, e.g. from "
                         f"Crimp().run(...) on a periodic fabric), got periodic = "
                         f"{tuple(model.periodic)}; use the coupon tests for finite pieces")


@dataclass(frozen=True, kw_only=True)
class _PeriodicCellTest(RelaxedDrivenTest):
    """Box-deformation test of a periodic cell (shared machinery): the loading, contact,
    output and ``relax`` fields of :class:`~fabmd.protocols.driven.RelaxedDrivenTest`,
    ``speed_fraction`` that of the moving box face, fewer curve points and frames; the
    ``drag`` (default ``"affine"``) acts relative to the box's affine velocity field."""

    samples: int = 100
    trajectory: TrajectoryOutput = field(default_factory=lambda: TrajectoryOutput(frames=10))

    title: ClassVar[str] = ""

    def cell(self, model: BeadModel) -> tuple[float, float, float]:
        """(lx, ly, lz) of the box [m]."""
        size = model.box_hi - model.box_lo
        return float(size[0]), float(size[1]), float(size[2])

    def prepare(self, model: BeadModel) -> BeadModel:
        check_periodic_cell(model, self.protocol)
        return model

    def box_motion(self, model: BeadModel) -> str:
        raise NotImplementedError

    def transverse_block(self, model: BeadModel) -> str:
        return "# transverse size held"

    affine_start_supported = True

    #: the entries of the box's velocity gradient L = ḣ·h⁻¹ that the test moves (LAMMPS
    #: variables of ``periodic_cell.lmp``)
    box_gradient: ClassVar[dict[str, str]] = {}

    def affine_field(self, model: BeadModel) -> AffineField:
        """The box's affine velocity field, L·(r − r0), r0 the beads' mean position at the
        start (the fabric's centre of mass does not move, so the field leaves it at rest)."""
        centre = model.positions[:, :2].mean(axis=0)
        return AffineField(origin_m=(float(centre[0]), float(centre[1])), tools="box faces",
                           **self.box_gradient)

    def input_text(self, model: BeadModel) -> str:
        check_periodic_cell(model, self.protocol)
        dt = self.time_step_s(model)
        ea = max(bt.bond_axial_stiffness_n for bt in model.bond_type_table)
        field = self.affine_field(model)
        damping, damping_power = self.drag_block(model, field)
        # the affine drag's +γ·v_affine (an addforce) is in f too: the box power takes it out
        affine = self.drag == "affine"
        refs = {a: f"-{name}" if affine and name else ""
                for a, name in affine_force_names(field).items()}
        outputs = self.outputs_block(
            model, "# power of the box deformation: v_p_box (above)", "v_p_box",
            mean_values="v_nxx v_nyy v_nxy",
            mean_names="n_xx_n_m n_yy_n_m n_xy_n_m",
            print_values="${s} $(lx:%.12g) $(ly:%.12g) $(xy:%.12g)",
            print_names="boundary_travel_m box_lx_m box_ly_m box_xy_m",
            thermo_values="v_s lx ly xy v_nxx v_nyy v_nxy", damping_power=damping_power,
            affine=field if affine else None)
        text = render("periodic_cell", title=self.title,
                      relax=self.relax_block(model, "clamps", "free", 1e-3 * ea),
                      box_motion=self.box_motion(model), damping=damping,
                      transverse=self.transverse_block(model), gamma=self.gamma(model),
                      drag_fx=refs["x"], drag_fy=refs["y"], outputs=outputs,
                      # the box's gradient variables read the box when LAMMPS gets there:
                      # after the release, if any
                      start=self.start_block(field))
        return self.scene_text(model, dt, text)

    def _schedule(self, model: BeadModel) -> dict[str, str]:
        """Boundary travel s(t) [m] and its rate [m/s] as LAMMPS expressions."""
        load = self.loading(model)
        return {"displacement": load.lammps_displacement(), "velocity": load.lammps_velocity()}

    def _common_summary(self, model: BeadModel, out, progress, plan: RunPlan) -> dict:
        lx, ly, lz = self.cell(model)
        return {
            "protocol": self.protocol,
            "n_beads": model.n_beads,
            "cell_m": [lx, ly],
            "time_step_s": plan.time_step_s,
            "steps": plan.steps,
            "boundary_speed_m_s": plan.loading.speed_m_s,
            "start": self.start_kind(),
            **self.quasi_static_evidence(out, model, progress),
        }


@dataclass(frozen=True, kw_only=True)
class PeriodicTension(_PeriodicCellTest):
    """Uniaxial tension of a periodic cell along x by box deformation.

    Args:
        max_strain_pct: box strain along x at the end [%], (0, 50].
        transverse: ``"held"`` (ly fixed) or ``"free"`` (zero transverse membrane force,
            ``fix press/berendsen`` on y; its box work is not in the energy balance).
        transverse_damping_fraction: Berendsen time constant over the test duration.
        report_strains_pct: strains at which N_xx is reported.
    """

    protocol = "periodic_tension"
    box_gradient = {"xx": "v_lg_xx"}
    title = "uniaxial tension along x"
    rate_curve = ("strain_pct", "force_per_width_n_m")
    interval_axis = ("strain_pct", 0.25)
    rate_keys = {"initial_stiffness_change": "initial_stiffness_n_m_per_width"}

    max_strain_pct: float = 2.0
    transverse: str = "held"
    transverse_damping_fraction: float = 0.1
    report_strains_pct: tuple[float, ...] = (0.5, 1.0)
    speed_fraction: float = 2e-4

    def check_fields(self) -> None:
        inputs.in_range("periodic_tension.max_strain_pct", self.max_strain_pct, 0, 50,
                        low_open=True)
        inputs.one_of("periodic_tension.transverse", self.transverse, TRANSVERSE)
        inputs.in_range("periodic_tension.transverse_damping_fraction",
                        self.transverse_damping_fraction, 0, 1, low_open=True)

    def travel_m(self, model: BeadModel) -> float:
        return self.cell(model)[0] * self.max_strain_pct / 100

    def box_motion(self, model: BeadModel) -> str:
        return render_inline("periodic_tension_box", **self._schedule(model))

    def transverse_block(self, model: BeadModel) -> str:
        if self.transverse == "held":
            return "# transverse size held (ly fixed)"
        lx, ly, lz = self.cell(model)
        ea = max(bt.bond_axial_stiffness_n for bt in model.bond_type_table)
        n_fibres = max(model.n_fibres, 1)
        # Berendsen's modulus: a tenth of all fibres' E·A over the cell section (a
        # crimped fabric is far softer across than its fibres; a low guess relaxes faster
        # and stays stable while the time constant is many time steps)
        modulus = 0.1 * n_fibres * ea / (ly * lz)
        pdamp = self.transverse_damping_fraction * self.duration_s(model)
        settle = math.ceil(10 * pdamp / self.time_step_s(model))
        return render_inline("periodic_transverse_free", pdamp=pdamp, modulus=modulus,
                             settle_steps=settle)

    def after_verdict(self, result: DrivenResult) -> None:
        """The initial stiffness is the slope over 10-40 % of the strain range: marked where
        the verdict flags part of that range (as the tension's toe)."""
        mark_fitted_stiffness(result.summary, 0.1 * self.max_strain_pct,
                              0.4 * self.max_strain_pct, "%")

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        plan = self.read_plan(run_dir, model)  # what the run was written with
        out = read_outputs(run_dir, plan.every, plan.time_step_s, monitor)
        lx0, ly0, _ = self.cell(model)
        strain = (out["box_lx_m"] - lx0) / lx0
        nxx = out["n_xx_n_m"]
        curve = {"time_s": out["time_s"], "strain_pct": 100 * strain,
                 "force_per_width_n_m": nxx, "transverse_force_per_width_n_m": out["n_yy_n_m"],
                 "box_ly_m": out["box_ly_m"], **energy_columns(out)}
        fit = bilinear_fit(100 * strain, nxx)
        # tangents: 10-40 % of the strain range (past the smooth start) and the last 20 %
        tangents = tangent_intersection(strain, nxx, initial=(0.1, 0.4), final=0.2)
        summary = self._common_summary(model, out, strain / (self.max_strain_pct / 100),
                                       plan)
        summary.update({
            "transverse": self.transverse,
            "width_m": ly0,
            "initial_stiffness_n_m_per_width": tangents["initial_slope"],  # per unit strain
            "final_stiffness_n_m_per_width": tangents["final_slope"],
            "stiffness_note": "slopes of N_xx against strain fitted over 10-40 % and over the "
                              "last 20 % of the strain range",
            "bilinear_transition_strain_pct": fit["break_x"],
            "force_per_width_at_strain_n_m": {f"{k:g}": v for k, v in values_at(
                100 * strain, nxx, self.report_strains_pct).items()},
            "max_abs_transverse_force_per_width_n_m": float(np.abs(out["n_yy_n_m"]).max()),
            "transverse_strain_pct": float(100 * (out["box_ly_m"][-1] - ly0) / ly0),
        })
        if self.transverse == "free":
            summary["energy_balance"]["note"] = (
                "the work of the Berendsen barostat on the box y size is not counted "
                "(it drives the transverse force to zero)")
        plot = {"path": "curve.png",
                "series": [{"x": 100 * strain, "y": nxx, "label": "N_xx (virial)"}],
                "xlabel": "strain [%]", "ylabel": "membrane force per width [N/m]",
                "title": f"Periodic cell: tension (transverse {self.transverse})",
                "notes": f"cell {1e3 * lx0:.2f} x {1e3 * ly0:.2f} mm\n{model.n_beads:,} beads",
                "marks": report_marks(summary["force_per_width_at_strain_n_m"])}
        return DrivenResult(Path(run_dir), curve, summary, [plot])


@dataclass(frozen=True, kw_only=True)
class PeriodicShear(_PeriodicCellTest):
    """Trellis (pure) shear of a periodic cell: both fibre families keep their length.
    ``speed_fraction`` is that of the turning cell edge (b·γ̇); the trajectory stores the
    box tilt of the sheared cell too.

    The locking angle is read by the picture frame's stated method
    (:func:`fabmd.results.curves.locking_angle`: departure from the 10–20° line by a
    factor 2), so the two compare and neither depends on where the test stops.

    Args:
        max_shear_angle_deg: shear angle γ at the end [deg], (0, 70].
        report_angles_deg: shear angles at which forces are reported.
        locking_initial_deg: shear-angle range [deg] of the initial branch of the
            locking-angle method.
        locking_factor: the force over the initial line that marks the departure.
        release_tension: before the shear, let the cell's in-plane size follow zero
            membrane force (Berendsen on x and y, both fibre families free to shorten),
            as a coupon cut from the roll loses its weaving tension; False (default): the
            cell keeps the crimp stage's size and its yarns their weaving tension. The
            shear then turns the released cell's edge, and the summary's ``released``
            gives the cell's size before and after and its strain.
        release_fraction: the release's Berendsen time constant over the test duration
            (it settles for ten of them before the shear starts), (0, 0.2].
    """

    protocol = "periodic_shear"
    box_gradient = {"xy": "v_lg_xy", "yy": "v_lg_yy"}
    title = "trellis shear"
    rate_curve = ("shear_angle_deg", "normalised_force_n_m")
    interval_axis = ("shear_angle_deg", 5.0)
    rate_keys = {"initial_stiffness_change": "initial_shear_stiffness_n_m_per_rad"}

    max_shear_angle_deg: float = 40.0
    report_angles_deg: tuple[float, ...] = (10.0, 20.0, 30.0)
    speed_fraction: float = 1e-3
    locking_initial_deg: tuple[float, float] = (10.0, 20.0)
    locking_factor: float = 2.0
    release_tension: bool = False
    release_fraction: float = 0.02

    def check_fields(self) -> None:
        inputs.in_range("periodic_shear.max_shear_angle_deg", self.max_shear_angle_deg, 0, 70,
                        low_open=True)
        inputs.boolean("periodic_shear.release_tension", self.release_tension)
        inputs.in_range("periodic_shear.release_fraction", self.release_fraction, 0, 0.2,
                        low_open=True)
        inputs.locking_method("periodic_shear", self.locking_initial_deg, self.locking_factor, 70)

    def travel_m(self, model: BeadModel) -> float:
        """Arc the turning edge's end travels, b·γ [m]."""
        return self.cell(model)[1] * math.radians(self.max_shear_angle_deg)

    def box_motion(self, model: BeadModel) -> str:
        # released: the size the release left, read when LAMMPS reaches this line
        b = "$(ly:%.15g)" if self.release_tension else fmt(self.cell(model)[1])
        source = ("after the release of the yarns' tension" if self.release_tension
                  else "the crimped cell's")
        return render_inline("periodic_shear_box", b=b, b_source=source,
                             **self._schedule(model))

    def transverse_block(self, model: BeadModel) -> str:
        if not self.release_tension:
            return "# the cell keeps its size: the yarns keep the crimp stage's tension"
        modulus = berendsen_modulus_pa(model)
        pdamp = self.release_fraction * self.duration_s(model)
        return render_inline("periodic_release", pdamp=pdamp, modulus=modulus,
                             settle_steps=math.ceil(10 * pdamp / self.time_step_s(model)))

    def reduce(self, run_dir: Path, model: BeadModel,
               monitor: ContactPower | None = None) -> DrivenResult:
        plan = self.read_plan(run_dir, model)  # what the run was written with
        out = read_outputs(run_dir, plan.every, plan.time_step_s, monitor)
        # the cell as the shear starts (after a release of the yarns' tension, if any)
        lx0, ly0 = float(out["box_lx_m"][0]), float(out["box_ly_m"][0])
        gamma = np.arctan2(out["box_xy_m"], out["box_ly_m"])
        # F_norm = power per initial area / (cos γ γ̇): work over A0·Δ(sin γ) per interval
        fnorm = interval_force(np.sin(gamma), out.external_work_j) / (lx0 * ly0)
        deg = np.degrees(gamma)
        curve = {"time_s": out["time_s"], "shear_angle_deg": deg, "normalised_force_n_m": fnorm,
                 "shear_force_per_length_n_m": out["n_xy_n_m"], **energy_columns(out)}
        # the picture frame's method, so the two compare (a tangent over the test's last
        # part read the same curve 10° later: benchmarks/RESULTS.md "The picture frame's
        # edges")
        lock = locking_angle(deg, fnorm, initial_deg=self.locking_initial_deg,
                             factor=self.locking_factor)
        initial = (None if lock["initial_slope"] is None
                   else float(np.degrees(lock["initial_slope"])))  # per radian
        summary = self._common_summary(model, out, deg / self.max_shear_angle_deg, plan)
        cell = self.cell(model)
        first = min(1, len(out["n_xx_n_m"]) - 1)
        summary.update({
            "released": None if not self.release_tension else {
                "cell_before_m": [cell[0], cell[1]], "cell_after_m": [lx0, ly0],
                "strain_pct": [100 * (lx0 / cell[0] - 1), 100 * (ly0 / cell[1] - 1)],
                # what is left of the membrane forces as the shear starts (ten Berendsen
                # time constants, each release_fraction of this test's duration: a slower
                # test releases more completely): the first average (row 0 has none yet)
                "membrane_force_at_start_n_m": [float(out["n_xx_n_m"][first]),
                                                float(out["n_yy_n_m"][first])]},
            "initial_shear_stiffness_n_m_per_rad": initial,
            "locking_angle_deg": lock["x"] if lock["found"] else None,
            "locking": lock,
            "normalised_force_at_angle_n_m": {f"{k:g}": v for k, v in values_at(
                deg, fnorm, self.report_angles_deg).items()},
            "max_normalised_force_n_m": float(fnorm.max()),
        })
        plot = {"path": "curve.png",
                "series": [{"x": deg, "y": fnorm, "label": "F_norm (power / A0 cos γ γ̇)"},
                           {"x": deg, "y": out["n_xy_n_m"], "style": "--",
                            "label": "N_xy (virial)"}],
                "xlabel": "shear angle γ [deg]", "ylabel": "shear force per length [N/m]",
                "title": "Periodic cell: trellis shear",
                "notes": f"cell {1e3 * lx0:.2f} x {1e3 * ly0:.2f} mm\n{model.n_beads:,} beads",
                "marks": report_marks(summary["normalised_force_at_angle_n_m"])
                + ([{"kind": "vline", "x": lock["x"], "label": f"locking {lock['x']:.3g}°"}]
                   if lock["found"] else [])}
        return DrivenResult(Path(run_dir), curve, summary, [plot])
