"""Bending stiffness for the fibres of a cut piece (a straight rest shape).

A woven yarn is bent elastically around the yarns it crosses; its bending stiffness presses
the crossings together, and that normal force (with friction) is what holds a cut piece of
fabric together. Bead chains without bending are strings: once the crimp tension is gone
their crossings carry no force. :func:`add_bending` gives every fibre of a model a bending
term (``angle cosine``, as ``[discretisation] bending_factor`` does for a whole scene) with a
straight rest shape, so the woven crimp is elastic; a coupon can thus get bending without
the crimp stage paying for it.

For a fibre of diameter d and axial stiffness E·A, E·I = E·A·d²/16; a real yarn of n
filaments of diameter d_f has E·I_yarn = n·E·π·d_f⁴/64, a small fraction of the solid rod's
(600 tex E-glass, 17 µm filaments, 7 virtual fibres: about 0.008).

Why not the woven shape as rest shape: a bending term of one bead triple knows only the
angle, not the direction of the bend. With a rest angle below 180° every bend of that size
in *any* direction is at rest and the straight chain is the tip of a cone of energy, whose
force LAMMPS's ``angle harmonic`` cannot evaluate (it clamps 1/sin θ); chains flip through
it and gain energy. Measured on the bias-extension coupon (one fibre per yarn, the crimp as
rest shape): the free fabric took 3.6× and 21× the external work out of nowhere. A set
shape needs a bending term with a reference direction; fabmd does not have one.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import inputs
from ..errors import InputError
from .bead_model import AngleType, BeadModel


def chain_triples(model: BeadModel) -> np.ndarray:
    """(a, b, c) for every bead b with two bond partners a, c of its own fibre (0-based)."""
    b = model.bonds[model.fibre_bond_mask()]
    same = model.fibre_ids[b[:, 0]] == model.fibre_ids[b[:, 1]]
    pairs = np.vstack([b[same], b[same][:, ::-1]])
    pairs = pairs[np.argsort(pairs[:, 0], kind="stable")]
    counts = np.bincount(pairs[:, 0], minlength=model.n_beads)
    middle = np.flatnonzero(counts == 2)
    start = np.concatenate([[0], np.cumsum(counts)])[middle]
    return np.column_stack([pairs[start, 1], middle, pairs[start + 1, 1]]).astype(np.int64)


def add_bending(model: BeadModel, factor: float) -> BeadModel:
    """``model`` with a bending term on every inner bead of every fibre (straight rest shape).

    Args:
        factor: fraction of the solid virtual fibre's E·I, in (0, 1]; the coefficient is
            K = factor·E·I/l0 per family (the stiffest bond type's E·A and l0).
    """
    inputs.in_range("bending_factor", factor, 0.0, 1.0, low_open=True)
    if len(model.angles):
        raise InputError("this model already has bending terms; add_bending gives them to a "
                         "model without any")
    triples = chain_triples(model)
    if not len(triples):
        return model
    family = np.asarray(model.family_names)[model.atom_types[triples[:, 1]] - 1]
    names = sorted(set(family.tolist()))
    table = []
    for fam in names:
        types = [bt for bt in model.fibre_bond_types() if bt.family == fam]
        bt = max(types, key=lambda t: t.coefficient * t.rest_length_m)
        ea = bt.bond_axial_stiffness_n
        d = float(model.diameters[model.atom_types == model.family_names.index(fam) + 1].max())
        table.append(AngleType(factor * ea * d * d / 16.0 / bt.rest_length_m, fam))
    index = {fam: i + 1 for i, fam in enumerate(names)}
    types = np.array([index[f] for f in family.tolist()], np.int64)
    return dataclasses.replace(model, angles=triples, angle_types=types, angle_type_table=table)
