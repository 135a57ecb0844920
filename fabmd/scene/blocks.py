"""Input fragments rendered from ``lammps_templates/`` for a bead model."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..model.bead_model import BeadModel
from ..model.beads import BeadParameters
from ..model.bundle_contact import TABLE_POINTS
from ..model.contact import (
    WITHIN_FAMILY_TABLE,
    ContactModel,
    ToolContact,
)
from ..model.crossing_law import CROSSING_KEYWORD
from .templates import fmt, render, render_inline

#: neighbour skin as a fraction of the smallest bead diameter (LAMMPS-NOTES: ~0.2 d)
SKIN_FRACTION = 0.2
#: a bead that moves this fraction of the shortest bond per step is running away
SPEED_FRACTION = 0.1
#: a bond longer than this multiple of the longest rest length is running away
BOND_RUNAWAY = 1.5
#: steps between bond-stretch checks: fix halt's own ``bondmax`` is cheap, and a time-step
#: blow-up must be stopped within a few steps, before LAMMPS loses bond atoms
BOND_GUARD_EVERY = 2
#: the file the overlap monitor writes into the run folder
OVERLAP_FILE = "overlap.dat"
#: overlap/d that stops a run with tool contact only (no ContactModel to say)
TOOL_OVERLAP_LIMIT = 0.5
#: overlap/d above which a run with tool contact only warns
TOOL_OVERLAP_WARNING = 0.1


def boundary_text(model: BeadModel) -> str:
    """LAMMPS ``boundary`` argument: p where periodic, else shrink-wrapped with the data
    file's box as minimum (m), so that moving clamps and tools never lose beads."""
    return " ".join("p" if p else "m" for p in model.periodic)


def neighbour_skin(model: BeadModel) -> float:
    """Neighbour skin [m]."""
    return SKIN_FRACTION * float(model.diameters.min())


def comm_cutoff(model: BeadModel) -> float:
    """Ghost cutoff [m]: covers contact (largest diameter + skin), three fibre bond lengths
    (angles, special neighbours) and a stretched cohesion link."""
    longest_bond = max((bt.rest_length_m for bt in model.fibre_bond_types()), default=0.0)
    longest_link = max((bt.rest_length_m for bt in model.bond_type_table
                        if bt.kind == "cohesion"), default=0.0)
    return max(float(model.diameters.max()) + neighbour_skin(model), 3.0 * longest_bond,
               1.5 * longest_link) * 1.01


def setup(model: BeadModel, protocol: str, data_file: str, time_step_s: float) -> str:
    """Units, atom style, box, beads, neighbour settings, time step."""
    return render("setup", protocol=protocol, boundary=boundary_text(model),
                  comm_cutoff=comm_cutoff(model), data_file=data_file,
                  skin=neighbour_skin(model), time_step=time_step_s)


def bond_coeffs(model: BeadModel, rest_length_scale: dict[int, float] | None = None,
                types: list[int] | None = None, note: str = "") -> str:
    """``bond_coeff`` lines of the bond types ``types`` (1-based; None: all), each with its
    rest length [m] times ``rest_length_scale[type]`` (default 1) and a comment naming the
    family, the kind of non-fibre bonds, then ``note``."""
    scale = rest_length_scale or {}
    table = model.bond_type_table
    wanted = range(1, len(table) + 1) if types is None else types
    lines = []
    for i in wanted:
        bt = table[i - 1]
        lines.append(render_inline(
            "bond_coeff", type=i, coefficient=bt.coefficient,
            rest_length=bt.rest_length_m * scale.get(i, 1.0), family=bt.family,
            note=("" if bt.kind == "fibre" else f" {bt.kind}") + note))
    return "\n".join(lines)


def bonds(model: BeadModel, rest_length_scale: dict[int, float] | None = None) -> str:
    """``bond_style harmonic`` with one coefficient line per bond type (and angles)."""
    table = model.angle_type_table
    if table and len(model.angles):
        angle_block = render_inline("angle_style", angle_coeffs="\n".join(
            render_inline("angle_coeff", type=i, coefficient=at.coefficient, family=at.family)
            for i, at in enumerate(table, start=1)))
    else:
        angle_block = "# no bending term in this scene"
    return render("bonds", bond_coeffs=bond_coeffs(model, rest_length_scale),
                  angle_block=angle_block)


def bond_ramp(model: BeadModel, fix_id: str, strains: dict[int, float],
              shrink: bool = False) -> str:
    """Start ramping the rest length of bond types (1-based keys of ``strains``) over the
    next ``run``: r0·(1 + strain·ramp(0,1)) (``shrink``: r0·(1 − strain·ramp(0,1))), one
    ``fix adapt`` named ``fix_id``. Types with zero strain keep their rest length; with none
    left, type 1 is adapted to its own rest length (a ramp that changes nothing). End it
    with :func:`bond_ramp_end`."""
    table = model.bond_type_table
    ramped = [(i, s) for i, s in strains.items() if s != 0.0]
    if ramped:
        variables = [render_inline("bond_ramp_variable", type=i,
                                   rest_length=table[i - 1].rest_length_m,
                                   sign="-" if shrink else "+", strain=s) for i, s in ramped]
    else:  # nothing to ramp
        ramped = [(1, 0.0)]
        variables = [render_inline("bond_ramp_fixed", type=1,
                                   rest_length=table[0].rest_length_m)]
    args = " ".join(render_inline("bond_ramp_adapt", type=i) for i, _ in ramped)
    return render_inline("bond_ramp", variables="\n".join(variables), fix_id=fix_id,
                         adapt_args=args)


def bond_ramp_end(model: BeadModel, fix_id: str, rest_length_scale: dict[int, float],
                  types: list[int] | None = None, note: str = "") -> str:
    """After the ramp run: drop ``fix_id`` and keep the final rest lengths (``bond_coeff``
    of ``types``, None: all, see :func:`bond_coeffs`)."""
    return render_inline("bond_ramp_end", fix_id=fix_id,
                         bond_coeffs=bond_coeffs(model, rest_length_scale, types, note))


def group_ids(name: str, atom_ids) -> str:
    """``group <name> id ...`` of LAMMPS atom ids (1-based), 16 a line; an empty group
    when there are none."""
    ids = [str(int(i)) for i in atom_ids]
    if not ids:
        return render_inline("group_empty", group=name)
    rows = [" ".join(ids[k:k + 16]) for k in range(0, len(ids), 16)]
    return render_inline("group_ids", group=name, ids=" &\n    ".join(rows))


def lost_check() -> str:
    """Atoms or bond partners lost are errors (``thermo_modify lost``)."""
    return render_inline("lost_check")


def guards(model: BeadModel, time_step_s: float, every: int = 20,
           max_rest_length_scale: float = 1.0, check_lost: bool = True) -> str:
    """Stability guards (see :mod:`fabmd.engine.diagnosis` for the causes).

    ``check_lost=False`` leaves out :func:`lost_check` (a blank line instead), for an
    input that puts it after its runs.
    """
    shortest = min((bt.rest_length_m for bt in model.bond_type_table),
                   default=float(model.diameters.min()))
    speed_limit = SPEED_FRACTION * shortest / time_step_s
    if model.n_bonds:
        longest = max(bt.rest_length_m for bt in model.bond_type_table)
        bond_guard = render("bond_guard", bond_limit=BOND_RUNAWAY * longest
                            * max_rest_length_scale, every=BOND_GUARD_EVERY)
    else:
        bond_guard = "# no bonds: no bond-stretch guard"
    return render("guards", speed_fraction=SPEED_FRACTION, speed_limit=speed_limit,
                  every=every, bond_guard=bond_guard,
                  lost_check=lost_check() if check_lost else "")


def trajectory(every: int, *, velocities: bool = False, bond_forces: bool = True) -> str:
    """Outputs block: a trajectory frame every ``every`` steps (see
    :mod:`fabmd.scene.outputs`; put :func:`trajectory_final` after the last run and call
    :func:`fabmd.results.trajectory.finalise` on the run folder afterwards)."""
    from . import outputs

    return outputs.trajectory(every, velocities=velocities, bond_forces=bond_forces)


def trajectory_final(bond_forces: bool = True, close: bool = False) -> str:
    """After the last run: the final step as the trajectory's last frame (``close``: then
    ``undump``, as LAMMPS needs before a ``reset_timestep``)."""
    from . import outputs

    return outputs.trajectory_final(bond_forces, close=close)


def contact(model: BeadModel, contact_model: ContactModel | None,
            beads: list[BeadParameters]) -> str:
    """Fibre–fibre contact, or ``pair_style none`` when the scene needs none."""
    if contact_model is None:
        return render("contact_none")
    if contact_model.split:  # per type pair: pair_style granular (ContactModel docstring)
        law = contact_model.within_family_law
        lines = [render_inline("pair_coeff_granular_split", i=i, j=j, kn=fmt(c["kn"]),
                               gamman=fmt(c["gamman"]), kt=fmt(c["kt"]),
                               xgammat=fmt(c["gammat"] / c["gamman"]),
                               friction=fmt(c["friction"]),
                               sub_style="" if law is None else "granular ")
                 for i, j, c in contact_model.type_pair_coefficients(
                     beads, len(model.family_names), model.family_names)]
        if law is None:
            return render("contact_granular_split", friction=contact_model.friction,
                          pair_coeffs="\n".join(lines))
        return _contact_law(model, contact_model, beads, lines)
    c = contact_model.pair_coefficients(beads)
    return render("contact_granular", normal=contact_model.normal,
                  style=contact_model.pair_style(), **c)


def _contact_law(model: BeadModel, contact_model: ContactModel, beads: list[BeadParameters],
                 pair_coeffs: list[str]) -> str:
    """``hybrid/overlay granular table``: the within-family law (ContactModel docstring),
    each family on its own table section (its fibre's diameter); the table file comes from
    :meth:`ContactModel.table_files` (:func:`contact_files`)."""
    law = contact_model.within_family_law
    listed = contact_model.law_sections(beads)
    sections = {s.bundle: s for s in listed}
    tables = []
    for i, family in enumerate(model.family_names, start=1):
        own = contact_model.family_law(family)
        d = model.diameters[model.atom_types == i]
        if not d.size:  # a family without beads here: any section will do
            own = listed[0].bundle
        elif own not in sections or np.max(np.abs(d / own.diameter_m - 1.0)) > 1e-9:
            raise InputError(f"contact.within_family_law: the {family} fibres need the "
                             f"law's bead diameter {own.diameter_m:.6g} m (their fibre's), "
                             f"got {d.min():.6g}–{d.max():.6g} m")
        tables.append(render_inline("pair_coeff_table_law", i=i, j=i,
                                    table_file=WITHIN_FAMILY_TABLE,
                                    keyword=sections[own].keyword, cutoff=own.cutoff_text))
    if contact_model.crossing == "law":  # every pair of different families: the crossing
        n = len(model.family_names)
        tables += [render_inline("pair_coeff_table_law", i=i, j=j, table_file=WITHIN_FAMILY_TABLE,
                                 keyword=CROSSING_KEYWORD, cutoff=law.cutoff_text)
                   for i in range(1, n + 1) for j in range(i + 1, n + 1)]
    note = ("fibres of different families cross\n# through a patch that compacts by the same "
            "law (section CROSSING; contact.crossing = 'law')"
            if contact_model.crossing == "law" else
            "fibres of different families\n# touch with the crossing stiffness")
    return render("contact_granular_law", law=law.law.name, friction=contact_model.friction,
                  crossing_note=note,
                  table_file=WITHIN_FAMILY_TABLE, points=TABLE_POINTS,
                  pair_coeffs="\n".join(pair_coeffs), table_coeffs="\n".join(tables))


def contact_files(contact_model: ContactModel | None, beads: list[BeadParameters]
                  ) -> dict[str, str]:
    """Files :func:`contact` reads, by name, for the run folder (the within-family law's
    table; none for the other contacts): pass them to ``write_run_folder(files=...)``."""
    return {} if contact_model is None else contact_model.table_files(beads)


def relax(model: BeadModel, time_step_s: float, held: str, free: str, quasi_static,
          reference_force_n: float, reference_energy_j: float, damping_ratio: float = 0.7,
          drag_time_steps: float = 200.0, trajectory=None) -> str:
    """Relax with ``held`` fixed until at rest, then reset the clock (time 0).

    Two runs of at most ``quasi_static.max_steps`` each. First damped: local (Cundall)
    damping plus a light viscous drag γ = m/τ with τ = ``drag_time_steps`` time steps,
    which stops force-free floppy motion, until the quasi-static criterion holds. Then
    undamped, every velocity zeroed on each step the fabric's own forces work against
    the motion, until the criterion holds on those forces and on the kinetic energy
    averaged over the check interval (the ``settled`` halt): the drag overdamps slow
    modes that carry force, which creep on below the criterion's scales (benchmarks/
    RESULTS.md "A relaxation that stops while the fabric still creeps").

    Args:
        trajectory: a :class:`fabmd.scene.outputs.TrajectoryOutput` to write over the
            relaxation (frames spread over a quarter of ``max_steps``, the final state
            the last frame; closed before the clock is reset); None: no trajectory.
    """
    drag = float(np.median(model.masses)) / (drag_time_steps * time_step_s)
    if trajectory is not None and trajectory.enabled:
        dump = trajectory.commands(max(1, quasi_static.max_steps // 4))
        final = trajectory.final_commands(close=True)
    else:
        dump = final = "# no trajectory of the relaxation"
    return render("relax", held=held, free=free, damping_ratio=damping_ratio, drag=drag,
                  monitors=quasi_static.monitors(free, reference_force_n, reference_energy_j),
                  check_every=quasi_static.check_every, max_steps=quasi_static.max_steps,
                  motion_ratio=quasi_static.motion_ratio,
                  diameter=float(np.min(model.diameters)), trajectory=dump,
                  trajectory_final=final)


def _tool_contact(tool: ToolContact, beads: list[BeadParameters], fix_id: str, group: str,
                  wall_fix: str, where: str, contacts: bool) -> str:
    c = tool.wall_coefficients(beads)
    # granular's tangential damping is a multiple of the normal one
    ratio = c["gammat"] / c["gamman"] if c["gamman"] else 0.0
    return render("wall_gran", fix_id=fix_id, group=group, where=where, wall_fix=wall_fix,
                  contacts=" contacts" if contacts else "", kn=c["kn"], kt=c["kt"],
                  gamman=c["gamman"], tangential_damping=ratio, friction=c["friction"])


def tool_region(tool: ToolContact, beads: list[BeadParameters], region_id: str,
                fix_id: str = "tool", group: str = "all", contacts: bool = True) -> str:
    """Fibres in ``group`` touch the surface of LAMMPS region ``region_id`` (defined before).

    ``fix <fix_id> <group> wall/gran/region granular hooke ... region <region_id>``; the
    region may move (``region ... move``) and its velocity enters the friction.
    ``contacts`` keeps the per-bead contact array that :func:`overlap_monitor` reads.
    """
    return _tool_contact(tool, beads, fix_id, group, "wall/gran/region",
                         render_inline("wall_region", region_id=region_id), contacts)


def tool_plane(tool: ToolContact, beads: list[BeadParameters], axis: str,
               lo_m: float | None = None, hi_m: float | None = None, fix_id: str = "tool",
               group: str = "all", contacts: bool = True) -> str:
    """Flat walls normal to ``axis`` at ``lo_m`` and/or ``hi_m`` [m] (``fix wall/gran``)."""
    if axis not in ("x", "y", "z"):
        raise ValueError(f"axis must be 'x', 'y' or 'z', got {axis!r}")
    if lo_m is None and hi_m is None:
        raise ValueError("tool_plane needs lo_m or hi_m")
    where = render_inline("wall_plane", axis=axis,
                          lo="NULL" if lo_m is None else float(lo_m),
                          hi="NULL" if hi_m is None else float(hi_m))
    return _tool_contact(tool, beads, fix_id, group, "wall/gran", where, contacts)


def _overlap_families(model: BeadModel, contact_model: ContactModel,
                      beads: list[BeadParameters], d_min: float) -> str:
    """Overlap lines of the within-family law: each family's own pairs by distance, counted
    from the law's hard core (its pairs are meant to close to the packing limit, so only
    what passes the core is an overlap: 1 − r_min/r_core), crossings by force (templates
    overlap_pair_family[ies])."""
    lines, overlap = [], "v_fabmd_overlap_cross"
    k_cross = contact_model.crossing_stiffness_pa(beads)
    for i, family in enumerate(model.family_names, start=1):
        if not np.any(model.atom_types == i):
            continue
        core = contact_model.family_law(family).core_spacing_m(k_cross)
        lines.append(render("overlap_pair_family", i=i, core=core))
        overlap = f"ternary(v_fabmd_overlap_{i}>{overlap},v_fabmd_overlap_{i},{overlap})"
    if contact_model.crossing == "law":  # crossings too close to the law's core by design
        return render("overlap_pair_law_all", core=contact_model.crossing_law(beads)
                      .core_spacing_m)
    return render("overlap_pair_families", family_lines="\n".join(lines), overlap=overlap,
                  kn=fmt(contact_model.normal_stiffness_n_per_m(beads)), diameter=d_min)


def overlap_monitor(model: BeadModel, contact_model: ContactModel | None,
                    beads: list[BeadParameters], every: int = 100,
                    tool_fixes: tuple[str, ...] = (), file: str = OVERLAP_FILE) -> str:
    """Largest overlap/d between beads of different fibres (and with tools), every ``every`` steps.

    Fibre–fibre pairs: with one bead diameter d in the model, overlap/d = 1 − r_min/d over
    pairs in contact (exact); with several, the overlap follows from the largest normal
    contact force through k_n and is divided by the smallest diameter (an upper bound).
    With the within-family law, a family's own pairs count only what passes the law's hard
    core, 1 − r_min/r_core (they close to the packing limit by design), and crossings
    follow from the force as above.
    Tools: the fixes named in ``tool_fixes`` must be ``fix wall/gran[/region] ... contacts``
    (:func:`tool_region`, :func:`tool_plane`); overlap/d = (r − distance to the contact
    point)/(2r). Writes ``step pair_overlap_ratio tool_overlap_ratio`` to ``file`` for
    :func:`fabmd.protocols.common.overlap_summary` and stops the run (``guard_overlap``,
    cause "overlap") past ``contact_model.overlap_limit``. Costs one occasional neighbour
    list per sample.
    """
    pair = contact_model is not None
    if not pair and not tool_fixes:
        return "# no contact in this scene: no overlap monitor"
    if pair:
        d_min = float(model.diameters.min())
        if contact_model.within_family_law is not None:
            pair_lines = _overlap_families(model, contact_model, beads, d_min)
        elif np.ptp(model.diameters) <= 1e-9 * d_min:
            pair_lines = render("overlap_pair_distance", diameter=d_min)
        else:
            c = contact_model.pair_coefficients(beads)
            if contact_model.normal == "hooke":  # split contact: the softer pair bounds it
                formula = ("c_fabmd_contact_fmax/"
                           f"{fmt(contact_model.softest_normal_stiffness_n_per_m(beads))}")
                text = "F/k_n"
            else:  # F = Kn sqrt(R_eff) delta^1.5; the smallest R_eff gives the largest delta
                root = c["kn"] * math.sqrt(d_min / 4.0)
                formula = f"(c_fabmd_contact_fmax/{fmt(root)})^(2.0/3.0)"
                text = "(F/(K_n sqrt(R_eff)))^(2/3)"
            pair_lines = render("overlap_pair_force", force_to_overlap=text,
                                overlap_formula=formula, diameter=d_min)
    else:
        pair_lines = render_inline("overlap_pair_none")
    tool_lines = [render("overlap_tool", fix_id=f) for f in tool_fixes]
    tool_overlap = "0.0"
    for f in tool_fixes:
        c = f"c_fabmd_tool_max_{f}"
        tool_overlap = c if tool_overlap == "0.0" else \
            f"ternary({c}>{tool_overlap},{c},{tool_overlap})"
    tool_lines.append(render_inline("overlap_tool_max", tool_overlap=tool_overlap))
    warning = contact_model.overlap_warning if pair else TOOL_OVERLAP_WARNING
    limit = contact_model.overlap_limit if pair else TOOL_OVERLAP_LIMIT
    return render("overlap_monitor", every=int(every), file=file, warning=warning, limit=limit,
                  pair_lines=pair_lines, tool_lines="\n".join(tool_lines),
                  overlap="ternary(v_fabmd_pair_overlap>v_fabmd_tool_overlap,"
                          "v_fabmd_pair_overlap,v_fabmd_tool_overlap)")
