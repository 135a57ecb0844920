"""The LAMMPS input of a drape: ``lammps_templates/drape.lmp`` (tools, holder force control,
clamping phase, draw, outputs) and ``drape_symmetry*.lmp`` (the symmetry planes), filled with
the numbers of a :class:`~fabmd.protocols.drape.Drape` on its blank (SI units throughout).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...model.bead_model import BeadModel
from ...model.beads import BeadParameters, model_bead_parameters
from ...scene import blocks
from ...scene.adaptive import speed_commands
from ...scene.templates import render
from .geometry import DrapeGeometry, tool_geometry

if TYPE_CHECKING:
    from .protocol import Drape

#: tool wall fix ids (their contact arrays feed the forces and the overlap monitor)
TOOLS = ("punch", "die", "die_wall", "holder")
#: forces and powers are sampled every this many steps for the interval means
SAMPLE_EVERY = 5
#: overlap monitor interval, and its log of the clamping phase (overlap.dat: the draw)
OVERLAP_EVERY = 100
CLAMP_OVERLAP_FILE = "clamp_overlap.dat"
#: bead ids per line of a group command (LAMMPS lines continue with " &")
IDS_PER_LINE = 16


def id_list(ids: tuple[int, ...]) -> str:
    """LAMMPS atom ids (1-based) of the 0-based bead indices ``ids``, 16 per line."""
    words = [str(i + 1) for i in ids]
    rows = [" ".join(words[k:k + IDS_PER_LINE]) for k in range(0, len(words), IDS_PER_LINE)]
    return " &\n    ".join(rows)


def symmetry_fixes(g: DrapeGeometry) -> str:
    """The symmetry planes of a quarter model: the fibre ends cut there held in the plane's
    normal direction (none for the full model)."""
    if not g.quarter:
        return render("drape_symmetry_full").rstrip("\n")
    planes = {}
    for name, ids, comps in (("sym_x", g.sym_x, "0.0 NULL NULL"),
                             ("sym_y", g.sym_y, "NULL 0.0 NULL")):
        if ids:
            text = render("drape_symmetry_plane", group=name, ids=id_list(ids),
                          components=comps)
        else:
            text = render("drape_symmetry_no_ends", axis=name[-1])
        planes[f"plane_{name[-1]}"] = text.rstrip("\n")
    return render("drape_symmetry", **planes).rstrip("\n")


def clamp_values(test: Drape, model: BeadModel, geometry: DrapeGeometry) -> dict:
    """Template values of the clamping phase: local damping and a light drag (as in
    :func:`fabmd.scene.blocks.relax`) until quasi-static with the holder force within
    5 % of its set value. Quasi-static reference force: the holder force per yarn
    crossing under it."""
    control = test.holder_control(model, geometry)
    ref = test.holder_share_n(geometry) / control["crossings_under_holder"]
    k = max(bt.spring_n_per_m for bt in model.fibre_bond_types())
    dt = test.time_step_s(model)
    return {"clamp_damping": 0.7,
            "clamp_drag": float(np.median(model.masses)) / (200.0 * dt),
            "clamp_monitors": test.clamp.monitors("free", ref,
                                                  model.n_bonds * ref**2 / (2 * k)),
            "clamp_tolerance": 0.05, "clamp_check_every": test.clamp.check_every,
            "clamp_max_steps": test.clamp.max_steps}


def tool_walls(test: Drape, beads: list[BeadParameters]) -> str:
    """The granular walls of punch, die, die wall and holder, each on its zone's beads."""
    zones = {"punch": ("punch", "punch_zone"), "die": ("die", "die_zone"),
             "die_wall": ("die_wall", "die_wall_zone"), "holder": ("holder", "holder_zone")}
    return "\n".join(blocks.tool_region(test.holder_tool if tool == "holder" else test.tool,
                                        beads, region, tool, group=group)
                     for tool, (region, group) in zones.items())


def adaptive_motion(test: Drape, model: BeadModel, g: DrapeGeometry) -> tuple[str, str, str]:
    """(punch travel, punch speed, LAMMPS text) of the adaptive punch
    (:mod:`fabmd.scene.adaptive`): the speed is the smooth start's times the adapted factor,
    the travel its integral (a ``fix controller`` that adds speed · dt each step). Its
    kinetic measure is the fabric's inertial force over the punch force (the drape's own
    quasi-static measure), held under ``max_kinetic_ratio``; floor force of that and of the
    drag share: ``floor_force_n``, default a hundredth of the holder force (this model's
    share); the drag share's memory a tenth of the draw (the other tests' drag time), not
    the drape's drag time."""
    plan = test.plan(model)
    load = test.loading(model)
    floor_force = test.loading_speed.floor_force_n or 0.01 * test.holder_share_n(g)
    interval = plan.extra["control_interval_steps"]
    speed = speed_commands(
        plan, "v_p_ext", 0.0, floor_force * plan.speed_m_s, displacement="punch_travel",
        kinetic=("v_adapt_inertia", "the fabric's inertial force over the punch force"),
        # the drape's drag time is its whole draw (a light drag): averaged over it, the
        # early draw's drag share would hold the speed to the end
        memory_s=plan.duration_s / 10,
        # before the punch carries force the drag share and inertia say nothing of the
        # blank: free to speed up there, the punch reached the blank at 4x its base speed
        gate=("v_adapt_punch_engaged", "1 once the punch carries the floor force (before: "
              "the base speed)"))
    # the interval is a multiple of SAMPLE_EVERY (Drape.plan_loading)
    text = render("drape_adaptive", interval=interval, interval_s=interval * plan.time_step_s,
                  floor_force=floor_force, sample_every=SAMPLE_EVERY,
                  copy_alpha=1.0 / (interval * plan.time_step_s),
                  samples=interval // SAMPLE_EVERY, speed=speed)
    return "v_punch_travel_int", f"({load.lammps_velocity()})*v_adapt_factor", text


def input_text(test: Drape, model: BeadModel) -> str:
    """The whole LAMMPS input of ``test`` on ``model`` (a blank from ``Drape.prepare``)."""
    g = tool_geometry(test, model)
    dt = test.time_step_s(model)
    load = test.loading(model)
    beads = model_bead_parameters(model)
    steps = test.steps(model)
    control = test.holder_control(model, g)
    every = test.every(model)  # a multiple of SAMPLE_EVERY, adaptive or not
    displacement, velocity, adaptive = load.lammps_displacement(), load.lammps_velocity(), ""
    if test.loading_speed.adaptive:
        displacement, velocity, adaptive = adaptive_motion(test, model, g)
    text = render(
        "drape", symmetry=test.symmetry, radius=g.radius_m, punch_z=g.punch_z_m,
        z_die=g.z_die_m, die_radius=g.die_radius_m, holder_radius=g.holder_radius_m,
        die_wall_gap=0.5 * g.diameter_m,
        face_radius=g.face_radius_m, z_face_top=g.z_die_m + 1e-6 * g.face_radius_m,
        wall_lo=g.z_die_m - 2 * g.radius_m, wall_hi=g.z_die_m - 0.5 * g.diameter_m,
        holder_force=test.holder_share_n(g), z_holder=g.z_holder_m,
        walls=tool_walls(test, beads),
        **test.reach(g),
        holder_gain=control["gain_m_s_n"], symmetry_fixes=symmetry_fixes(g),
        holder_ki=1.0 / control["integral_time_s"],
        guards=blocks.guards(model, dt),
        overlap=blocks.overlap_monitor(model, test.contact, beads, every=OVERLAP_EVERY,
                                       tool_fixes=TOOLS, file=CLAMP_OVERLAP_FILE),
        overlap_every=OVERLAP_EVERY,
        clamp_every=max(1, test.clamp.check_every // 5),
        holder_integral_time=control["integral_time_s"],
        **clamp_values(test, model, g),
        displacement=displacement, velocity=velocity,
        gamma=test.gamma(model), sample_every=SAMPLE_EVERY,
        samples_per_interval=every // SAMPLE_EVERY, every=every,
        strain_energy="ebond+eangle" if len(model.angles) else "ebond",
        thermo_every=max(test.every(model), steps // 20))
    # the drape's guards sit in its template (before the clamping phase)
    return test.scene_text(model, dt, text, after=(
        *([adaptive] if adaptive else []), test.trajectory.commands(steps),
        render("run", steps=steps),
        test.trajectory.final_commands(), render("finish", final_data="final.data")))
