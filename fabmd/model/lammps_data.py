"""LAMMPS data files of bead models (``atom_style hybrid sphere angle``).

Atoms lines are ``id type x y z diameter density molecule ix iy iz`` (SI);
coefficients are not written here: the input script sets them, so a crimp ramp
or a preset changes them without touching geometry. :func:`read_data` reads our
files and the ones LAMMPS ``write_data`` produces after a run.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np

from ..errors import InputError
from .bead_model import AngleType, BeadModel, BondType, Yarn

ATOM_STYLE = "hybrid sphere angle"


def _table(f, rows: np.ndarray, fmt: str) -> None:
    if len(rows):
        np.savetxt(f, rows, fmt=fmt)


def write_data(model: BeadModel, path: Path) -> None:
    """Write ``model`` to ``path`` as a LAMMPS data file."""
    n = model.n_beads
    volume = math.pi * model.diameters**3 / 6.0
    density = model.masses / volume
    buf = io.StringIO()
    buf.write("LAMMPS data file written by fabmd (units si, atom_style hybrid sphere angle)\n\n")
    buf.write(f"{n} atoms\n{model.n_bonds} bonds\n{len(model.angles)} angles\n")
    buf.write(f"{len(model.family_names)} atom types\n{max(1, len(model.bond_type_table))} "
              f"bond types\n")
    if len(model.angle_type_table):
        buf.write(f"{len(model.angle_type_table)} angle types\n")
    buf.write("\n")
    for k, axis in enumerate("xyz"):
        buf.write(f"{model.box_lo[k]:.12e} {model.box_hi[k]:.12e} {axis}lo {axis}hi\n")
    # atom_style hybrid wants per-type masses too; LAMMPS uses the per-atom ones
    buf.write("\nMasses\n\n")
    for t in range(1, len(model.family_names) + 1):
        of_type = model.masses[model.atom_types == t]
        buf.write(f"{t} {of_type.mean() if of_type.size else model.masses.mean():.9e}\n")
    buf.write("\nAtoms # hybrid\n\n")
    ids = np.arange(1, n + 1)
    atoms = np.column_stack([ids, model.atom_types, model.positions, model.diameters, density,
                             model.fibre_ids, model.images])
    _table(buf, atoms, "%d %d %.12e %.12e %.12e %.9e %.9e %d %d %d %d")
    if model.n_bonds:
        buf.write("\nBonds\n\n")
        bonds = np.column_stack([np.arange(1, model.n_bonds + 1), model.bond_types,
                                 model.bonds + 1])
        _table(buf, bonds, "%d %d %d %d")
    if len(model.angles):
        buf.write("\nAngles\n\n")
        angles = np.column_stack([np.arange(1, len(model.angles) + 1), model.angle_types,
                                  model.angles + 1])
        _table(buf, angles, "%d %d %d %d %d")
    Path(path).write_text(buf.getvalue())


_SECTIONS = {"Atoms", "Velocities", "Bonds", "Angles", "Masses", "Bond Coeffs",
             "Angle Coeffs", "Pair Coeffs", "PairIJ Coeffs", "Dihedrals", "Impropers"}


def _split_sections(text: str) -> tuple[list[str], dict[str, list[str]]]:
    header: list[str] = []
    sections: dict[str, list[str]] = {}
    current: list[str] | None = None
    for raw in text.splitlines()[1:]:
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if line in _SECTIONS:
            current = sections.setdefault(line, [])
            continue
        (header if current is None else current).append(line)
    return header, sections


def read_data(path: Path, meta: dict) -> BeadModel:
    """Read a LAMMPS data file written by fabmd or by LAMMPS ``write_data``."""
    text = Path(path).read_text()
    header, sections = _split_sections(text)
    lo = np.zeros(3)
    hi = np.zeros(3)
    for line in header:
        words = line.split()
        for k, axis in enumerate("xyz"):
            if words[-2:] == [f"{axis}lo", f"{axis}hi"]:
                lo[k], hi[k] = float(words[0]), float(words[1])
    if "Atoms" not in sections:
        raise InputError(f"{path}: no Atoms section")
    atoms = np.loadtxt(sections["Atoms"], ndmin=2)
    if atoms.shape[1] not in (8, 11):
        raise InputError(f"{path}: Atoms lines must have 8 or 11 columns "
                         f"(atom_style {ATOM_STYLE}), found {atoms.shape[1]}")
    atoms = atoms[np.argsort(atoms[:, 0])]
    ids = atoms[:, 0].astype(np.int64)
    if not np.array_equal(ids, np.arange(1, len(ids) + 1)):
        raise InputError(f"{path}: atom ids must run 1..N without gaps")
    diam = atoms[:, 5]
    mass = atoms[:, 6] * math.pi * diam**3 / 6.0
    images = atoms[:, 8:11].astype(np.int64) if atoms.shape[1] == 11 else None

    def _links(name: str, width: int) -> tuple[np.ndarray, np.ndarray]:
        if name not in sections:
            return np.zeros((0, width), np.int64), np.zeros(0, np.int64)
        rows = np.loadtxt(sections[name], dtype=np.int64, ndmin=2)
        rows = rows[np.argsort(rows[:, 0])]
        return rows[:, 2:2 + width] - 1, rows[:, 1]

    bonds, bond_types = _links("Bonds", 2)
    angles, angle_types = _links("Angles", 3)
    return BeadModel(
        positions=atoms[:, 2:5], diameters=diam, masses=mass,
        atom_types=atoms[:, 1].astype(np.int64), fibre_ids=atoms[:, 7].astype(np.int64),
        bonds=bonds, bond_types=bond_types,
        family_names=tuple(meta["families"]),
        bond_type_table=[BondType(**bt) for bt in meta["bond_types"]],
        fibre_yarn=np.asarray(meta["fibre_yarn"], np.int64),
        yarns=[Yarn(**y) for y in meta["yarns"]],
        box_lo=lo, box_hi=hi, periodic=tuple(meta.get("periodic", (False,) * 3)),
        images=images, angles=angles, angle_types=angle_types,
        angle_type_table=[AngleType(**a) for a in meta.get("angle_types", [])],
        info=meta.get("info", {}),
    )
