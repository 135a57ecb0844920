"""The bead model: every bead, bond and angle of a virtual-fibre system.

:class:`BeadModel` is the hand-over point of the pipeline: geometry renders
into it, the LAMMPS scene writes it as a data file, results read it back.
Arrays are SI; indices into ``positions`` are 0-based, LAMMPS ids 1-based.

Identity of a bead:

* ``atom_types``   — 1-based; one type per yarn family (``family_names``);
* ``fibre_ids``    — 1-based LAMMPS molecule id, one per virtual fibre (beads of
  one fibre never contact each other);
* ``fibre_yarn``   — yarn id (1-based) of each fibre, so ``yarn_ids`` per bead
  follow; ``yarns`` names each yarn and its family.

Invariant: the beads of one fibre are contiguous and ordered along the fibre
(first bead = one end). A periodic fibre closes with a bond from its last bead
to its first across the box face. ``info`` carries JSON-able facts about where
the model came from (fabric, unit cell, tiling) for later stages.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError
from .lammps_data import read_data, write_data

MODEL_FORMAT = "fabmd-bead-model"
MODEL_FORMAT_VERSION = 1


@dataclass(frozen=True)
class BondType:
    """One LAMMPS bond type: ``bond harmonic`` K [J/m²], rest length r0 [m], family.

    ``kind`` is ``"fibre"`` for the bonds along a virtual fibre and ``"cohesion"`` for the
    bonds that hold the fibres of one yarn together (:mod:`fabmd.model.cohesion`); measures
    of fibres (crimp, tension, length) use the fibre bonds only. ``spec`` names the yarn
    spec whose fibres the type joins.
    """

    coefficient: float
    rest_length_m: float
    family: str
    axial_stiffness_n: float = 0.0
    kind: str = "fibre"
    #: yarn spec key (``Fabric.yarn_spec_table``): the family, or "<family>:<k>" for the
    #: yarns of override k; "" where unknown (models saved before overrides)
    spec: str = ""

    @property
    def spring_n_per_m(self) -> float:
        """Axial spring of one bond, k = 2·K [N/m] (``bond harmonic`` is E = K(r − r0)²)."""
        return 2 * self.coefficient

    @property
    def bond_axial_stiffness_n(self) -> float:
        """E·A the bond carries, k·r0 = 2·K·r0 [N] (recovered from the coefficient: also
        for cohesion links and models saved without ``axial_stiffness_n``)."""
        return 2 * self.coefficient * self.rest_length_m


@dataclass(frozen=True)
class AngleType:
    """One LAMMPS angle type: bending coefficient K = E·I/l0 [J] (``angle cosine``: a
    straight rest shape), family."""

    coefficient: float
    family: str


@dataclass(frozen=True)
class Yarn:
    """A yarn: its name (e.g. ``"warp-3"``) and family (``"warp"``, ``"weft"``, ``"binder"``)."""

    name: str
    family: str


@dataclass
class BeadModel:
    """All beads, bonds and angles of a system; see the module docstring."""

    positions: np.ndarray
    diameters: np.ndarray
    masses: np.ndarray
    atom_types: np.ndarray
    fibre_ids: np.ndarray
    bonds: np.ndarray
    bond_types: np.ndarray
    family_names: tuple[str, ...]
    bond_type_table: list[BondType]
    fibre_yarn: np.ndarray
    yarns: list[Yarn]
    box_lo: np.ndarray
    box_hi: np.ndarray
    periodic: tuple[bool, bool, bool] = (False, False, False)
    images: np.ndarray | None = None
    angles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    angle_types: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    angle_type_table: list[AngleType] = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        self.positions = np.asarray(self.positions, dtype=float).reshape(-1, 3)
        n = len(self.positions)
        self.diameters = np.broadcast_to(np.asarray(self.diameters, float), (n,)).copy()
        self.masses = np.broadcast_to(np.asarray(self.masses, float), (n,)).copy()
        self.atom_types = np.broadcast_to(np.asarray(self.atom_types, np.int64), (n,)).copy()
        self.fibre_ids = np.asarray(self.fibre_ids, np.int64).reshape(n)
        self.bonds = np.asarray(self.bonds, np.int64).reshape(-1, 2)
        self.bond_types = np.broadcast_to(np.asarray(self.bond_types, np.int64),
                                          (len(self.bonds),)).copy()
        self.angles = np.asarray(self.angles, np.int64).reshape(-1, 3)
        self.angle_types = np.broadcast_to(np.asarray(self.angle_types, np.int64),
                                           (len(self.angles),)).copy()
        self.fibre_yarn = np.asarray(self.fibre_yarn, np.int64).reshape(-1)
        self.box_lo = np.asarray(self.box_lo, float).reshape(3)
        self.box_hi = np.asarray(self.box_hi, float).reshape(3)
        self.periodic = tuple(bool(p) for p in self.periodic)
        self.images = (np.zeros((n, 3), np.int64) if self.images is None
                       else np.asarray(self.images, np.int64).reshape(n, 3))
        self.family_names = tuple(self.family_names)
        self.check()

    # -- derived ----------------------------------------------------------------------
    @property
    def n_beads(self) -> int:
        return len(self.positions)

    @property
    def n_bonds(self) -> int:
        return len(self.bonds)

    @property
    def n_fibres(self) -> int:
        return len(self.fibre_yarn)

    @property
    def yarn_ids(self) -> np.ndarray:
        """1-based yarn id of every bead."""
        return self.fibre_yarn[self.fibre_ids - 1]

    @property
    def families(self) -> np.ndarray:
        """Family name of every bead."""
        return np.asarray(self.family_names, dtype=object)[self.atom_types - 1]

    @property
    def unwrapped_positions(self) -> np.ndarray:
        """Positions plus image flags × box length (continuous across periodic faces)."""
        return self.positions + self.images * (self.box_hi - self.box_lo)

    def fibre_bond_mask(self) -> np.ndarray:
        """True for the bonds along a virtual fibre (not cohesion bonds)."""
        fibre = np.array([bt.kind == "fibre" for bt in self.bond_type_table], bool)
        return fibre[self.bond_types - 1] if self.n_bonds else np.zeros(0, bool)

    def fibre_bond_types(self) -> list[BondType]:
        """The bond types of fibre bonds."""
        return [bt for bt in self.bond_type_table if bt.kind == "fibre"]

    def bond_lengths(self) -> np.ndarray:
        """Current length of every bond (minimum image in periodic directions) [m]."""
        d = self.positions[self.bonds[:, 1]] - self.positions[self.bonds[:, 0]]
        length = self.box_hi - self.box_lo
        for k in range(3):
            if self.periodic[k]:
                d[:, k] -= length[k] * np.round(d[:, k] / length[k])
        return np.linalg.norm(d, axis=1)

    def fibre_ends(self) -> np.ndarray:
        """(n_fibres, 2) indices of the first and last bead of every fibre."""
        starts = np.searchsorted(self.fibre_ids, np.arange(1, self.n_fibres + 1), side="left")
        stops = np.searchsorted(self.fibre_ids, np.arange(1, self.n_fibres + 1), side="right")
        return np.column_stack([starts, stops - 1])

    def beads_of_family(self, family: str) -> np.ndarray:
        """Indices of the beads of one yarn family."""
        if family not in self.family_names:
            raise InputError(f"family must be one of {list(self.family_names)}, got {family!r}")
        return np.flatnonzero(self.atom_types == self.family_names.index(family) + 1)

    # -- checks -----------------------------------------------------------------------
    def check(self) -> None:
        """Raise :class:`InputError` if arrays are inconsistent."""
        n = self.n_beads
        if n == 0:
            raise InputError("bead model has no beads")
        if not np.all(np.isfinite(self.positions)):
            raise InputError("bead model has non-finite positions")
        if np.any(self.diameters <= 0) or np.any(self.masses <= 0):
            raise InputError("every bead needs a diameter > 0 and a mass > 0")
        if self.atom_types.min() < 1 or self.atom_types.max() > len(self.family_names):
            raise InputError(f"atom types must be 1..{len(self.family_names)}")
        if self.fibre_ids.min() < 1 or self.fibre_ids.max() > len(self.fibre_yarn):
            raise InputError(f"fibre ids must be 1..{len(self.fibre_yarn)}")
        if len(self.fibre_yarn) and (self.fibre_yarn.min() < 1
                                     or self.fibre_yarn.max() > len(self.yarns)):
            raise InputError(f"fibre_yarn must name yarns 1..{len(self.yarns)}")
        if len(self.bonds):
            if self.bonds.min() < 0 or self.bonds.max() >= n:
                raise InputError("bond refers to a bead that does not exist")
            if np.any(self.bonds[:, 0] == self.bonds[:, 1]):
                raise InputError("a bond joins a bead to itself")
            if self.bond_types.min() < 1 or self.bond_types.max() > len(self.bond_type_table):
                raise InputError(f"bond types must be 1..{len(self.bond_type_table)}")
        kinds = {bt.kind for bt in self.bond_type_table} - {"fibre", "cohesion"}
        if kinds:
            raise InputError(f"bond type kind must be 'fibre' or 'cohesion', got {sorted(kinds)}")
        if len(self.angles) and (self.angle_types.min() < 1
                                 or self.angle_types.max() > len(self.angle_type_table)):
            raise InputError(f"angle types must be 1..{len(self.angle_type_table)}")
        if np.any(self.box_hi <= self.box_lo):
            raise InputError("box_hi must exceed box_lo in every direction")

    # -- metadata (what the LAMMPS data file cannot hold) --------------------------------
    def metadata(self) -> dict:
        """JSON-able description of types, yarns and fibres."""
        return {
            "format": MODEL_FORMAT,
            "version": MODEL_FORMAT_VERSION,
            "units": "si",
            "n_beads": self.n_beads,
            "n_bonds": self.n_bonds,
            "n_angles": len(self.angles),
            "families": list(self.family_names),
            "bond_types": [bt.__dict__ for bt in self.bond_type_table],
            "angle_types": [at.__dict__ for at in self.angle_type_table],
            "yarns": [y.__dict__ for y in self.yarns],
            "fibre_yarn": self.fibre_yarn.tolist(),
            "periodic": list(self.periodic),
            "info": self.info,
        }

    def save(self, folder: Path, stem: str = "model") -> tuple[Path, Path]:
        """Write ``<stem>.data`` (LAMMPS) and ``<stem>.json`` (metadata) into ``folder``."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        data = folder / f"{stem}.data"
        meta = folder / f"{stem}.json"
        write_data(self, data)
        meta.write_text(json.dumps(self.metadata(), indent=1))
        return data, meta

    @classmethod
    def load(cls, data_path: Path, metadata_path: Path | None = None) -> BeadModel:
        """Read a model back from a LAMMPS data file (ours or ``write_data``'s) + metadata."""
        data_path = Path(data_path)
        if metadata_path is None:
            metadata_path = data_path.with_suffix(".json")
        meta = json.loads(Path(metadata_path).read_text())
        if meta.get("format") != MODEL_FORMAT or meta.get("version", 0) > MODEL_FORMAT_VERSION:
            raise InputError(f"{metadata_path} is not a fabmd bead model metadata file "
                             f"(format {meta.get('format')!r}, version {meta.get('version')})")
        return cls(
            **read_data(data_path),
            family_names=tuple(meta["families"]),
            bond_type_table=[BondType(**bt) for bt in meta["bond_types"]],
            fibre_yarn=np.asarray(meta["fibre_yarn"], np.int64),
            yarns=[Yarn(**y) for y in meta["yarns"]],
            periodic=tuple(meta.get("periodic", (False,) * 3)),
            angle_type_table=[_angle_type(a) for a in meta.get("angle_types", [])],
            info=meta.get("info", {}),
        )


def _angle_type(entry: dict) -> AngleType:
    """An angle type from ``model.json`` (files with a bent rest shape are refused)."""
    if entry.get("rest_angle_deg") not in (None, 180.0):
        raise InputError("this model was saved by an older fabmd with a bent rest shape for "
                         "its bending terms, which is no longer supported "
                         "(fabmd.model.bending); cut the coupon again")
    return AngleType(entry["coefficient"], entry["family"])
