"""Crimp to a stated yarn tension: adjust the rest-length change per family until the
crimped fabric carries the target tension.

A target is given per family (or one for all) as N per yarn (a number or ``"5 N"``)
or as ``"1 cN/tex"`` (the model must know the family's linear density). Each family's
tension after crimp falls as its expansion α·ΔT rises; the search starts from the
scene's expansion, takes a first step with the yarn's axial stiffness
(ΔT_yarn ≈ −n_fibres·E·A·Δ(α·ΔT), the stiffest the response can be) and then secant
steps (bisection once the target is bracketed and a secant step would leave the
bracket), all families at once, until every family is within ``tolerance`` of its target
(default 5 %) or ``max_runs`` (8) crimp runs are spent (then it warns and keeps the
closest). Every run overwrites the crimp folder; the last one stays, and its
``summary.json`` → ``tension_search`` lists the expansions tried and the tensions they
gave. A family also given ``target_crimp_pct = "auto"`` never shrinks beyond that
strain (its loose crimp less the margin, :mod:`fabmd.protocols.crimp_target`): a tension
the fabric only carries with the yarns pulled straighter is not reached, and the search
says so (``shrink_bound``, ``at_bound``) instead of pulling them into zig-zags.
"""

from __future__ import annotations

import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np

from .. import units
from ..engine import mpi
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..results.folder import write_json

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


def crimp_to_tension(crimp, model: BeadModel, out: Path | None, engine=None,
                     overwrite: bool = False, tolerance: float = 0.05, max_runs: int = 8):
    """Run ``crimp`` (a :class:`~fabmd.protocols.crimp.Crimp` with ``target_tension``)
    until each family's mean yarn tension is within ``tolerance`` of its target."""
    targets = target_tensions_n(crimp.target_tension, model)
    fams = sorted(targets)
    stiffness = {f: yarn_axial_stiffness_n(model, f) for f in fams}
    bound = shrink_bounds(crimp, model, fams)
    expansion = {f: float(max(crimp.expansion.get(f, 0.0), bound.get(f, -1.0)))
                 for f in fams}
    tried: list[dict] = []
    best = None
    for run in range(max_runs):
        stage = _stage(crimp, fams, expansion)
        result = stage.run(model, out, engine=engine, overwrite=overwrite or run > 0)
        got = {f: result.summary["yarn_tension"][f]["yarn_n"] for f in fams}
        error = max(abs(got[f] / targets[f] - 1) for f in fams)
        tried.append({"expansion": dict(expansion), "yarn_tension_n": got,
                      "largest_relative_error": error})
        if best is None or error <= best[0]:
            best = (error, result)
        if error <= tolerance:
            break
        step = {}
        for f in fams:
            if len(tried) >= 2 and tried[-1]["expansion"][f] != tried[-2]["expansion"][f]:
                de = tried[-1]["expansion"][f] - tried[-2]["expansion"][f]
                dt = tried[-1]["yarn_tension_n"][f] - tried[-2]["yarn_tension_n"][f]
                slope = dt / de if dt / de < 0 else -stiffness[f]  # secant, if it falls
            else:
                slope = -stiffness[f]
            step[f] = (targets[f] - got[f]) / slope
        new = {}
        for f in fams:
            e = float(np.clip(expansion[f] + step[f], bound.get(f, -0.45), 0.45))
            # once the target is bracketed (tension falls as the expansion rises), stay
            # inside the bracket: bisect where the secant would leave it (the response
            # turns steep where slack yarns go taut)
            below = [r["expansion"][f] for r in tried if r["yarn_tension_n"][f] < targets[f]]
            above = [r["expansion"][f] for r in tried if r["yarn_tension_n"][f] > targets[f]]
            if below and above:
                lo, hi = max(above), min(below)  # expansions: more tension at lo
                if not lo < e < hi:
                    e = 0.5 * (lo + hi)
            new[f] = e
        if new == expansion:  # every family held at its shrink bound: nothing left to try
            break
        expansion = new
    error, result = best
    at_bound = sorted(f for f in bound if tried[-1]["expansion"][f] <= bound[f]
                      and tried[-1]["yarn_tension_n"][f] < targets[f])
    search = {"targets_n": targets, "tolerance": tolerance, "runs": tried,
              "reached": error <= tolerance, "shrink_bound": bound or None,
              "at_bound": at_bound}
    if error > tolerance:
        if tried[-1]["largest_relative_error"] != error:  # rerun the closest for the folder
            closest = next(t for t in tried if t["largest_relative_error"] == error)
            result = _stage(crimp, fams, closest["expansion"]).run(model, out, engine=engine,
                                                                  overwrite=True)
        why = (f"; {', '.join(at_bound)} at the \"auto\" shrink bound (more tension would "
               f"pull them straighter than the margin allows)" if at_bound else "")
        warnings.warn(f"crimp: the yarn tension did not reach its target within "
                      f"{100 * tolerance:g} % in {len(tried)} runs (closest: "
                      f"{100 * error:.1f} % off){why}; see summary.json tension_search",
                      stacklevel=3)
    result.summary["tension_search"] = search
    if mpi.is_root():
        write_json(Path(result.run_dir) / "summary.json", result.summary)
    return result


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


def _stage(crimp, fams, expansion: dict[str, float]):
    """One run of the search: the tension families at ``expansion``, their "auto" bound
    (kept by the search) taken out of the crimp targets."""
    return dataclasses.replace(
        crimp, target_tension=None, expansion={**crimp.expansion, **expansion},
        target_crimp_pct={f: v for f, v in crimp.target_crimp_pct.items() if f not in fams})
