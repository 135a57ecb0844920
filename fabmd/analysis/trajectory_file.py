"""Reading ``trajectory.h5``, the H5MD file of every run folder (writer:
:mod:`fabmd.results.trajectory`).

Layout of ``trajectory.h5`` (H5MD 1.1 with the units module; every value carries a
``unit``; lengths in nanometres, a unit stock H5MD readers know, everything else SI)::

    /                      attrs fabmd_format="fabmd-trajectory", fabmd_format_version=3,
                           length_unit="nm", length_scale_m=1e-9 (stored length x scale = m)
    /h5md                  attrs version=[1, 1]; author/ (name: $FABMD_AUTHOR or the
                           login name; email: $FABMD_AUTHOR_EMAIL if set), creator/ (name,
                           version), modules/units (attrs version=[1, 0], system="SI")
    /particles/all/
        box/               attrs dimension=3, boundary=["periodic"|"none"] x 3
            edges/         step [nf], time [nf] s, value [nf, 3] nm (box lengths)
        position/          step, time, value [nf, N, 3] nm — unwrapped (fibres never torn
                           at periodic faces; wrap with the box if needed)
        velocity/          (optional) value [nf, N, 3] m s-1
        species [N]        family code = LAMMPS atom type (1-based)
        fibre_id [N]       virtual fibre = LAMMPS molecule id (1-based)
        yarn_id [N]        yarn (1-based)
        mass [N] kg, diameter [N] nm
    /connectivity/bonds    [nb, 2] 0-based bead indices; attr particles_group
    /observables/
        box_offset/        step, time, value [nf, 3] nm (lower box corner)
        box_tilt/          (a triclinic box: a sheared periodic cell) value
                           [nf, 3] nm, the tilt factors xy, xz, yz as LAMMPS has them;
                           edges are then the lengths lx, ly, lz of the untilted cell
                           (the box vectors are (lx,0,0), (xy,ly,0), (xz,yz,lz))
        bond_force/        (optional) value [nf, nb] N, axial force, > 0 in tension
    /parameters/fabmd      attrs family_names, yarn_names, yarn_families, model_json;
                           datasets fibre_yarn [n_fibres], bond_type [nb]

Every ``step`` dataset is one dataset hard-linked into each element. Readers
(:func:`open_trajectory`) refuse files of an unknown format or a newer version.
Versions 1 and 2 (fabmd before the units module) stored lengths in metres (2: with
``box_tilt``); fabmd reads them all and returns SI (:func:`read_lengths` scales by each
dataset's ``unit``). Stock MDAnalysis reads version 3 with no fabmd code, given a
topology, e.g. the run folder's data file::

    mda.Universe("model.data", "trajectory.h5", format="H5MD",
                 atom_style="id type x y z diameter density resid")   # positions in Å

:func:`fabmd.load` gives the same frames with yarns, fibres and SI units.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import FabmdError, InputError
from ..model.bead_model import BeadModel

FORMAT = "fabmd-trajectory"
#: the format version this fabmd writes, the newest it reads (1: metres; 2: metres, may
#: have box_tilt; 3: nanometres, units module)
FORMAT_VERSION = 3
#: the version of every file this fabmd writes, with or without box_tilt
BASE_VERSION = FORMAT_VERSION
H5MD_VERSION = (1, 1)
#: H5MD units module version
UNITS_MODULE_VERSION = (1, 0)
#: the unit lengths are stored in, and its size in metres
LENGTH_UNIT = "nm"
LENGTH_SCALE_M = 1e-9
#: length units fabmd reads: how many make a metre (versions 1 and 2 wrote "m")
_LENGTH_UNITS_PER_M = {"m": 1.0, "nm": 1e9, "Angstrom": 1e10}

TRAJECTORY_FILE = "trajectory.h5"


class TrajectoryFormatError(FabmdError):
    """A file is not a fabmd trajectory, or one of a version this fabmd cannot read."""


@dataclass
class Frame:
    """One trajectory frame (SI): unwrapped positions, box, optional extras."""

    step: int
    time: float
    box_lo: np.ndarray
    box_hi: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None = None
    bond_force: np.ndarray | None = None
    tilt: np.ndarray | None = None  # xy, xz, yz of a triclinic box [m]


def check_format(f, path: Path | str = "") -> int:
    """The format version of an open file; raise if it is not one this fabmd reads."""
    where = f" {path}" if path else ""
    fmt = f.attrs.get("fabmd_format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode()
    if fmt != FORMAT:
        raise TrajectoryFormatError(f"{where.strip() or 'file'} is not a fabmd trajectory "
                                    f"(fabmd_format = {fmt!r}, expected {FORMAT!r})")
    version = int(f.attrs.get("fabmd_format_version", -1))
    if not 1 <= version <= FORMAT_VERSION:
        raise TrajectoryFormatError(
            f"trajectory{where} has format version {version}; this fabmd reads versions "
            f"1..{FORMAT_VERSION} (update fabmd to read it)")
    return version


def format_version(path: Path) -> int:
    """The ``fabmd_format_version`` of a trajectory file."""
    with open_trajectory(path) as f:
        return int(f.attrs["fabmd_format_version"])


def open_trajectory(path: Path):
    """Open a trajectory read-only (an ``h5py.File``) after checking its format."""
    import h5py

    path = Path(path)
    if not path.exists():
        raise InputError(f"no trajectory at {path}")
    f = h5py.File(path, "r")
    try:
        check_format(f, path)
    except Exception:
        f.close()
        raise
    return f


def _units_per_m(dataset) -> float:
    unit = dataset.attrs.get("unit", "m")
    unit = unit.decode() if isinstance(unit, bytes) else str(unit)
    if unit not in _LENGTH_UNITS_PER_M:
        raise TrajectoryFormatError(f"{dataset.name} has the length unit {unit!r}; fabmd "
                                    f"reads {', '.join(_LENGTH_UNITS_PER_M)}")
    return _LENGTH_UNITS_PER_M[unit]


def length_scale_m(dataset) -> float:
    """Metres per stored unit of a length dataset (its ``unit``: m, nm or Angstrom)."""
    return 1.0 / _units_per_m(dataset)


def read_lengths(dataset, index=()) -> np.ndarray:
    """``dataset[index]`` of a length dataset in metres, whatever unit the file used
    (to within an ulp of the value written)."""
    return np.asarray(dataset[index], float) / _units_per_m(dataset)


def _strings(values) -> list[str]:
    return [v.decode() if isinstance(v, bytes) else str(v) for v in values]


def read_model(path: Path, frame: int = -1) -> BeadModel:
    """The bead model stored in a trajectory, with the positions of one frame (a tilted
    box's tilt is not part of a bead model: see :func:`read_tilt`)."""
    from ..model.bead_model import AngleType, BondType, Yarn

    with open_trajectory(path) as f:
        meta = json.loads(f["parameters/fabmd"].attrs["model_json"])
        part = f["particles/all"]
        positions = read_lengths(part["position/value"], frame)
        lengths = read_lengths(part["box/edges/value"], frame)
        lo = read_lengths(f["observables/box_offset/value"], frame)
        species = part["species"][()]
        fibre_ids = part["fibre_id"][()]
        masses = part["mass"][()]
        diameters = read_lengths(part["diameter"])
        bonds = f["connectivity/bonds"][()]
        bond_types = f["parameters/fabmd/bond_type"][()]
    return BeadModel(
        positions=positions, diameters=diameters, masses=masses, atom_types=species,
        fibre_ids=fibre_ids, bonds=bonds, bond_types=bond_types,
        family_names=tuple(meta["families"]),
        bond_type_table=[BondType(**bt) for bt in meta["bond_types"]],
        fibre_yarn=meta["fibre_yarn"], yarns=[Yarn(**y) for y in meta["yarns"]],
        box_lo=lo, box_hi=lo + lengths, periodic=tuple(meta.get("periodic", [False] * 3)),
        angle_type_table=[AngleType(**a) for a in meta.get("angle_types", [])],
        info=meta.get("info", {}))


def read_tilt(path: Path, frame: int = -1) -> np.ndarray | None:
    """Tilt factors (xy, xz, yz) [m] of one frame's box; None for an orthogonal box."""
    with open_trajectory(path) as f:
        tilt = f["observables"].get("box_tilt")
        return None if tilt is None else read_lengths(tilt["value"], frame)


def trajectory_path(path: Path) -> Path:
    """``path`` itself if it is a file, else ``path/trajectory.h5``."""
    path = Path(path)
    return path / TRAJECTORY_FILE if path.is_dir() else path


def frame_count(path: Path) -> int:
    with open_trajectory(trajectory_path(path)) as f:
        return int(f["particles/all/position/value"].shape[0])
