"""Cohesion of a yarn: elastic links between the touching fibres of one yarn.

A real yarn holds together (sizing, twist, thousands of filaments pressed by the weave);
cut out of the fabric it stays a yarn, with a bending stiffness in its own plane that keeps
it nearly straight while the crossings turn — the trellising of a bias-extension coupon.
A bundle of a few bead chains with nothing between them is a set of loose strings: cut
free at 45°, the clamped fibres slide out and the centre does not shear.

:func:`add_cohesion` links every bead to the beads of the *other* fibres of its yarn that
lie within ``reach`` bead diameters (the touching neighbours, and their neighbours along
the fibre, so the links cross diagonally and carry shear between fibres), with
``bond harmonic`` springs whose rest length is the distance when linked: the piece is at
rest in the shape it had when linked, the yarn keeps its cross-section and its woven
(crimped) shape, and it bends as a truss of its fibres. Link a piece whose fibres carry no
load (:class:`fabmd.protocols.coupon.Coupon` links after the free relaxation): links made
while the fibres are stretched would hold that stretch (measured on the example's bias
coupon linked as cut: 125 N of yarn tension kept after relaxing, against 1e-5 N without).
Rest lengths are binned into bond types (relative width ``REST_BIN``, each type at the
mean length of its links): the misfit, at most ``REST_BIN`` of a link's length, leaves a
tiny self-stress.

Link stiffness: ``factor`` × the fibre bond's spring E·A/l0. With stiff links the yarn
bends like a solid beam of its fibres, E·I = E·A·Σ y_i² over the fibres' offsets y_i from
the neutral axis (tested); a small factor makes the fibres slide against each other
(a shear-flexible yarn), in the limit the loose strings again.

The truss bends only across the directions in which its fibres are spread: a yarn of fibres
side by side in one layer (three fibres in a 1.6 × 0.8 mm section) has no depth across
the fabric, its crimp is not held, and the example's bias coupon made that way frays as
before (measured: centre 4° for 40°, drag 87 % of the work); seven fibres in two layers
hold. The link factor sets the yarn's bending stiffness and with it the level of a bias
force (measured on the example at speed 2e-4: 1.0 / 1.7 / 2.5 N at 10 / 20 / 30° with
0.001, 5.0 / 9.8 / 13.5 N with 0.01): treat it as a yarn property to calibrate against a
measured bias curve.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import inputs
from ..errors import InputError
from .bead_model import BeadModel, BondType
from .rest_state import length_bins

REST_BIN = 1e-4  # relative width of a rest-length bin
DEFAULT_REACH = 1.5  # link beads of other fibres closer than this many bead diameters


def close_pairs(points: np.ndarray, radius: float) -> np.ndarray:
    """All index pairs (i < j) of ``points`` closer than ``radius`` (cell lists, numpy)."""
    points = np.asarray(points, float)
    if len(points) < 2:
        return np.zeros((0, 2), np.int64)
    cell = np.floor((points - points.min(axis=0)) / radius).astype(np.int64)
    dims = cell.max(axis=0) + 3
    key = ((cell[:, 0] + 1) * dims[1] + cell[:, 1] + 1) * dims[2] + cell[:, 2] + 1
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    found = []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                shift = (dx * dims[1] + dy) * dims[2] + dz
                lo = np.searchsorted(sorted_key, key + shift, side="left")
                hi = np.searchsorted(sorted_key, key + shift, side="right")
                count = hi - lo
                i = np.repeat(np.arange(len(points)), count)
                start = np.repeat(lo - np.cumsum(count) + count, count)
                j = order[start + np.arange(count.sum())]
                keep = i < j
                found.append(np.column_stack([i[keep], j[keep]]))
    pairs = np.vstack(found)
    dist = np.linalg.norm(points[pairs[:, 1]] - points[pairs[:, 0]], axis=1)
    return pairs[dist < radius]


def cohesion_links(model: BeadModel, reach: float = DEFAULT_REACH) -> np.ndarray:
    """(i, j) bead pairs of different fibres of one yarn closer than ``reach`` diameters."""
    if any(model.periodic):
        raise InputError("yarn cohesion is for a cut piece (coupon); this model is periodic")
    pos = model.positions
    pairs = close_pairs(pos, reach * float(model.diameters.max()))
    yarn = model.yarn_ids
    a, b = pairs[:, 0], pairs[:, 1]
    limit = reach * 0.5 * (model.diameters[a] + model.diameters[b])
    dist = np.linalg.norm(pos[b] - pos[a], axis=1)
    keep = ((yarn[a] == yarn[b]) & (model.fibre_ids[a] != model.fibre_ids[b])
            & (dist < limit))
    return pairs[keep]


def add_cohesion(model: BeadModel, factor: float, reach: float = DEFAULT_REACH) -> BeadModel:
    """``model`` with cohesion links in every yarn, at rest in the model's present shape.

    Args:
        factor: link spring as a fraction of the fibre bond's spring E·A/l0, in (0, 1].
        reach: link beads of other fibres of the same yarn closer than ``reach`` × the
            bead diameter, in [1, 3] (1.5: the touching fibres and their beads one to two
            spacings along).
    """
    inputs.in_range("cohesion_factor", factor, 0.0, 1.0, low_open=True)
    inputs.in_range("cohesion_reach", reach, 1.0, 3.0)
    if any(bt.kind == "cohesion" for bt in model.bond_type_table):
        raise InputError("this model already has cohesion links; add_cohesion gives them to "
                         "a model without any")
    links = cohesion_links(model, reach)
    if not len(links):
        return model
    rest = np.linalg.norm(model.positions[links[:, 1]] - model.positions[links[:, 0]], axis=1)
    family = np.asarray(model.family_names)[model.atom_types[links[:, 0]] - 1]
    spring = {}
    for fam in set(family.tolist()):
        bt = max((t for t in model.fibre_bond_types() if t.family == fam),
                 key=lambda t: t.coefficient)
        spring[fam] = bt.coefficient
    bins = length_bins(rest, REST_BIN)
    table = list(model.bond_type_table)
    types = np.zeros(len(links), np.int64)
    keys = np.unique(np.column_stack([np.searchsorted(sorted(spring), family), bins]), axis=0)
    names = sorted(spring)
    for fam_index, b in keys:
        fam = names[fam_index]
        sel = (family == fam) & (bins == b)
        table.append(BondType(coefficient=factor * spring[fam],
                              rest_length_m=float(rest[sel].mean()), family=fam,
                              kind="cohesion"))
        types[sel] = len(table)
    return dataclasses.replace(
        model, bonds=np.vstack([model.bonds, links]),
        bond_types=np.concatenate([model.bond_types, types]), bond_type_table=table,
        info={**model.info, "cohesion": {"factor": factor, "reach": reach,
                                         "links": int(len(links))}})
