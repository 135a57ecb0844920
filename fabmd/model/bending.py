"""Bending stiffness of cut fibres, with a rest shape between straight and as woven.

A woven yarn is bent elastically around the yarns it crosses: its bending stiffness presses
the crossings together, and that normal force (with friction) is what holds a cut piece of
fabric together. Bead chains without bending are strings; once the crimp tension is gone
their crossings carry no force and a coupon cut free at 45° falls apart.

:func:`set_bending` gives every fibre a bending term (``angle harmonic``), stiffness a
fraction of the solid virtual fibre's E·I, and rest angle ``180° − set·(180° − θ_now)``
(binned to ``bin_deg``): ``set = 0`` a straight rest shape — the crimp is all elastic and
presses the crossings; ``set = 1`` the as-woven shape itself — the crimp is a permanent set
and nothing is pre-stressed (the crossings stay unloaded).

For a fibre of diameter d and axial stiffness E·A, E·I = E·A·d²/16; a real yarn of n
filaments of diameter d_f has E·I_yarn = n·E·π·d_f⁴/64, a small fraction of the solid rod's
(600 tex E-glass, 17 µm filaments, 7 virtual fibres: about 0.008).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import inputs
from ..errors import InputError
from .bead_model import AngleType, BeadModel


def chain_triples(model: BeadModel) -> np.ndarray:
    """(a, b, c) for every bead b with two bond partners a, c of its own fibre (0-based)."""
    b = model.bonds
    same = model.fibre_ids[b[:, 0]] == model.fibre_ids[b[:, 1]]
    pairs = np.vstack([b[same], b[same][:, ::-1]])
    pairs = pairs[np.argsort(pairs[:, 0], kind="stable")]
    counts = np.bincount(pairs[:, 0], minlength=model.n_beads)
    middle = np.flatnonzero(counts == 2)
    start = np.concatenate([[0], np.cumsum(counts)])[middle]
    return np.column_stack([pairs[start, 1], middle, pairs[start + 1, 1]]).astype(np.int64)


def set_bending(model: BeadModel, factor: float, set_fraction: float = 1.0,
                bin_deg: float = 0.25) -> BeadModel:
    """``model`` with bending terms whose rest shape is a fraction of its present bend.

    Args:
        factor: fraction of the solid virtual fibre's E·I, in (0, 1].
        set_fraction: share of the present bend kept as rest shape, in [0, 1]: the rest
            angle is 180° − set_fraction·(180° − θ) (0: straight, 1: as it is now).
        bin_deg: rest angles are rounded to this (one angle type per family and bin).
    """
    inputs.in_range("bending_factor", factor, 0.0, 1.0, low_open=True)
    inputs.in_range("bending_set", set_fraction, 0.0, 1.0)
    inputs.positive("bending bin_deg", bin_deg)
    if len(model.angles):
        raise InputError("this model already has bending terms; set_bending gives a fresh "
                         "set to a model without them")
    triples = chain_triples(model)
    if not len(triples):
        return model
    pos = model.unwrapped_positions
    u = pos[triples[:, 0]] - pos[triples[:, 1]]
    v = pos[triples[:, 2]] - pos[triples[:, 1]]
    cos = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
    theta = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    rest = np.round((180.0 - set_fraction * (180.0 - theta)) / bin_deg) * bin_deg
    family = np.asarray(model.family_names)[model.atom_types[triples[:, 1]] - 1]
    # E·I = E·A·d²/16 of the solid virtual fibre, per family (the stiffest bond type's E·A)
    coefficient = {}
    for fam in np.unique(family):
        types = [bt for bt in model.bond_type_table if bt.family == fam]
        bt = max(types, key=lambda t: t.coefficient * t.rest_length_m)
        ea = 2.0 * bt.coefficient * bt.rest_length_m
        d = float(model.diameters[model.atom_types == model.family_names.index(fam) + 1].max())
        coefficient[fam] = factor * ea * d * d / 16.0 / bt.rest_length_m
    pairs = list(zip(family.tolist(), rest.tolist(), strict=True))
    keys = sorted(set(pairs))
    index = {k: i + 1 for i, k in enumerate(keys)}
    table = [AngleType(coefficient[f], f, rest_angle_deg=float(r)) for f, r in keys]
    types = np.array([index[k] for k in pairs], np.int64)
    return dataclasses.replace(model, angles=triples, angle_types=types, angle_type_table=table)
