"""Fibres at rest in their present shape: the crimp's locked-in tension taken out.

The crimp shrinks the fibres' rest lengths until the yarns press the fabric together; the
periodic cell holds the tension that leaves in its fibres (about 90 N per virtual fibre,
3.6 % fibre strain, on the plain-weave example). A coupon cut from it and relaxed free lets
that tension go through its cut edges only: friction at the crossings holds it inside, so
the relaxed coupon's crimp varies along it and with its length (measured on the example's
7-fibre tension coupons: warp crimp 3.4–4.1 % at the cut ends, 2.4 / 1.6 / 1.0 % in the middle
of coupons 3 / 4 / 6 cells long; the tension toe, and every force at a stated strain,
followed it). A real fabric is conditioned free of tension before specimens are cut (ISO
139), evenly over the piece.

:func:`relieve_fibre_tension` does that for a bead model: every fibre bond's rest length
becomes its present length, so the woven shape (crimp, thickness, spacings) is kept and no
fibre carries tension. Rest lengths are binned into bond types per original type (relative
width ``bin_width``, each type at the mean length of its bonds): the misfit leaves at most
``bin_width``/2 of fibre strain, of either sign (±0.6 N per 7-fibre glass virtual fibre at
the default). The bond spring k = 2K is kept, as the crimp's rest-length ramp keeps it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import inputs
from .bead_model import BeadModel, BondType

#: default relative width of a rest-length bin
RELIEF_BIN = 5e-4


def length_bins(lengths_m: np.ndarray, bin_width: float) -> np.ndarray:
    """Bin index of each length on a logarithmic scale of relative width ``bin_width``:
    lengths within about ``bin_width`` of each other share a bond type (also the
    cohesion links' binning, :mod:`fabmd.model.cohesion`)."""
    return np.round(np.log(lengths_m) / np.log1p(bin_width)).astype(np.int64)


def relieve_fibre_tension(model: BeadModel, bin_width: float = RELIEF_BIN) -> BeadModel:
    """``model`` with its fibre bonds at rest in their present lengths (binned into bond
    types, ``bin_width`` relative; other bonds and the positions unchanged).

    The new table keeps the order of the original fibre types (each replaced by its
    bins, so a family's types stay contiguous), then the other bond types.
    """
    inputs.in_range("relieve_fibre_tension.bin_width", bin_width, 0.0, 0.05, low_open=True)
    if not model.n_bonds:
        return model
    lengths = model.bond_lengths()
    fibre = model.fibre_bond_mask()
    bins = length_bins(lengths, bin_width)
    table: list[BondType] = []
    new_types = np.zeros(model.n_bonds, np.int64)
    old_table = model.bond_type_table
    for t, bt in enumerate(old_table, start=1):
        if bt.kind != "fibre":
            continue
        sel = fibre & (model.bond_types == t)
        for b in np.unique(bins[sel]):
            part = sel & (bins == b)
            table.append(dataclasses.replace(bt, rest_length_m=float(lengths[part].mean())))
            new_types[part] = len(table)
    for t, bt in enumerate(old_table, start=1):  # cohesion links and other kinds: as they were
        if bt.kind == "fibre":
            continue
        table.append(bt)
        new_types[model.bond_types == t] = len(table)
    info = dict(model.info)
    if "bond_types_per_family" in info:  # the fabric's count, now the bins'
        info["bond_types_per_family"] = {
            fam: sum(bt.kind == "fibre" and bt.family == fam for bt in table)
            for fam in info["bond_types_per_family"]}
    return dataclasses.replace(model, bond_types=new_types, bond_type_table=table,
                               info={**info, "fibre_tension_relieved": {
                                   "bin_width": bin_width,
                                   "bond_types": sum(bt.kind == "fibre" for bt in table)}})
