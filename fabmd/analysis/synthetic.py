"""Synthetic woven sheets with closed-form geometry, for tests, notebooks and benchmarks.

Not the geometry package: a plain weave of straight-sided yarns whose
centrelines are exact sinusoids, so crimp, curvature, cross-sections and
(after an affine shear) the shear angle are known in closed form.

Warp yarns run along x (at y = (j + ½)·s), weft yarns along y (at x = (i + ½)·s);
warp ``j`` follows z = A·(−1)^j·cos(π(x − s/2)/s), weft ``i`` the opposite sign,
so they pass over and under each other at every crossing. Each yarn is a
rectangular bundle of ``fibres = (across, through)`` virtual fibres.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..geometry.material import GLASS, FibreMaterial, VirtualFibre
from ..model.bead_model import BeadModel, BondType, Yarn
from ..model.beads import Discretisation, bead_parameters


def crossing_amplitude(fibres_through: int, pitch_m: float, diameter_m: float,
                       clearance: float) -> float:
    """Centreline amplitude A that leaves ``clearance``·d between crossing yarns."""
    return 0.5 * ((fibres_through - 1) * pitch_m + diameter_m * (1.0 + clearance))


def _even_arc_stations(amp: float, s: float, length: float, n: int, closed: bool
                       ) -> np.ndarray:
    """Positions along the yarn axis that cut z = A·cos(π(x − s/2)/s) into equal arcs."""
    x = np.linspace(0.0, length, 200 * n + 1)
    z = amp * np.cos(math.pi * (x - 0.5 * s) / s)
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(z)))])
    targets = np.arange(n if closed else n + 1) * (arc[-1] / n)
    return np.interp(targets, arc, x)


def _check_sheet(warp_yarns: int, weft_yarns: int, spacing_m: float, fibres, d: float,
                 pitch: float, shear_deg: float, periodic: bool) -> tuple[int, int]:
    """Fibres across and through a yarn, after checking that the sheet can be built."""
    nw, nh = (int(f) for f in fibres)
    if nw < 1 or nh < 1:
        raise InputError(f"woven_sheet.fibres must be two integers >= 1, got {fibres}")
    if periodic and (warp_yarns % 2 or weft_yarns % 2):
        raise InputError("a periodic plain weave needs even numbers of warp and weft yarns, "
                         f"got {warp_yarns} and {weft_yarns}")
    if periodic and shear_deg:
        raise InputError("woven_sheet.shear_deg needs periodic=False (the box would be "
                         "triclinic)")
    p = pitch * d
    if (nw - 1) * p + d >= spacing_m:
        raise InputError(f"yarns of {nw} fibres across ({(nw - 1) * p + d:g} m wide) do not "
                         f"fit a spacing of {spacing_m:g} m")
    return nw, nh


def woven_sheet(warp_yarns: int = 2, weft_yarns: int = 2, spacing_m: float = 2e-3,
                fibres: tuple[int, int] = (3, 2), fibre_diameter_m: float = 0.1e-3,
                spacing_ratio: float = 0.5, pitch: float = 1.05, clearance: float = 0.1,
                amplitude_m: float | None = None, shear_deg: float = 0.0,
                periodic: bool = True, material: FibreMaterial = GLASS) -> BeadModel:
    """A plain-weave bead model with sinusoidal yarns.

    Args:
        warp_yarns, weft_yarns: yarns of each family (even when periodic).
        spacing_m: yarn spacing s [m] (centre to centre).
        fibres: virtual fibres per yarn across its width and through its thickness.
        fibre_diameter_m: virtual fibre (bead) diameter d [m].
        spacing_ratio: bead spacing over d.
        pitch: fibre centre spacing inside a yarn over d (>= 1: fibres do not overlap).
        clearance: gap between crossing yarns over d.
        amplitude_m: centreline amplitude A (default: crossing yarns just clear).
        shear_deg: affine in-plane shear γ (x, y) → (x + y·sin γ, y·cos γ): the weft
            turns by γ towards the warp (non-periodic sheets only).
        periodic: close every fibre across a periodic x-y box.
        material: fibre material.
    """
    nw, nh = _check_sheet(warp_yarns, weft_yarns, spacing_m, fibres, fibre_diameter_m, pitch,
                          shear_deg, periodic)
    d = fibre_diameter_m
    p = pitch * d
    amp = crossing_amplitude(nh, p, d, clearance) if amplitude_m is None else amplitude_m
    fibre = VirtualFibre.solid(material, d)
    s = spacing_m
    lengths = {"warp": weft_yarns * s, "weft": warp_yarns * s}
    counts = {"warp": warp_yarns, "weft": weft_yarns}
    pos, types, fib, bonds, btypes, yarns, fibre_yarn, table = [], [], [], [], [], [], [], []
    k = 0
    for t, fam in enumerate(("warp", "weft"), start=1):
        length = lengths[fam]
        n = max(4, round(length / (spacing_ratio * d)))
        b = bead_parameters(fibre, Discretisation(spacing_ratio=spacing_ratio),
                            bond_length_m=length / n)
        table.append(BondType(b.bond_coefficient, b.bond_length_m, fam, b.axial_stiffness_n))
        along = _even_arc_stations(amp, s, length, n, closed=periodic)
        sign = 1.0 if fam == "warp" else -1.0
        for j in range(counts[fam]):
            yarns.append(Yarn(f"{fam}-{j}", fam))
            centre = (j + 0.5) * s
            zc = sign * amp * (-1) ** j * np.cos(math.pi * (along - 0.5 * s) / s)
            for xyz in _fibre_lines(fam, along, centre, zc, nw, nh, p):
                m = len(along)
                pos.append(xyz)
                fibre_yarn.append(len(yarns))
                fib += [len(fibre_yarn)] * m
                types += [t] * m
                bonds += [(k + i, k + i + 1) for i in range(m - 1)]
                if periodic:
                    bonds.append((k + m - 1, k))
                btypes += [t] * (m if periodic else m - 1)
                k += m
    pos = np.vstack(pos)
    if shear_deg:
        g = math.radians(shear_deg)
        pos = np.column_stack([pos[:, 0] + pos[:, 1] * math.sin(g), pos[:, 1] * math.cos(g),
                               pos[:, 2]])
    # z: room for the crossings and a few diameters; x, y: the period or 2 d of margin
    zpad = amp + nh * p + 4 * d
    if periodic:
        lo, hi = np.array([0.0, 0.0, -zpad]), np.array([lengths["warp"], lengths["weft"], zpad])
    else:
        lo = np.array([*(pos[:, :2].min(axis=0) - 2 * d), -zpad])
        hi = np.array([*(pos[:, :2].max(axis=0) + 2 * d), zpad])
    model = BeadModel(
        positions=pos, diameters=d, masses=1.0, atom_types=types, fibre_ids=fib, bonds=bonds,
        bond_types=btypes, family_names=("warp", "weft"), bond_type_table=table,
        fibre_yarn=fibre_yarn, yarns=yarns, box_lo=lo, box_hi=hi,
        periodic=(periodic, periodic, False))
    model.bond_type_table = _unstressed_types(model, table)
    model.masses = np.full(model.n_beads, bead_parameters(
        fibre, Discretisation(spacing_ratio=spacing_ratio)).mass_kg)
    model.info = {"synthetic": "woven_sheet", "spacing_m": s, "amplitude_m": amp,
                  "fibres": [nw, nh], "shear_deg": shear_deg,
                  "fibre_area_m2": {"warp": fibre.area_m2, "weft": fibre.area_m2}}
    return model


def sinusoid_crimp(amplitude_m: float, wavelength_m: float, samples: int = 200_001) -> float:
    """Crimp of z = A·cos(2πx/λ) over whole periods (numerical quadrature of the arc)."""
    x = np.linspace(0.0, wavelength_m, samples)
    k = 2 * math.pi / wavelength_m
    slope = amplitude_m * k * np.sin(k * x)
    integrand = np.sqrt(1.0 + slope**2)
    return float(np.trapezoid(integrand, x) / wavelength_m - 1.0)


def sinusoid_curvature(amplitude_m: float, wavelength_m: float, x) -> np.ndarray:
    """Curvature of z = A·cos(2πx/λ) at x [1/m]."""
    k = 2 * math.pi / wavelength_m
    x = np.asarray(x, float)
    return (amplitude_m * k * k * np.abs(np.cos(k * x))
            / (1.0 + (amplitude_m * k * np.sin(k * x)) ** 2) ** 1.5)


def _fibre_lines(fam: str, along: np.ndarray, centre: float, zc: np.ndarray, nw: int, nh: int,
                 p: float):
    """Bead positions (k, 3) [m] of the ``nw`` × ``nh`` fibres of one yarn, ``p`` apart
    around its centreline (``along`` the yarn axis, at ``centre`` across, height ``zc``)."""
    m = len(along)
    for a in range(nw):
        for c in range(nh):
            across = centre + (a - 0.5 * (nw - 1)) * p
            z = zc + (c - 0.5 * (nh - 1)) * p
            yield (np.column_stack([along, np.full(m, across), z]) if fam == "warp"
                   else np.column_stack([np.full(m, across), along, z]))


def _unstressed_types(model: BeadModel, table: list[BondType]) -> list[BondType]:
    """Rest length = mean bond length of the family (same E·A): the sheet starts (nearly)
    unstressed."""
    blen = model.bond_lengths()
    return [BondType(bt.coefficient * bt.rest_length_m / blen[model.bond_types == i].mean(),
                     float(blen[model.bond_types == i].mean()), bt.family, bt.axial_stiffness_n)
            for i, bt in enumerate(table, start=1)]
