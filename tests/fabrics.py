"""Tiny hand-built fabrics for protocol tests (the geometry package builds real ones)."""

from __future__ import annotations

import math

import numpy as np

from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.material import FibreMaterial, VirtualFibre

SOFT_GLASS = FibreMaterial(modulus_pa=1e9, density_kg_m3=2540.0, name="soft glass")


def plain_weave_cell(spacing_m=2e-3, diameter_m=0.5e-3, gap=1.5, cells=(1, 1),
                     periodic=True, spacing_ratio=0.5, material=SOFT_GLASS) -> BeadModel:
    """A plain weave of single-fibre yarns with sinusoidal loose paths.

    Warp along x, weft along y, ``2 * cells`` yarns each way; crossing yarns are
    ``gap`` diameters apart (centre to centre) at the crossings.
    """
    fibre = VirtualFibre.solid(material, diameter_m)
    nx, ny = cells
    period = (2 * nx * spacing_m, 2 * ny * spacing_m)
    amp = gap * diameter_m / 2
    pos, types, fib, bonds, btypes, yarns = [], [], [], [], [], []
    table = []
    k = 0
    for fam, count, length, along in (("warp", 2 * ny, period[0], 0), ("weft", 2 * nx,
                                                                        period[1], 1)):
        n = round(length / (spacing_ratio * diameter_m))
        b = bead_parameters(fibre, Discretisation(spacing_ratio=spacing_ratio),
                            bond_length_m=length / n)
        table.append(BondType(b.bond_coefficient, b.bond_length_m, fam, b.axial_stiffness_n))
        sign = 1 if fam == "warp" else -1
        for j in range(count):
            s = np.arange(n) * b.bond_length_m if periodic else np.linspace(0, length, n)
            across = (j + 0.5) * spacing_m
            z = sign * amp * (-1) ** j * np.cos(math.pi * (s - 0.5 * spacing_m) / spacing_m)
            xyz = np.column_stack([s, np.full(n, across), z]) if along == 0 else \
                np.column_stack([np.full(n, across), s, z])
            pos.append(xyz)
            types += [1 if fam == "warp" else 2] * n
            fib += [len(yarns) + 1] * n
            bonds += [(k + i, k + i + 1) for i in range(n - 1)]
            if periodic:
                bonds.append((k + n - 1, k))
            btypes += [len(table)] * (n if periodic else n - 1)
            yarns.append(Yarn(f"{fam}-{j}", fam))
            k += n
    pos = np.vstack(pos)
    # rest length = mean bond length of the family, so the loose fabric starts unstressed
    probe = BeadModel(positions=pos, diameters=diameter_m, masses=1.0, atom_types=types,
                      fibre_ids=fib, bonds=bonds, bond_types=btypes, family_names=("warp", "weft"),
                      bond_type_table=table, fibre_yarn=np.arange(1, len(yarns) + 1), yarns=yarns,
                      box_lo=[0, 0, -1], box_hi=[period[0], period[1], 1],
                      periodic=(periodic, periodic, False))
    lengths = probe.bond_lengths()
    btypes_arr = np.asarray(btypes)
    table = [BondType(bt.coefficient * bt.rest_length_m / lengths[btypes_arr == i + 1].mean(),
                      float(lengths[btypes_arr == i + 1].mean()), bt.family, bt.axial_stiffness_n)
             for i, bt in enumerate(table)]
    return BeadModel(
        positions=pos, diameters=diameter_m, masses=bead_parameters(fibre).mass_kg,
        atom_types=types, fibre_ids=fib, bonds=bonds, bond_types=btypes,
        family_names=("warp", "weft"), bond_type_table=table,
        fibre_yarn=np.arange(1, len(yarns) + 1), yarns=yarns,
        box_lo=[0, 0, -4 * diameter_m] if periodic else [-diameter_m, -diameter_m,
                                                         -4 * diameter_m],
        box_hi=[period[0], period[1], 4 * diameter_m] if periodic else
        [period[0] + diameter_m, period[1] + diameter_m, 4 * diameter_m],
        periodic=(periodic, periodic, False),
        info={"families": {f: {"fibre_area_m2": fibre.area_m2} for f in ("warp", "weft")}})


def parallel_fibres(n=4, length_m=10e-3, diameter_m=0.5e-3, spacing_ratio=0.5,
                    material=SOFT_GLASS, gap=1.2) -> BeadModel:
    """``n`` straight, parallel single-fibre yarns along x in one plane."""
    fibre = VirtualFibre.solid(material, diameter_m)
    b = bead_parameters(fibre, Discretisation(spacing_ratio=spacing_ratio))
    nb = round(length_m / b.bond_length_m) + 1
    x = np.arange(nb) * b.bond_length_m
    pos = np.vstack([np.column_stack([x, np.full(nb, j * gap * diameter_m), np.zeros(nb)])
                     for j in range(n)])
    bonds = [(j * nb + i, j * nb + i + 1) for j in range(n) for i in range(nb - 1)]
    return BeadModel(
        positions=pos, diameters=diameter_m, masses=b.mass_kg, atom_types=1,
        fibre_ids=np.repeat(np.arange(1, n + 1), nb), bonds=bonds, bond_types=1,
        family_names=("warp",),
        bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "warp",
                                  b.axial_stiffness_n)],
        fibre_yarn=np.arange(1, n + 1), yarns=[Yarn(f"warp-{j}", "warp") for j in range(n)],
        box_lo=[-diameter_m, -diameter_m, -diameter_m],
        box_hi=[x[-1] + diameter_m, (n - 1) * gap * diameter_m + diameter_m, diameter_m],
        info={"families": {"warp": {"fibre_area_m2": fibre.area_m2}}})
