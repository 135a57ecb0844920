"""Crimp to a stated yarn tension: adjust the rest-length change per family until the
crimped fabric carries the target tension.

A target is given per family (or one for all) as N per yarn (a number or ``"5 N"``)
or as ``"1 cN/tex"`` (the model must know the family's linear density). Each family's
tension after crimp falls, in the large, as its expansion α·ΔT rises — but not always
monotonically: with the within-family law the plain-weave cell snaps flat between −4.5
and −6 % and its tension falls to ≈ 0 before the straightened fibres stretch
(benchmarks/RESULTS.md, "Nonlinear within-family law"). The search
(:func:`next_expansion`, each family on its own expansion, all families in every run)
starts from the scene's expansion with a first step from the yarn's axial stiffness
(ΔT_yarn ≈ −n_fibres·E·A·Δ(α·ΔT), the stiffest the response can be); while every
tension tried lies on one side of the target it goes on outwards from the furthest
expansion tried — secant steps where the tension so far moves the way it should (at most
4× the last step), steps of twice the last one where the response has turned back (a
snap): a local peak short of the target is not taken for the answer; once two neighbouring
expansions bracket the target, false position inside the bracket (kept in its middle
three fifths, :func:`~fabmd.protocols.calibrate_search.inside_bracket`, the rule of
``fabmd calibrate``), until every family is within ``tolerance`` of its target (default
5 %). **A root on a falling branch is not taken**: each run within tolerance is followed
by a probe with :data:`PROBE_STRAIN` (0.1 %) more shrink, in a temporary folder; where a
family's tension falls there (by more than :data:`PROBE_NOISE`), more shrink slackens the
fabric — it is about to snap into a flatter state, and the target is met again past the
snap — so the search goes on from the probe into more shrink, lists the root in
``tension_search.rejected_roots`` (with both thicknesses) and warns that the target has more
than one root. The example's cell at 1 cN/tex has a thick root at s/d 0.5 and 0.25 that is
gone at s/d 0.125 (the most its search saw before the snap was 0.78 cN/tex) and a flat
one at all three whose shear converges (benchmarks/RESULTS.md "One drawing at three bead
spacings, and the crimp's two states"). The probe sees only a fall within 0.1 % of shrink:
it does not make the state unique — where the tension lingers near the target over a range
of shrink while the fabric thins (the example at s/d 0.25 drawn 0.64 mm: 6.0–7.0 N from
−4.55 to −4.69 % while 0.864 → 0.785 mm thick), a root on a rising stretch of it is taken
(RESULTS "The tension search takes the root past the snap"). The probe's slopes say how
loosely the target pins the state: over the shrink in which the tension stays within
tolerance the thickness moves by ``tension_search.thickness_spread_m``, and a spread over
2 % of the thickness (:data:`THICKNESS_SPREAD`) is warned about — state the thickness
instead. A probe costs one crimp run per root met. Where no crossing exists — the expansion
limit reached on the same side of the target, or the tension jumping across it between two
expansions closer than 2e-5 — the crimp raises
:class:`~fabmd.errors.CalibrationNotReached` naming the family's expansion, the target,
why, and every expansion and tension seen. After ``max_runs`` (16) crimp runs (probes
counted) it warns and keeps the closest. Every run overwrites the crimp folder; the last one stays
(the closest, rerun where needed), and its ``summary.json`` → ``tension_search`` lists the
expansions tried and the tensions they gave.
A family also given ``target_crimp_pct = "auto"`` never shrinks beyond that strain (its
loose crimp less the margin, :mod:`fabmd.protocols.crimp_target`): a tension the fabric only
carries with the yarns pulled straighter is not reached, and the search says so
(``shrink_bound``, ``at_bound``) instead of pulling them into zig-zags.
"""

from __future__ import annotations

import dataclasses
import re
import shutil
import warnings
from pathlib import Path

import numpy as np

from .. import units
from ..engine import mpi
from ..errors import CalibrationNotReached, InputError
from ..model.bead_model import BeadModel
from ..results.folder import write_json
from .calibrate_search import STRAIN_RESOLUTION, inside_bracket

_CN_PER_TEX = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*cN/tex\s*$")


def check_target_tension(target, key: str = "crimp.target_tension") -> None:
    """Validate ``Crimp.target_tension`` without a model (units, sign, shape); ``key``
    is its name in messages."""
    values = target.items() if isinstance(target, dict) else [("", target)]
    for fam, value in values:
        name = f"{key}{'.' + fam if fam else ''}"
        match = _CN_PER_TEX.match(value) if isinstance(value, str) else None
        number = float(match.group(1)) if match else units.quantity(value, "force", name)
        if not number > 0:
            raise InputError(f"{name} must be > 0 (N per yarn or cN/tex), got {value!r}")


def target_tensions_n(target, model: BeadModel,
                      key: str = "crimp.target_tension") -> dict[str, float]:
    """The target tension per family in N per yarn, from ``Crimp.target_tension`` (``key``:
    its name in messages)."""
    if not isinstance(target, dict):
        target = {fam: target for fam in model.family_names}
    unknown = set(target) - set(model.family_names)
    if unknown:
        raise InputError(f"{key} names families {sorted(unknown)} that the "
                         f"fabric does not have (it has {list(model.family_names)})")
    families = (model.info or {}).get("families", {})
    out = {}
    for fam, value in target.items():
        name = f"{key}.{fam}"
        match = _CN_PER_TEX.match(value) if isinstance(value, str) else None
        if match:
            tex = families.get(fam, {}).get("linear_density_tex")
            if not tex:
                raise InputError(f"{name} = {value!r} needs the yarn's linear density, which "
                                 f"this model does not carry; give the tension in N per yarn")
            newtons = float(match.group(1)) * tex / 100.0
        else:
            newtons = units.quantity(value, "force", name)
        if not newtons > 0:
            raise InputError(f"{name} must be > 0, got {value!r}")
        out[fam] = newtons
    return out


def yarn_axial_stiffness_n(model: BeadModel, family: str) -> float:
    """Σ E·A over the fibres of a yarn of ``family`` (mean over its yarns) [N]; yarns of
    one family may differ (yarn spec overrides)."""
    fibre = model.fibre_bond_mask()
    ea_of_type = np.array([bt.axial_stiffness_n for bt in model.bond_type_table])
    fibre_ea = np.zeros(len(model.fibre_yarn) + 1)
    fibre_ea[model.fibre_ids[model.bonds[fibre, 0]]] = ea_of_type[model.bond_types[fibre] - 1]
    yarn_ea = np.bincount(model.fibre_yarn, weights=fibre_ea[1:],
                          minlength=len(model.yarns) + 1)
    yarns = [k + 1 for k, y in enumerate(model.yarns) if y.family == family]
    return float(yarn_ea[yarns].mean())


#: the largest shrink or expansion the tension search tries [-]
EXPANSION_LIMIT = 0.45
#: a bracket narrower than this (in expansion) is not refined further: the tension jumps
MIN_BRACKET = 2 * STRAIN_RESOLUTION


def crimp_to_tension(crimp, model: BeadModel, out: Path | None, engine=None,
                     overwrite: bool = False, tolerance: float = 0.05, max_runs: int = 16,
                     quiet: bool = False):
    """Run ``crimp`` (a :class:`~fabmd.protocols.crimp.Crimp` with ``target_tension``)
    until each family's mean yarn tension is within ``tolerance`` of its target (module
    docstring).

    Raises:
        CalibrationNotReached: a family's expansion cannot give its target (no crossing
            in the expansion range, or a jump across it); the crimp folder holds the
            closest run and its ``tension_search``.
    """
    targets = target_tensions_n(crimp.target_tension, model)
    fams = sorted(targets)
    stiffness = {f: yarn_axial_stiffness_n(model, f) for f in fams}
    bound = shrink_bounds(crimp, model, fams)
    expansion = {f: float(max(crimp.expansion.get(f, 0.0), bound.get(f, -1.0)))
                 for f in fams}
    # the largest expansion still searched per family: past a rejected root, its probe
    limit = {f: EXPANSION_LIMIT for f in fams}
    tried: list[dict] = []
    refused: list[str] = []
    # the crimp's own, where given; else the target per virtual fibre
    settle = crimp.settle_force_n or settle_force_n(model, targets)
    in_folder = None  # the run whose folder ``out`` holds
    while len(tried) < max_runs:
        stage = _stage(crimp, fams, expansion, settle)
        result = stage.run(model, out, engine=engine, overwrite=overwrite or bool(tried),
                           quiet=True)
        entry = _sample(result, expansion, fams, targets)
        tried.append(entry)
        in_folder = (entry, result)
        if entry["largest_relative_error"] <= tolerance:
            falling = _probe(entry, stage, model, engine, fams, targets, tried, tolerance)
            if not falling:
                break
            for f in falling:  # a metastable root: search on past its probe
                limit[f] = entry["probe"]["expansion"][f]
        new = {}
        for f in fams:
            if abs(entry["yarn_tension_n"][f] / targets[f] - 1) <= tolerance \
                    and f not in entry.get("rejected", ()):  # this one is there: stay
                new[f] = expansion[f]
                continue
            seen = [(t["expansion"][f], t["yarn_tension_n"][f]) for t in tried
                    if t["expansion"][f] <= limit[f]]
            new[f], why = next_expansion(
                seen, targets[f], tolerance, stiffness[f],
                first_step=PROBE_STRAIN if limit[f] < EXPANSION_LIMIT else None)
            if new[f] is None:
                refused.append(f"crimp.target_tension.{f} = {targets[f]:.4g} N cannot be "
                               f"reached with crimp.expansion.{f}: {why}")
            elif f in bound:  # "auto": never shrink past the loose crimp less the margin
                new[f] = max(new[f], bound[f])
        if refused or new == expansion:  # nothing left to try (every family held at its
            break  # shrink bound, or no crossing)
        expansion = new
    # the answer: the closest run whose root was not rejected (probes are not candidates)
    runs = [t for t in tried if "probe_of" not in t]
    candidates = [t for t in runs if not t.get("rejected")] or runs
    chosen = min(candidates, key=lambda t: t["largest_relative_error"])
    error = chosen["largest_relative_error"]
    reached = error <= tolerance and not chosen.get("rejected")
    last = runs[-1]
    at_bound = sorted(f for f in bound if last["expansion"][f] <= bound[f]
                      and last["yarn_tension_n"][f] < targets[f])
    search = {"targets_n": targets, "tolerance": tolerance, "runs": tried,
              "reached": reached, "shrink_bound": bound or None,
              "at_bound": at_bound, "probe_strain": PROBE_STRAIN,
              "rejected_roots": [_root_record(t) for t in runs if t.get("rejected")],
              # the thickness the tolerance leaves open at the answer (its probe's slopes)
              "thickness_spread_m": (chosen.get("probe") or {}).get("thickness_spread_m")}
    if refused:
        search["reason"] = "; ".join(refused)
    result = in_folder[1]
    if chosen is not in_folder[0]:  # rerun the chosen one, so that the folder holds it
        result = _stage(crimp, fams, chosen["expansion"], settle).run(
            model, out, engine=engine, overwrite=True, quiet=True)
    result.summary["tension_search"] = search
    if mpi.is_root():
        write_json(Path(result.run_dir) / "summary.json", result.summary)
        if not quiet:
            from .crimp_balance import warn_interchange

            warn_interchange(result.run_dir, result.summary, stacklevel=4)
    if not quiet and mpi.is_root():
        for message in straight_warnings(result.summary):
            warnings.warn(message, UserWarning, stacklevel=3)
    if search["rejected_roots"] and not quiet and mpi.is_root():
        warnings.warn(_two_roots_message(search["rejected_roots"], chosen, reached),
                      stacklevel=3)
    loose = _loose_pin_message(chosen, tolerance) if reached else None
    if loose and not quiet and mpi.is_root():
        warnings.warn(loose, stacklevel=3)
    if refused:
        raise CalibrationNotReached(f"crimp: {search['reason']} (the crimp folder holds "
                                    f"the closest run, {100 * error:.1f} % off)",
                                    run_dir=result.run_dir)
    if not reached:
        why = (f"; {', '.join(at_bound)} at the \"auto\" shrink bound (more tension would "
               f"pull them straighter than the margin allows)" if at_bound else "")
        warnings.warn(f"crimp: the yarn tension did not reach its target within "
                      f"{100 * tolerance:g} % in {len(tried)} runs (closest: "
                      f"{100 * error:.1f} % off){why}; see summary.json tension_search",
                      stacklevel=3)
    return result


#: a crimp [%] below which a family's yarns are taken as pulled straight
STRAIGHT_CRIMP_PCT = 0.1


def straight_warnings(summary: dict) -> list[str]:
    """The shrink warnings of a searched crimp (``summary["shrink_warnings"]``) for the
    families whose crimp it measured below :data:`STRAIGHT_CRIMP_PCT`. A shrink beyond the
    loose crimp is warned of where the search ends there and the yarns came out straight,
    not for its trial runs: the example's search starts at -6.8 % on a cell drawn 0.57 mm
    high (loose crimp 5.27 %) and ends at -3.95 % with 1.5 % crimp, and warning of its first
    run told the demo's user that the yarns end straight."""
    crimp = (summary.get("crimped") or {}).get("crimp_pct") or {}
    out = []
    for message in summary.get("shrink_warnings") or []:
        fam = message.removeprefix("crimp.expansion.").split(" ", 1)[0]
        measured = crimp.get(fam)
        if measured is None or measured < STRAIGHT_CRIMP_PCT:
            out.append(message if measured is None else
                       f"{message} (crimped: {measured:.3g} %)")
    return out


#: how much more shrink the probe past a root applies [-]: the example's cell at s/d 0.5
#: peaks at -4.43 % and is 19 % slacker at -4.50 % (benchmarks/RESULTS.md "One drawing at
#: three bead spacings, and the crimp's two states")
PROBE_STRAIN = 1e-3
#: a probe whose tension is lower than its root's by more than this (relative) rejects
#: the root: the tension at rest repeats within 2 % between halts 100x apart (same section)
PROBE_NOISE = 0.02


def _sample(result, expansion: dict[str, float], fams, targets: dict[str, float]) -> dict:
    """One run of the search as recorded in ``tension_search.runs``."""
    got = {f: result.summary["yarn_tension"][f]["yarn_n"] for f in fams}
    return {"expansion": dict(expansion), "yarn_tension_n": got,
            "thickness_m": (result.summary.get("crimped") or {}).get("thickness_m"),
            "largest_relative_error": max(abs(got[f] / targets[f] - 1) for f in fams)}


def _probe(root: dict, stage, model: BeadModel, engine, fams, targets, tried,
           tolerance: float) -> list[str]:
    """Crimp once more with :data:`PROBE_STRAIN` more shrink than ``root`` (a run within
    tolerance), in a temporary folder; returns the families whose tension fell there (by
    more than :data:`PROBE_NOISE`): for them ``root`` lies on a branch that more shrink
    slackens — the fabric is about to snap into a flatter state, and the same tension is
    met again past the snap. Such a root is metastable: at 1 cN/tex the example's thick
    state (drawn 0.621 mm) exists at s/d 0.5 and 0.25 but not at 0.125 (the most its
    search saw before the snap was 0.78 cN/tex), while the flat one exists at all three."""
    from ..results.folder import prepare_run_folder

    expansion = {f: root["expansion"][f] - PROBE_STRAIN for f in fams}
    folder = prepare_run_folder(None, prefix="tension-probe")
    try:
        probe = dataclasses.replace(stage, expansion={**stage.expansion, **expansion})
        result = probe.run(model, folder, engine=engine, overwrite=True, quiet=True,
                           figures=False)
        entry = _sample(result, expansion, fams, targets)
    finally:
        mpi.barrier()  # every rank has read the crimped model back from the folder
        if mpi.is_root():
            shutil.rmtree(folder, ignore_errors=True)
    entry["probe_of"] = len(tried) - 1
    tried.append(entry)
    root["probe"] = {"expansion": expansion, "yarn_tension_n": entry["yarn_tension_n"],
                     "thickness_m": entry["thickness_m"],
                     "thickness_spread_m": thickness_spread_m(root, entry, fams, targets,
                                                              tolerance)}
    falling = [f for f in fams
               if entry["yarn_tension_n"][f] < (1 - PROBE_NOISE) * root["yarn_tension_n"][f]]
    if falling:
        root["rejected"] = falling
    return falling


def thickness_spread_m(root: dict, probe: dict, fams, targets: dict[str, float],
                       tolerance: float) -> float | None:
    """How much thickness [m] the tension target leaves open at ``root``: over the shrink
    in which a family's tension stays within ``tolerance`` of its target (2·tol·T over
    the slope dT/dε that the ``probe``, :data:`PROBE_STRAIN` further, measured) the
    thickness moves by its own slope dh/dε; the largest over ``fams``. None where a
    thickness is not known or the tension did not rise."""
    if root["thickness_m"] is None or probe["thickness_m"] is None:
        return None
    dh = abs(probe["thickness_m"] - root["thickness_m"]) / PROBE_STRAIN
    spreads = []
    for f in fams:
        slope = (probe["yarn_tension_n"][f] - root["yarn_tension_n"][f]) / PROBE_STRAIN
        if slope > 0:
            spreads.append(dh * 2 * tolerance * targets[f] / slope)
    return max(spreads) if spreads else None


#: a root whose tension tolerance leaves the thickness open by more than this share of it
#: is warned about: the example's roots on steep branches leave 0.01-1.2 % (the 3D
#: example's binders 0.3 %), two on the plateau of its s/d 0.25 cell drawn 0.64 and
#: 0.622 mm 3.8 and 7.5 % (RESULTS "The tension search takes the root past the snap")
THICKNESS_SPREAD = 0.02


def _loose_pin_message(chosen: dict, tolerance: float) -> str | None:
    """The warning that the tension target pins the thickness only loosely (or None)."""
    probe = chosen.get("probe") or {}
    spread = probe.get("thickness_spread_m")
    if spread is None or not spread > THICKNESS_SPREAD * chosen["thickness_m"]:
        return None
    return (f"crimp: the target tension pins the fabric's state only loosely: here "
            f"{PROBE_STRAIN:.0e} more shrink changes the tension by "
            f"{_n_change(chosen, probe)} while the cell thins from "
            f"{_mm(chosen['thickness_m'])} to {_mm(probe['thickness_m'])}, so within the "
            f"{100 * tolerance:g} % tolerance the thickness is open by about "
            f"{1e3 * spread:.3f} mm ({100 * spread / chosen['thickness_m']:.1f} %): another "
            f"start of the search can end elsewhere. State the thickness instead (fabmd "
            f"calibrate, [calibrate] thickness_m) or give a tighter tolerance; "
            f"summary.json tension_search.thickness_spread_m")


def _n_change(root: dict, probe: dict) -> str:
    return ", ".join(f"{probe['yarn_tension_n'][f] - t:+.3g} N ({f})"
                     for f, t in root["yarn_tension_n"].items())


def _root_record(run: dict) -> dict:
    """A rejected root as ``tension_search.rejected_roots`` lists it."""
    return {"expansion": run["expansion"], "yarn_tension_n": run["yarn_tension_n"],
            "thickness_m": run["thickness_m"], "families": run["rejected"],
            "probe": run["probe"]}


def _mm(thickness_m) -> str:
    return "?" if thickness_m is None else f"{1e3 * thickness_m:.3f} mm"


def _two_roots_message(rejected: list[dict], chosen: dict, reached: bool) -> str:
    """The warning that the target tension was met more than once."""
    first = rejected[0]
    fam = first["families"][0]
    took = (f"took the root at {chosen['expansion'][fam]:+.4f} "
            f"({chosen['yarn_tension_n'][fam]:.4g} N, {_mm(chosen['thickness_m'])} thick), "
            f"where more shrink pulls harder" if reached else
            "found no root past it within its runs (see summary.json tension_search)")
    return (f"crimp: the target tension of {', '.join(first['families'])} is met at more "
            f"than one shrink: at {first['expansion'][fam]:+.4f} the cell carries "
            f"{first['yarn_tension_n'][fam]:.4g} N per yarn and is "
            f"{_mm(first['thickness_m'])} thick, but {PROBE_STRAIN:.0e} more shrink "
            f"slackens it to {first['probe']['yarn_tension_n'][fam]:.4g} N "
            f"({_mm(first['probe']['thickness_m'])}): that state is about to snap flatter. "
            f"The search {took}.")


def shrink_bounds(crimp, model: BeadModel, fams) -> dict[str, float]:
    """The lowest strain per family of ``fams`` that ``target_crimp_pct = "auto"`` allows
    (its loose crimp less the margin); families without "auto" are not bounded here."""
    auto = {f: v for f, v in crimp.target_crimp_pct.items() if isinstance(v, str)
            and f in fams}
    if not auto:
        return {}
    from .crimp_target import derive_expansion

    derived = derive_expansion(model, auto, crimp.auto_margin_pct)
    return {f: derived[f]["expansion"] for f in auto}


def settle_force_n(model: BeadModel, targets_n: dict[str, float]) -> float:
    """The smallest target tension per virtual fibre [N] (a yarn's target over its
    fibres): what each run of the search is judged at rest against, so that it stops
    once the tension it reports is the one the fabric keeps."""
    per_yarn = np.bincount(model.fibre_yarn, minlength=len(model.yarns) + 1)
    out = []
    for fam, target in targets_n.items():
        counts = [per_yarn[k + 1] for k, y in enumerate(model.yarns) if y.family == fam]
        out.append(target / max(float(np.mean(counts)) if counts else 1.0, 1.0))
    return float(min(out))


def _stage(crimp, fams, expansion: dict[str, float], settle: float):
    """One run of the search: the tension families at ``expansion``, their "auto" bound
    (kept by the search) taken out of the crimp targets, judged at rest against
    ``settle`` (N per virtual fibre)."""
    return dataclasses.replace(
        crimp, target_tension=None, expansion={**crimp.expansion, **expansion},
        settle_force_n=settle,
        target_crimp_pct={f: v for f, v in crimp.target_crimp_pct.items() if f not in fams})


def next_expansion(seen: list[tuple[float, float]], target_n: float, tolerance: float,
                   stiffness_n: float, first_step: float | None = None
                   ) -> tuple[float | None, str]:
    """The next expansion α·ΔT [-] for one family from the (expansion, yarn tension [N])
    pairs ``seen`` so far (latest last), or (None, why) where no expansion within
    ±:data:`EXPANSION_LIMIT` can give ``target_n`` [N] within ``tolerance`` (relative).

    ``stiffness_n``: the yarn's axial stiffness n·E·A [N], for the first step (or
    ``first_step``, where given: past a rejected root, the probe's strain). The rule
    (module docstring): inside a bracket false position; else outwards from the furthest
    expansion tried, secant where the tension so far moves the right way, doubling the
    step where it turned back."""
    by_expansion = dict(seen)  # an expansion tried twice: its latest tension
    pts = sorted(by_expansion.items())
    err = [t - target_n for _, t in pts]
    numbers = ", ".join(f"{e:+.4f} -> {t:.4g} N" for e, t in pts)
    brackets = [i for i in range(len(pts) - 1) if err[i] * err[i + 1] < 0]
    if brackets:
        latest = seen[-1][0]  # the bracket next to the latest run
        i = min(brackets, key=lambda j: min(abs(pts[j][0] - latest),
                                            abs(pts[j + 1][0] - latest)))
        (e0, t0), (e1, t1) = pts[i], pts[i + 1]
        if e1 - e0 < MIN_BRACKET:
            return None, (f"the tension jumps from {t0:.4g} N at {e0:+.4f} to {t1:.4g} N "
                          f"at {e1:+.4f}, across the target: no expansion in between gives "
                          f"it within {100 * tolerance:g} % (expansion -> tension seen: "
                          f"{numbers})")
        return inside_bracket(e0, err[i], e1, err[i + 1]), ""
    below = err[0] < 0  # every tension on one side: below needs more shrink
    direction = -1 if below else 1
    k = 0 if below else len(pts) - 1  # the furthest expansion tried that way
    e_far, t_far = pts[k]
    if len(pts) == 1:
        step = first_step or abs(err[k]) / stiffness_n
    else:
        e_near, t_near = pts[1] if below else pts[-2]
        gap = abs(e_far - e_near)
        slope = (t_far - t_near) / (e_far - e_near)
        closest = min(range(len(pts)), key=lambda j: abs(err[j]))
        if slope < 0 and closest == k:  # so far the tension moves the way it should
            step = min(abs(err[k] / slope), 4 * gap)
        else:  # it turned back (a snap): go on outwards, not back to a local peak
            step = 2 * gap
    new = min(max(e_far + direction * step, -EXPANSION_LIMIT), EXPANSION_LIMIT)
    if new != e_far:
        return new, ""
    way = "shrink" if below else "expansion"
    side = "below" if below else "above"
    peak = max(pts, key=lambda p: p[1]) if below else min(pts, key=lambda p: p[1])
    turned = (f"; not monotone: {'the highest' if below else 'the lowest'} tension, "
              f"{peak[1]:.4g} N, came at {peak[0]:+.4f}" if peak[0] != e_far else "")
    return None, (f"the tension stays {side} the target up to the {way} limit "
                  f"{e_far:+.4f} ({t_far:.4g} N there){turned} (expansion -> tension seen: "
                  f"{numbers})")
