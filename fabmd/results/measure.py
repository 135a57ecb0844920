"""Measures of a fabric state: thickness, crimp, fibre volume fraction, yarn tension.

Definitions (TEXTILE-PRIMER.md):

* thickness — extent of the beads in z including their radius, over the
  measured region (default: every bead), so a loose and a crimped state compare;
* crimp of a fibre — path length over the in-plane length it spans, minus one:
  c = Σ|b_i| / |Σ b_i,xy| − 1 over its bonds (a closed periodic fibre spans its
  period); a family's crimp is the mean over its fibres (``crimp_pct``, named by
  ``crimp_definition``); the crimp of the yarn centrelines is beside it
  (``centreline_crimp_pct``, :func:`fabmd.analysis.crimp_by_family`);
* fabric fibre volume fraction — filament volume (Σ A·path length) over
  thickness × in-plane area of the region;
* bond tension — k·(r − r0) with k = E·A/r0 of the bond type (the rest length
  may be scaled by a crimp stage).
"""

from __future__ import annotations

import numpy as np

from ..model.bead_model import BeadModel


def bond_vectors(model: BeadModel) -> np.ndarray:
    """Minimum-image bond vectors j − i [m]."""
    d = model.positions[model.bonds[:, 1]] - model.positions[model.bonds[:, 0]]
    length = model.box_hi - model.box_lo
    for k in range(3):
        if model.periodic[k]:
            d[:, k] -= length[k] * np.round(d[:, k] / length[k])
    return d


def thickness_m(model: BeadModel, mask: np.ndarray | None = None) -> float:
    """z extent of the beads including their radius [m]."""
    sel = np.ones(model.n_beads, bool) if mask is None else mask
    z = model.unwrapped_positions[sel, 2]
    r = model.diameters[sel] / 2
    return float((z + r).max() - (z - r).min())


def interior_mask(model: BeadModel, edge_m: float) -> np.ndarray:
    """Beads at least ``edge_m`` inside the in-plane extent of the beads."""
    p = model.unwrapped_positions[:, :2]
    lo, hi = p.min(axis=0) + edge_m, p.max(axis=0) - edge_m
    return ((p >= lo) & (p <= hi)).all(axis=1)


def fibre_crimp(model: BeadModel, mask: np.ndarray | None = None) -> np.ndarray:
    """Crimp of every fibre (fraction, not %), over its bonds with both beads in ``mask``."""
    fibre = model.fibre_bond_mask()
    vec = bond_vectors(model)[fibre]
    bonds = model.bonds[fibre]
    fib = model.fibre_ids[bonds[:, 0]] - 1
    if mask is not None:
        inside = mask[bonds[:, 0]] & mask[bonds[:, 1]]
        vec, fib = vec[inside], fib[inside]
    path = np.bincount(fib, weights=np.linalg.norm(vec, axis=1), minlength=model.n_fibres)
    span = np.column_stack([np.bincount(fib, weights=vec[:, k], minlength=model.n_fibres)
                            for k in range(2)])
    span = np.linalg.norm(span, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(span > 0, path / span - 1.0, np.nan)


def family_crimp(model: BeadModel, mask: np.ndarray | None = None) -> dict[str, float]:
    """Mean crimp per yarn family (fraction), over the beads in ``mask``."""
    c = fibre_crimp(model, mask)
    fam = np.asarray(model.family_names)[model.atom_types[model.fibre_ends()[:, 0]] - 1]
    return {f: float(np.nanmean(c[fam == f])) for f in model.family_names if (fam == f).any()}


def bond_tension_n(model: BeadModel, rest_length_scale: dict[int, float] | None = None
                   ) -> np.ndarray:
    """Axial force in every bond [N] (positive in tension)."""
    scale = rest_length_scale or {}
    r = np.linalg.norm(bond_vectors(model), axis=1)
    r0 = np.array([bt.rest_length_m * scale.get(i + 1, 1.0)
                   for i, bt in enumerate(model.bond_type_table)])[model.bond_types - 1]
    k = np.array([2.0 * bt.coefficient for bt in model.bond_type_table])[model.bond_types - 1]
    return k * (r - r0)


def family_tension_n(model: BeadModel, rest_length_scale: dict[int, float] | None = None
                     ) -> dict[str, dict[str, float]]:
    """Mean and max fibre tension and mean yarn tension per family [N]."""
    fibre = model.fibre_bond_mask()
    t = bond_tension_n(model, rest_length_scale)[fibre]
    fam_of_bond = np.asarray(model.family_names)[model.atom_types[model.bonds[fibre, 0]] - 1]
    fibres_per_yarn = np.bincount(model.fibre_yarn, minlength=len(model.yarns) + 1)[1:]
    out = {}
    for f in model.family_names:
        sel = fam_of_bond == f
        if not sel.any():
            continue
        yarns = [i for i, y in enumerate(model.yarns) if y.family == f]
        per_yarn = float(np.mean(fibres_per_yarn[yarns])) if yarns else 1.0
        out[f] = {"mean_fibre_tension_n": float(t[sel].mean()),
                  "max_fibre_tension_n": float(t[sel].max()),
                  "mean_yarn_tension_n": float(t[sel].mean() * per_yarn)}
    return out


def fibre_volume_m3(model: BeadModel) -> float:
    """Filament volume Σ A·(bond length) [m³].

    The filament area per family comes from ``model.info['families'][f]['fibre_area_m2']``
    (written by :func:`fabmd.model.fabric_model.render_fabric`); NaN when the model does
    not carry it.
    """
    areas = {f: v["fibre_area_m2"] for f, v in model.info.get("families", {}).items()
             if "fibre_area_m2" in v}
    if not areas:
        return float("nan")
    fibre = model.fibre_bond_mask()
    vec = np.linalg.norm(bond_vectors(model), axis=1)[fibre]
    fam_of_bond = np.asarray(model.family_names)[model.atom_types[model.bonds[fibre, 0]] - 1]
    a = np.array([areas.get(f, np.nan) for f in fam_of_bond])
    return float(np.sum(a * vec))


def areal_density_kg_m2(model: BeadModel) -> float:
    """Fibre mass per in-plane area [kg/m²]: bead masses without the mass scaling."""
    scaling = float(model.info.get("discretisation", {}).get("mass_scaling", 1.0))
    return float(np.sum(model.masses)) / scaling / in_plane_area_m2(model)


def in_plane_area_m2(model: BeadModel) -> float:
    """Box area for a periodic model, else the bead bounding box in x-y [m²]."""
    if model.periodic[0] and model.periodic[1]:
        length = model.box_hi - model.box_lo
        return float(length[0] * length[1])
    p = model.unwrapped_positions
    ext = p[:, :2].max(axis=0) - p[:, :2].min(axis=0)
    return float(ext[0] * ext[1])


def yarn_sections(model: BeadModel, stations=(0.25, 0.5, 0.75)) -> dict[str, dict]:
    """Mean yarn cross-section per family: width, height and yarn fibre volume fraction.

    Width and height are the extents of the fibres cutting a plane normal to the yarn
    centreline (plus one fibre diameter), averaged over every yarn of the family at
    ``stations``; the yarn fibre volume fraction is the yarn's filament area over the
    ellipse of that width and height, π·w·h/4. With few virtual fibres per yarn (7
    or fewer) the fibres' extent under-estimates the section and so over-estimates the
    yarn volume fraction; use 19 or more fibres for yarn-level measures.
    """
    from ..analysis import FabricFrame
    from ..analysis.sections import cross_section
    from ..errors import InputError

    frame = FabricFrame.from_model(model)
    areas = {f: v.get("fibre_area_m2") for f, v in model.info.get("families", {}).items()}
    fibres_per_yarn = np.bincount(model.fibre_yarn, minlength=len(model.yarns) + 1)[1:]
    out: dict[str, dict] = {}
    for family in model.family_names:
        widths, heights, fractions = [], [], []
        for k, yarn in enumerate(model.yarns):
            if yarn.family != family:
                continue
            for station in stations:
                try:
                    sec = cross_section(frame, yarn.name, station)
                except InputError:
                    continue
                widths.append(sec.width_m)
                heights.append(sec.height_m)
                if areas.get(family):
                    ellipse = np.pi * sec.width_m * sec.height_m / 4
                    fractions.append(fibres_per_yarn[k] * areas[family] / ellipse)
        if widths:
            out[family] = {"width_m": float(np.mean(widths)),
                           "height_m": float(np.mean(heights)),
                           "fibre_volume_fraction": float(np.mean(fractions))
                           if fractions else None,
                           "sections": len(widths)}
    return out


#: what ``crimp_pct`` of :func:`fabric_measures` is (the summary names it)
CRIMP_DEFINITION = ("per fibre: mean over a family's virtual fibres of path length / "
                    "in-plane span - 1")
#: what ``centreline_crimp_pct`` is
CENTRELINE_CRIMP_DEFINITION = ("yarn centreline: mean over a family's yarns of the crimp of "
                               "the centreline (mean of the yarn's fibres per station)")


def centreline_crimp_pct(model: BeadModel) -> dict[str, float] | None:
    """Crimp of the yarn centrelines per family [%] (``fabmd.analysis.crimp_by_family``),
    over every bead; None where the model has no yarn centrelines to take."""
    from ..analysis import FabricFrame, crimp_by_family

    try:
        crimps = crimp_by_family(FabricFrame.from_model(model))
    except (ValueError, IndexError, ZeroDivisionError):
        return None
    return {f: 100 * c for f, c in crimps.items()}


def fabric_measures(model: BeadModel, rest_length_scale: dict[int, float] | None = None,
                    edge_m: float = 0.0) -> dict:
    """Summary of a fabric state (keys carry units).

    ``edge_m`` > 0 measures thickness and crimp over the interior only (a finite
    piece's edge zone is not representative).
    """
    mask = interior_mask(model, edge_m) if edge_m > 0 else None
    t = thickness_m(model, mask)
    volume = fibre_volume_m3(model)
    area = in_plane_area_m2(model)
    return {
        "thickness_m": t,
        "crimp_pct": {f: 100 * c for f, c in family_crimp(model, mask).items()},
        "crimp_definition": CRIMP_DEFINITION,
        "centreline_crimp_pct": centreline_crimp_pct(model),
        "measured_over": "interior" if mask is not None else "all beads",
        "fibre_volume_fraction": volume / (t * area) if np.isfinite(volume) else None,
        "in_plane_area_m2": area,
        "yarn_sections": yarn_sections(model),
        "tension": family_tension_n(model, rest_length_scale),
        "n_beads": model.n_beads,
        "n_fibres": model.n_fibres,
    }


def _cell_pairs(points: np.ndarray, radius: float, box_len: np.ndarray | None,
                periodic: tuple[bool, ...]) -> np.ndarray:
    """All index pairs (i < j) closer than ``radius`` (numpy cell list, minimum image)."""
    n = len(points)
    lo = points.min(axis=0)
    cell = np.floor((points - lo) / radius).astype(np.int64)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    key_sorted = key[order]
    pairs = []
    offsets = [(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)]
    for da, db, dc in offsets:
        nb = cell + np.array([da, db, dc])
        for k in range(3):
            if periodic[k] and box_len is not None and dims[k] > 2:
                nb[:, k] %= dims[k]
        valid = ((nb >= 0) & (nb < dims)).all(axis=1)
        nkey = (nb[:, 0] * dims[1] + nb[:, 1]) * dims[2] + nb[:, 2]
        start = np.searchsorted(key_sorted, nkey, side="left")
        stop = np.searchsorted(key_sorted, nkey, side="right")
        counts = np.where(valid, stop - start, 0)
        if counts.sum() == 0:
            continue
        i = np.repeat(np.arange(n), counts)
        j = order[np.concatenate([np.arange(a, b) for a, b, c in zip(start, stop, counts,
                                                                         strict=True) if c])]
        keep = i < j
        pairs.append(np.column_stack([i[keep], j[keep]]))
    if not pairs:
        return np.zeros((0, 2), np.int64)
    pairs = np.unique(np.vstack(pairs), axis=0)
    d = points[pairs[:, 1]] - points[pairs[:, 0]]
    if box_len is not None:
        for k in range(3):
            if periodic[k]:
                d[:, k] -= box_len[k] * np.round(d[:, k] / box_len[k])
    return pairs[np.linalg.norm(d, axis=1) < radius]


def close_pairs_between_yarns(model: BeadModel, radius_m: float) -> np.ndarray:
    """Pairs of beads of different yarns closer than ``radius_m`` (minimum image)."""
    pairs = _cell_pairs(model.positions, radius_m, model.box_hi - model.box_lo, model.periodic)
    yarn = model.yarn_ids
    return pairs[yarn[pairs[:, 0]] != yarn[pairs[:, 1]]]


def passed_through(loose: BeadModel, deformed: BeadModel, radius_factor: float = 2.5
                   ) -> dict:
    """Check that no yarn passed through another between two states of one fabric.

    Pairs of beads of different yarns that touch (closer than ``radius_factor`` ×
    diameter) in the loose state must keep the sign of their separation along
    the line that joined them (the side each is on); a flipped sign means one
    fibre went through the other. Also reports the deepest overlap now.
    """
    d = float(loose.diameters.max())
    pairs = close_pairs_between_yarns(loose, radius_factor * d)

    before, after = sep_pairs(loose, pairs), sep_pairs(deformed, pairs)
    flipped = np.einsum("ij,ij->i", before, after) < 0
    now = close_pairs_between_yarns(deformed, d)
    gaps = np.linalg.norm(sep_pairs(deformed, now), axis=1) if len(now) else np.array([d])
    sizes = (deformed.diameters[now[:, 0]] + deformed.diameters[now[:, 1]]) / 2 if len(now) \
        else np.array([d])
    return {"pairs_checked": int(len(pairs)), "flipped_pairs": int(flipped.sum()),
            "max_overlap_ratio": float(max(0.0, (1 - gaps / sizes).max())),
            "flipped_yarns": sorted({(deformed.yarns[deformed.yarn_ids[a] - 1].name,
                                      deformed.yarns[deformed.yarn_ids[b] - 1].name)
                                     for a, b in pairs[flipped]})[:10]}


def sep_pairs(model: BeadModel, pairs: np.ndarray) -> np.ndarray:
    """Minimum-image vectors between bead pairs."""
    v = model.positions[pairs[:, 1]] - model.positions[pairs[:, 0]]
    length = model.box_hi - model.box_lo
    for k in range(3):
        if model.periodic[k]:
            v[:, k] -= length[k] * np.round(v[:, k] / length[k])
    return v
