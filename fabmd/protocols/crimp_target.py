"""Expansion from the crimp a fabric needs: a family's rest-length strain α·ΔT derived
from its loose geometry instead of typed in (``[crimp] target_crimp_pct``).

A yarn's rest length decides where it can lie without tension. Crimp is path length
over span minus one (TEXTILE-PRIMER.md; :func:`fabmd.results.measure.fibre_crimp`), so a
fibre whose bonds carry no force has the crimp its rest length allows. With the loose
*rest crimp* of a family,

    c0 = mean over its fibres of  Σ r0 / span − 1      (r0: bond rest lengths),

the strain that gives it a target crimp c is

    α = (1 + c) / (1 + c0) − 1.

What the crimp stage then does with it:

* a family that **shrinks** (c < c0) tightens until the yarns it crosses hold it; it
  ends at the target or above, by about its tension over E·A (its bonds are stretched),
  never straighter than the target: with c > 0 it cannot be pulled straight;
* a family that **expands** (c > c0) gets the length a longer wavy path needs; it ends
  at the target where the crossing yarns make room (their shrink, a thicker fabric) and
  slack where they do not (the length is there, the shape is not forced).

``"auto"`` (binders): shrink by the loose crimp less ``margin_pct`` percentage points,
i.e. target c = margin. The binders tighten and compact the fabric but keep that much
crimp, so they end under tension and still woven, not pulled into straight zig-zags
(the failure of a shrink beyond the loose crimp, issue #17).

Refused with the arithmetic shown: a target below 0 or of 100 % and more; a woven
(crimped) family told 0 % (it cannot be pulled straight); a straight family told to
crimp (an expansion gives it length, not waviness: it would end slack); ``"auto"`` on a
family whose loose crimp is not above the margin; a strain outside (−0.5, 0.5).
"""

from __future__ import annotations

import numpy as np

from .. import inputs
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..results.measure import bond_vectors

#: the word for "shrink by the loose crimp less the margin"
AUTO = "auto"
#: a family whose rest crimp is below this (fraction) counts as straight
STRAIGHT = 1e-4
#: the strain the crimp stage takes, exclusive (``crimp.expansion`` is checked so)
STRAIN_LIMIT = 0.5


def check_target_crimp(targets, margin_pct: float, key: str = "crimp.target_crimp_pct"
                       ) -> None:
    """Refuse a malformed target table at construction (the model is not needed)."""
    if not isinstance(targets, dict):
        raise InputError(f"{key} must be a table family -> crimp [%] or \"{AUTO}\", e.g. "
                         f"{{ warp = 1.2, weft = 0.8, binder = \"{AUTO}\" }}, got {targets!r}")
    for fam, value in targets.items():
        if isinstance(value, str):
            if value.strip() != AUTO:
                raise InputError(f"{key}.{fam} must be a crimp in % (a number) or "
                                 f"\"{AUTO}\", got {value!r}")
            continue
        inputs.in_range(f"{key}.{fam}", value, 0.0, 100.0, high_open=True)
    inputs.in_range(key.rsplit(".", 1)[0] + ".auto_margin_pct", margin_pct, 0.0, 100.0,
                    low_open=True, high_open=True)


def rest_crimp(model: BeadModel) -> dict[str, float]:
    """Rest crimp per family (fraction): mean over its fibres of Σ r0 / span − 1, the
    span taken from the fibre's bonds as :func:`fabmd.results.measure.fibre_crimp` does
    (a closed periodic fibre spans its period)."""
    fibre = model.fibre_bond_mask()
    bonds = model.bonds[fibre]
    vec = bond_vectors(model)[fibre]
    r0 = np.array([bt.rest_length_m for bt in model.bond_type_table])[
        model.bond_types[fibre] - 1]
    fib = model.fibre_ids[bonds[:, 0]] - 1
    path = np.bincount(fib, weights=r0, minlength=model.n_fibres)
    span = np.linalg.norm(np.column_stack([
        np.bincount(fib, weights=vec[:, k], minlength=model.n_fibres) for k in range(2)]),
        axis=1)
    fam = np.asarray(model.family_names)[model.atom_types[model.fibre_ends()[:, 0]] - 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        crimp = np.where(span > 0, path / span - 1.0, np.nan)
    return {f: float(np.nanmean(crimp[fam == f])) for f in model.family_names
            if (fam == f).any()}


def expansion_for(rest_crimp_fraction: float, target_fraction: float) -> float:
    """The rest-length strain α that gives a fibre of rest crimp ``rest_crimp_fraction``
    the crimp ``target_fraction`` without tension: (1 + c) / (1 + c0) − 1."""
    return (1.0 + target_fraction) / (1.0 + rest_crimp_fraction) - 1.0


def derive_expansion(model: BeadModel, targets: dict, margin_pct: float,
                     key: str = "crimp.target_crimp_pct") -> dict[str, dict]:
    """Per family named in ``targets``: its loose rest crimp, the target crimp and the
    strain that gives it (all in the summary's terms: % and a fraction).

    Raises:
        InputError: a family the fabric lacks, or a target the numbers cannot reach
            (module docstring), with the arithmetic.
    """
    unknown = sorted(set(targets) - set(model.family_names))
    if unknown:
        raise InputError(f"{key} names families {unknown} that the fabric does not have "
                         f"(it has {list(model.family_names)})")
    loose = rest_crimp(model)
    out: dict[str, dict] = {}
    for fam, value in targets.items():
        c0 = loose[fam]
        where = f"{key}.{fam} = {value!r}"
        if isinstance(value, str):  # AUTO (checked at construction)
            target = margin_pct / 100.0
            if c0 <= target:
                raise InputError(f"{where}: the {fam} yarns' loose crimp {100 * c0:.3g} % is "
                                 f"not above the margin {margin_pct:g} % "
                                 f"(crimp.auto_margin_pct): there is nothing to shrink; "
                                 f"give a smaller margin or a number")
        else:
            target = float(value) / 100.0
            if target == 0.0 and c0 > STRAIGHT:
                raise InputError(f"{where}: the {fam} yarns are woven (loose crimp "
                                 f"{100 * c0:.3g} %) and cannot be pulled straight; give a "
                                 f"crimp above 0")
            if c0 <= STRAIGHT and target > c0 + STRAIGHT:
                raise InputError(f"{where}: the {fam} yarns are straight in the loose fabric "
                                 f"(crimp {100 * c0:.2g} %); an expansion gives them length, "
                                 f"not waviness (they would end slack); leave them out")
        alpha = expansion_for(c0, target)
        if not -STRAIN_LIMIT < alpha < STRAIN_LIMIT:
            raise InputError(f"{where}: the strain it needs, (1 + {target:.4g}) / "
                             f"(1 + {c0:.4g}) - 1 = {alpha:.3g}, is outside "
                             f"(-{STRAIN_LIMIT:g}, {STRAIN_LIMIT:g})")
        out[fam] = {"loose_rest_crimp_pct": 100 * c0, "target_crimp_pct": 100 * target,
                    "expansion": alpha, "auto": isinstance(value, str)}
    return out
