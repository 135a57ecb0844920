"""The knobs of a calibration (:mod:`fabmd.protocols.calibrate`): which strain serves which
target, its range and first step, and every check of the targets that needs no LAMMPS
(families the fabric has, one target per family, a free thickness below the loose one, a
cell the platens can close on).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from ..errors import InputError
from ..model.bead_model import BeadModel
from ..results.measure import thickness_m
from .calibrate_search import STRAIN_LIMIT, Knob, on_grid

#: the relative change of a family's loose section height a crimp knob may try
#: (``crimp_by = "loose_height"``): a half to one and a half times the scene's
LOOSE_HEIGHT_RANGE = (-0.5, 0.5)

if TYPE_CHECKING:
    from .calibrate import CrimpTargets
    from .crimp import Crimp


def default_thickness_families(model: BeadModel) -> tuple[str, ...]:
    return ("binder",) if "binder" in model.family_names else tuple(model.family_names)


def check_targets(model: BeadModel, targets: CrimpTargets, base: Crimp,
                  fams: tuple[str, ...], compaction=None):
    """Every check of :func:`~fabmd.protocols.calibrate.calibrate` that needs no LAMMPS:
    (knobs searched, targets only reported, the compaction that measures a thickness
    under pressure or None).

    Raises:
        InputError: the first impossible target (module docstring).
    """
    knobs, uncontrolled = make_knobs(model, targets, base, fams)
    measure = _compaction(targets, compaction)
    if measure is not None:
        measure.input_text(model)  # a cell the platens can close on
    return knobs, uncontrolled, measure


def _compaction(targets: CrimpTargets, compaction):
    """The compaction that measures the thickness at the target's pressure (or None)."""
    if targets.at_pressure_pa is None:
        return None
    from .compaction import Compaction

    p = targets.at_pressure_pa
    return dataclasses.replace(compaction or Compaction(), max_pressure_pa=p,
                               datasheet_pressure_pa=p, unload=False)


def height_start(targets: CrimpTargets, group: tuple[str, ...]) -> float:
    """The relative loose height a knob of ``group`` starts at (0: the scene's); the
    families of a tied group start at one height."""
    starts = {targets.loose_height_start.get(fam, 0.0) for fam in group}
    if len(starts) > 1:
        raise InputError(f"crimp.loose_height_start_m: {', '.join(group)} are drawn alike "
                         f"and their loose height moves as one, so they start at one "
                         f"height; got {sorted(starts)} (relative to the yarns' height_m)")
    return on_grid(starts.pop())


def _bounds(model: BeadModel, targets: CrimpTargets, fams: tuple[str, ...],
            kind: str) -> tuple[float, float]:
    if targets.strain_range is not None:
        return (float(targets.strain_range[0]), float(targets.strain_range[1]))
    loose = (model.info or {}).get("crimp") or {}
    crimps = [loose[f] for f in fams if isinstance(loose.get(f), int | float)]
    if kind == "tension" or not crimps:
        return (-STRAIN_LIMIT, STRAIN_LIMIT)
    return (on_grid(-min(min(crimps), STRAIN_LIMIT)), STRAIN_LIMIT)


def make_knobs(model: BeadModel, targets: CrimpTargets, base: Crimp,
               fams: tuple[str, ...]) -> tuple[list[Knob], list[Knob]]:
    """The knobs the calibration searches and the targets it can only report (their
    family's expansion serves the thickness); impossible targets raise InputError."""
    from .crimp_tension import target_tensions_n, yarn_axial_stiffness_n

    tensions = {} if targets.target_tension is None else target_tensions_n(
        targets.target_tension, model, key="calibrate.target_tension")
    unknown = (set(fams) | set(targets.crimp_pct)) - set(model.family_names)
    if unknown:
        raise InputError(f"calibrate names families {sorted(unknown)}; the fabric has "
                         f"{list(model.family_names)}")
    by_height = targets.crimp_by == "loose_height"
    both = sorted(set(targets.crimp_pct) & set(tensions) - set(fams))
    if both and not by_height:
        raise InputError(f"calibrate.crimp_pct and calibrate.target_tension both name "
                         f"{both}: a family's expansion is one number and serves one "
                         f"target (the other follows from it); give one of them, or "
                         f"reach the crimp by the loose height (calibrate.crimp_by = "
                         f"\"loose_height\")")
    knobs: list[Knob] = []
    uncontrolled: list[Knob] = []
    if targets.thickness_m is not None:
        loose = thickness_m(model)
        if targets.at_pressure_pa is None and targets.thickness_m >= loose:
            raise InputError(f"calibrate.thickness_m = {targets.thickness_m:.4g} m is not "
                             f"below the loose fabric's thickness {loose:.4g} m: crimping "
                             f"only compacts; build a thicker loose fabric or lower the "
                             f"target")
        bounds = _bounds(model, targets, fams, "thickness")
        start = min((base.expansion.get(f, 0.0) for f in fams), default=0.0)
        start = start if start < 0 else -0.03
        knob = Knob("thickness", "thickness", fams, targets.thickness_m,
                    targets.thickness_tolerance * targets.thickness_m, +1, bounds,
                    on_grid(min(max(start, bounds[0]), bounds[1])))
        if by_height and tensions:  # the expansions serve the tension search
            knob.acts_on = "reported"
        (uncontrolled if knob.acts_on == "reported" else knobs).append(knob)
    thickness_fams = set(fams) if targets.thickness_m is not None else set()
    tied = _tied_groups(targets) if by_height else []
    for group in tied:  # one loose height for the group, each family's crimp reported
        target = float(targets.crimp_pct[group[0]])
        knobs.append(Knob("crimp:" + "+".join(group), "crimp", group, target,
                          targets.crimp_tolerance_pct, +1, LOOSE_HEIGHT_RANGE,
                          height_start(targets, group), first_step=0.1,
                          acts_on="loose_height"))
        uncontrolled.extend(Knob(f"crimp:{fam}", "crimp", (fam,), target,
                                 targets.crimp_tolerance_pct, +1, (-1.0, 1.0), 0.0,
                                 acts_on="tied_height") for fam in group)
    in_groups = {fam for group in tied for fam in group}
    for fam, crimp_target in targets.crimp_pct.items():
        if fam in in_groups:
            continue
        if by_height:  # the loose section, not the expansion: never taken by the thickness
            knobs.append(Knob(f"crimp:{fam}", "crimp", (fam,), float(crimp_target),
                              targets.crimp_tolerance_pct, +1, LOOSE_HEIGHT_RANGE,
                              height_start(targets, (fam,)), first_step=0.1,
                              acts_on="loose_height"))
            continue
        bounds = _bounds(model, targets, (fam,), "crimp")
        knob = Knob(f"crimp:{fam}", "crimp", (fam,), float(crimp_target),
                    targets.crimp_tolerance_pct, +1, bounds,
                    on_grid(min(max(base.expansion.get(fam, 0.0), bounds[0]), bounds[1])),
                    first_step=0.01)
        (uncontrolled if fam in thickness_fams else knobs).append(knob)
    for fam, newtons in sorted(tensions.items()):
        if by_height:  # the crimp stage's own tension search reaches it in every run
            uncontrolled.append(Knob(f"tension:{fam}", "tension", (fam,), newtons,
                                     targets.tension_tolerance * newtons, -1, (-1.0, 1.0),
                                     0.0, acts_on="crimp_search"))
            continue
        bounds = _bounds(model, targets, (fam,), "tension")
        stiffness = yarn_axial_stiffness_n(model, fam)
        knob = Knob(f"tension:{fam}", "tension", (fam,), newtons,
                    targets.tension_tolerance * newtons, -1, bounds,
                    on_grid(min(max(base.expansion.get(fam, 0.0), bounds[0]), bounds[1])),
                    first_step=min(max(newtons / stiffness, 2e-3), 0.03))
        (uncontrolled if fam in thickness_fams else knobs).append(knob)
    return knobs, uncontrolled


def _tied_groups(targets: CrimpTargets) -> list[tuple[str, ...]]:
    """``targets.tied_heights``' groups of two or more families with crimp targets, each
    with one target for all (refused otherwise)."""
    groups = []
    for group in targets.tied_heights:
        fams = tuple(f for f in group if f in targets.crimp_pct)
        if len(fams) < 2:
            continue
        if len({float(targets.crimp_pct[f]) for f in fams}) > 1:
            raise InputError(f"calibrate.tied_heights {list(fams)}: one loose height for "
                             f"families with different crimp targets "
                             f"({ {f: targets.crimp_pct[f] for f in fams} })")
        groups.append(fams)
    return groups

