"""Reading a drape run back: force curves, the holder's force control, energy balance,
inertia, the draped shape's measures and the summary (forces and energies for the whole
blank: the quarter model's × 4; SI units).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...engine import mpi
from ...model.bead_model import BeadModel
from ...model.contact import ContactModel
from ...results.curves import values_at
from ...results.folder import read_print_file
from ...scene.adaptive import adaptive_summary, window_mean, window_width_m
from ...scene.energy import ContactPower
from ..common import overlap_summary
from ..driven import DrivenResult
from ..driven_outputs import Outputs, kinetic_to_work_ratio, read_outputs, started_mask
from .geometry import DrapeGeometry, tool_geometry
from .input import CLAMP_OVERLAP_FILE
from .measures import draw_in, punch_reach, shear_grid, wrinkling
from .report import plot_specs, write_final

if TYPE_CHECKING:
    from ...analysis.angles import Field
    from ...scene.plan import RunPlan
    from .protocol import Drape


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

        from ...errors import OverlapWarning

        warnings.warn(out["warnings"][0], OverlapWarning, stacklevel=2)
    return out


def clamp_steps(run_dir: Path) -> int | None:
    """Steps the clamping phase took (from ``clamp.dat``)."""
    path = Path(run_dir) / "clamp.dat"
    if not path.exists():
        return None
    steps = read_print_file(path)["step"]
    return int(steps[-1]) if len(steps) else 0


def force_curve(out: Outputs, g: DrapeGeometry, every: int, dt: float) -> dict:
    """Curve columns for the whole blank: travel, depth, tool forces, energies, the work the
    tool contacts absorbed and the fabric's vertical momentum and inertial force."""
    scale = 1.0 / g.share
    travel = out["punch_travel_m"]
    depth = np.maximum(travel - g.gap_m, 0.0)
    tool_j = np.cumsum(out.means["tool_contact_power_w"] * every * dt)
    tool_j = np.interp(out["step"], out.means["step"], tool_j, left=0.0)
    curve = {"time_s": out["time_s"], "punch_travel_m": travel, "depth_m": depth,
             "punch_force_n": out["punch_force_n"] * scale,
             "holder_force_n": out["holder_force_n"] * scale,
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
    return curve


def holder_summary(run_dir: Path, out: Outputs, test: Drape, model: BeadModel,
                   g: DrapeGeometry, dt: float) -> dict:
    """The blank holder's force against its set value over the draw (interval means after
    the clamping phase, whole blank) and its force control at the time step ``dt`` [s]."""
    scale = 1.0 / g.share
    set_force = test.holder_force_n
    means = out.means
    after = means["step"] > 0
    hmean = means["holder_force_n"][after] * scale
    herr = (hmean - set_force) / set_force
    clamp = read_print_file(run_dir / "clamp.dat") if (run_dir / "clamp.dat").exists() else {}
    return {
        "set_force_n": set_force,
        "mean_force_n": float(hmean.mean()) if hmean.size else None,
        "max_relative_error": float(np.abs(herr).max()) if herr.size else None,
        "rms_relative_error": float(np.sqrt(np.mean(herr**2))) if herr.size else None,
        "max_force_n": float(hmean.max()) if hmean.size else None,
        "min_force_n": float(hmean.min()) if hmean.size else None,
        "holder_travel_m": float(np.ptp(out["holder_displacement_m"])),
        "clamp_end_force_n": float(clamp["holder_force_n"][-1] * scale) if clamp else None,
        "control": test.holder_control(model, g, dt),
        "note": "interval means over the draw (after the clamping phase), for the whole "
                "blank; error = (F - F_set)/F_set",
    }


def energy_terms(out: Outputs, tool_work_j: float, scale: float) -> dict:
    """External work = ΔU + ΔKE + damping + fibre contact work + tool contacts [J], whole
    blank, and the closing error (``tool_work_j``: the tool contacts' work, whole blank)."""
    w = float(out.external_work_j[-1])
    terms = {"external_work_j": w * scale,
             "strain_energy_change_j": float(out["strain_energy_j"][-1]
                                             - out["strain_energy_j"][0]) * scale,
             "kinetic_energy_change_j": float(out["kinetic_j"][-1] - out["kinetic_j"][0])
             * scale,
             "damping_dissipation_j": float(out.damping_j[-1]) * scale,
             "tool_contact_work_j": float(tool_work_j),
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
    return terms


def shear_summary(fld: Field, g: DrapeGeometry, cell: float) -> dict:
    """The largest shear angle over the cells clear of the blank's edges by a yarn spacing (at
    a cut edge the free fibre ends turn without shearing the fabric)."""
    hx, hy = g.half_size_m
    xc, yc = np.meshgrid(fld.x_centres_m, fld.y_centres_m)
    interior = ((np.abs(xc) + 0.5 * cell <= hx - 0.5 * g.spacing_m)
                & (np.abs(yc) + 0.5 * cell <= hy - 0.5 * g.spacing_m))
    finite = np.isfinite(fld.values)
    inside = finite & interior
    absg = np.abs(fld.values[inside])
    where = np.where(inside, np.abs(np.nan_to_num(fld.values)), -1.0)
    jmax, imax = np.unravel_index(np.argmax(where), fld.values.shape)
    return {"cell_m": cell, "cells": int(inside.sum()),
            "max_abs_deg": float(absg.max()) if absg.size else None,
            "p95_abs_deg": float(np.percentile(absg, 95)) if absg.size else None,
            "max_at_m": [float(fld.x_centres_m[imax]), float(fld.y_centres_m[jmax])],
            "max_abs_all_cells_deg": float(np.abs(fld.values[finite]).max())
            if finite.any() else None,
            "method": "angle between the summed warp and weft bead tangents (3D) per cell of "
                      "a grid over the initial in-plane positions, gamma = 90 - angle; the "
                      "largest value over the cells clear of the blank's edges by a yarn "
                      "spacing (max_abs_all_cells_deg: all cells)"}


def inertia_summary(out: Outputs, curve: dict, started: np.ndarray, scale: float) -> dict:
    """Mean inertial force over the draw against the mean punch force, and the largest
    ratio of the two where the punch force exceeds a tenth of its maximum."""
    punch, depth = curve["punch_force_n"], curve["depth_m"]
    momentum, inertial = -curve["momentum_z_kg_m_s"], curve["inertial_force_n"]
    loaded = started & (punch > 0.1 * punch.max()) if punch.max() > 0 else started
    duration = float(out["time_s"][-1] - out["time_s"][0])
    return {
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


def max_bond_strain(model: BeadModel, final: BeadModel) -> float:
    """Largest fibre bond strain of the final state against the rest lengths."""
    rest = np.array([bt.rest_length_m for bt in model.bond_type_table])[model.bond_types - 1]
    strain = (final.bond_lengths() / rest - 1.0)[model.fibre_bond_mask()]
    return float(strain.max())


def setup_summary(run_dir: Path, test: Drape, model: BeadModel, g: DrapeGeometry,
                  plan: RunPlan, strain: float) -> dict:
    """The summary's first part: the model, tools, zones and loading of the run (``plan``:
    what it was run with) and its largest bond strain."""
    reach = test.reach(g)
    r0 = np.hypot(model.positions[:, 0], model.positions[:, 1])
    return {
        "protocol": test.protocol,
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
        "max_bond_strain": strain,
        "tool_friction": test.tool.friction,
        "fibre_friction": test.contact.friction,
        "time_step_s": plan.time_step_s,
        "steps": plan.steps,
        "clamp_steps": clamp_steps(run_dir),
        "punch_speed_m_s": plan.speed_m_s,
    }


def reduce(run_dir: Path, model: BeadModel, test: Drape,
           monitor: ContactPower | None = None) -> DrivenResult:
    """Force curves, holder-force control, shear angles, wrinkling, draw-in, final shape."""
    run_dir = Path(run_dir)
    g = tool_geometry(test, model)
    scale = 1.0 / g.share
    plan = test.read_plan(run_dir, model)  # what the run was written with
    dt = plan.time_step_s
    out = read_outputs(run_dir, plan.every, dt, monitor)
    window = window_width_m(plan)
    if window is not None:  # adaptive: the tool forces over the fixed run's interval travel
        for name in ("punch_force_n", "holder_force_n", "die_force_n"):
            out.columns[name] = window_mean(out["punch_travel_m"], out[name], window)
    curve = force_curve(out, g, plan.every, dt)
    travel, depth = curve["punch_travel_m"], curve["depth_m"]
    speed = None
    if window is not None:  # the adapted punch speed, from its travel
        speed = np.gradient(travel, out["time_s"]) if len(travel) > 2 else 0 * travel
        curve["punch_speed_m_s"] = speed
    punch = curve["punch_force_n"]
    started = started_mask(out, plan.loading, travel / test.travel_m(model))
    holder = holder_summary(run_dir, out, test, model, g, dt)
    terms = energy_terms(out, curve["tool_contact_work_j"][-1], scale)
    final = BeadModel.load(run_dir / "final.data", run_dir / "model.json")
    ref, cur = model.positions, final.positions
    from ...analysis.surface import surface_shear_angle_field

    cell = test.shear_cell_m or 2.0 * g.spacing_m
    xe, ye = shear_grid(g, cell)
    fld = surface_shear_angle_field(ref, cur, model.fibre_ids, model.families, xe, ye)
    shear = shear_summary(fld, g, cell)
    inertia = inertia_summary(out, curve, started, scale)
    ratio = (inertia["mean_inertial_force_n"] / inertia["mean_punch_force_n"]
             if inertia["mean_inertial_force_n"] is not None and inertia["mean_punch_force_n"]
             else None)
    summary = setup_summary(run_dir, test, model, g, plan, max_bond_strain(model, final))
    summary.update(adaptive_summary(plan, out["step"], out["time_s"], speed))
    summary.update({
        "max_punch_force_n": float(punch.max()),
        "final_punch_force_n": float(punch[depth >= 0.95 * depth[-1]].mean()),
        "final_punch_force_note": "mean over the last 5 % of the depth",
        "punch_force_at_depth_n": {f"{k:g}": v for k, v in values_at(
            depth, punch, test.report_depths_m).items()},
        "holder_force": holder,
        "max_shear_angle_deg": shear["max_abs_deg"],
        "shear_angle": shear,
        "wrinkling": wrinkling(ref, cur, g, float(travel[-1])),
        "draw_in": draw_in(ref, cur, g),
        # the punch's reach against its contact zone; the zone radii under their own key
        # (punch_reach held the radii alone from the tool_zones switch to stop 16)
        "punch_reach": punch_reach(ref, cur, g, float(travel[-1]),
                                   test.reach(g)["punch_reach"]),
        "tool_zone_radii_m": test.reach(g),
        "max_kinetic_to_external_work": kinetic_to_work_ratio(out, started),
        "inertia": inertia,
        "mean_inertial_to_punch_force": ratio,
        "quasi_static_note": "kinetic energy of the fabric over the work done so far, after "
                             "the smooth start and the first tenth of the travel",
        "energy_balance": terms,
        "forces_note": "forces and energies are for the whole blank (the quarter model's x 4)"
                       if g.quarter else "forces and energies of the whole blank",
    })
    summary.update(merged_overlap(run_dir, test.contact))
    write_final(run_dir, model, final, fld, g, test, travel[-1])
    notes = (f"R = {1e3 * g.radius_m:g} mm, depth {1e3 * test.depth_m:g} mm, {test.symmetry}"
             f"\nholder {test.holder_force_n:g} N, mu tool {test.tool.friction:g}"
             f"\nmean inertial / punch force {'-' if ratio is None else f'{ratio:.2g}'}"
             f"\n{model.n_beads} beads")
    plots = plot_specs(depth, punch, curve["holder_force_n"], test.holder_force_n, notes,
                       holder["max_relative_error"])
    return DrivenResult(run_dir, curve, summary, plots)
