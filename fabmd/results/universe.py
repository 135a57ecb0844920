"""Results as MDAnalysis universes: ``fabmd.load(path)``.

Beads are atoms, virtual fibres are residues, yarns are segments:

========================  ===============================================
``u.select_atoms(...)``   selects
========================  ===============================================
``"segid warp-3"``        the beads of yarn ``warp-3``
``"segid binder*"``       every binder yarn (yarn names start with the family)
``"resname binder"``      every bead of the binder family (residue name = family)
``"type weft"``           the same, by atom type (= family name)
``"resid 12"``            virtual fibre 12 (= LAMMPS molecule id)
========================  ===============================================

Positions are in SI metres and time in seconds (the file stores lengths in nm; this
reader scales them to metres where stock MDAnalysis would give ångströms).
Positions are unwrapped, so fibres are continuous across periodic faces
(``u.bonds.values(pbc=True)`` gives true bond lengths even for the bond that closes
a periodic fibre). Per-bond forces [N] (> 0 in tension) of the current frame are in
``u.trajectory.ts.data["bond_force"]`` in the file's bond order
(``/connectivity/bonds``, the bead model's); :func:`bond_forces` gives them in the
order of ``u.bonds`` (which MDAnalysis sorts). ``u.fabmd`` holds the family names,
the periodicity, the source path and that bond order. A sheared periodic cell (a
trajectory with ``box_tilt``) gets triclinic ``dimensions``.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

from ..analysis.trajectory_file import (
    TRAJECTORY_FILE,
    length_scale_m,
    open_trajectory,
    read_lengths,
)
from ..errors import InputError
from ..model.bead_model import BeadModel

#: data files a run folder may hold, in the order :func:`load` prefers them without a trajectory
DATA_FILES = ("final.data", "model.data")


def data_file_bond_count(path: Path) -> int:
    """The ``N bonds`` count in the header of a LAMMPS data file."""
    with open(path) as f:
        next(f, None)
        for line in f:
            words = line.split("#", 1)[0].split()
            if len(words) == 2 and words[1] == "bonds":
                return int(words[0])
            if words and words[0] in ("Atoms", "Masses", "Bonds"):
                break
    return 0


def _build(n_atoms: int, fibre_ids, fibre_yarn, family_names, atom_types, yarn_names,
           yarn_families, masses, diameters, bonds, bond_types):
    import MDAnalysis as mda

    fibre_ids = np.asarray(fibre_ids, np.int64)
    fibre_yarn = np.asarray(fibre_yarn, np.int64)
    families = np.asarray(family_names, dtype=object)
    u = mda.Universe.empty(n_atoms, n_residues=len(fibre_yarn), n_segments=len(yarn_names),
                           atom_resindex=fibre_ids - 1, residue_segindex=fibre_yarn - 1,
                           trajectory=False)
    u.add_TopologyAttr("ids", np.arange(1, n_atoms + 1))
    u.add_TopologyAttr("types", families[np.asarray(atom_types) - 1].astype(str))
    u.add_TopologyAttr("names", np.full(n_atoms, "B"))
    u.add_TopologyAttr("masses", np.asarray(masses, float))
    u.add_TopologyAttr("radii", 0.5 * np.asarray(diameters, float))
    u.add_TopologyAttr("resids", np.arange(1, len(fibre_yarn) + 1))
    yarn_families = np.asarray(yarn_families, dtype=object)
    u.add_TopologyAttr("resnames", yarn_families[fibre_yarn - 1].astype(str))
    u.add_TopologyAttr("segids", np.asarray(yarn_names, dtype=str))
    bonds = np.asarray(bonds, np.int64).reshape(-1, 2)
    if len(bonds):
        u.add_bonds([tuple(b) for b in bonds.tolist()],
                    types=[str(t) for t in np.asarray(bond_types).tolist()])
    return u


@functools.cache
def reader_class():
    """MDAnalysis's H5MD reader that also knows the SI units fabmd writes (m, s, N).

    Values are never converted (``convert_units=False``): fabmd keeps SI.
    """
    from MDAnalysis.coordinates.H5MD import H5MDReader

    class FabmdH5MDReader(H5MDReader):
        format = "FABMD-H5MD"
        _unit_translation = {kind: dict(table)
                             for kind, table in H5MDReader._unit_translation.items()}
        _unit_translation["length"]["m"] = "m"

        def __init__(self, filename, convert_units=False, **kwargs):
            super().__init__(filename, convert_units=False, **kwargs)
            if self.units.get("length"):
                self.units["length"] = "m"  # _read_frame scales stored lengths to metres

        def _read_frame(self, frame):
            ts = super()._read_frame(frame)
            # to metres: lengths are stored in nm (format 3) or m (1, 2)
            part, obs = self._particle_group, self._file.get("observables", {})
            if ts.has_positions:
                ts.positions *= length_scale_m(part["position/value"])
            if ts.dimensions is not None:
                dims = ts.dimensions
                dims[:3] *= length_scale_m(part["box/edges/value"])
                ts.dimensions = dims
            for name in ("box_offset", "box_tilt"):
                if name in ts.data and name in obs:
                    ts.data[name] = np.asarray(ts.data[name], float) * length_scale_m(
                        obs[name]["value"])
            tilt = ts.data.get("box_tilt")
            if tilt is not None and ts.dimensions is not None:  # a sheared periodic cell
                from MDAnalysis.lib.mdamath import triclinic_box

                lx, ly, lz = ts.dimensions[:3]
                xy, xz, yz = (float(t) for t in tilt)
                ts.dimensions = triclinic_box([lx, 0, 0], [xy, ly, 0], [xz, yz, lz])
            return ts

    return FabmdH5MDReader


def universe_from_trajectory(path: Path):
    """A Universe with the topology and frames of a ``trajectory.h5``."""
    path = Path(path)
    with open_trajectory(path) as f:
        part = f["particles/all"]
        params = f["parameters/fabmd"]
        meta = json.loads(params.attrs["model_json"])
        names = [str(v) for v in meta["families"]]
        yarns = meta["yarns"]
        n_frames = part["position/value"].shape[0]
        bonds = f["connectivity/bonds"][()]
        u = _build(part["species"].shape[0], part["fibre_id"][()], params["fibre_yarn"][()],
                   names, part["species"][()], [y["name"] for y in yarns],
                   [y["family"] for y in yarns], part["mass"][()],
                   read_lengths(part["diameter"]),
                   bonds, params["bond_type"][()])
    if n_frames == 0:
        raise InputError(f"{path} holds no frames")
    u.load_new(str(path), format=reader_class())
    u.fabmd = {"path": str(path), "family_names": names,
               "periodic": list(meta.get("periodic", [False] * 3)), "source": "trajectory",
               "bond_order": bond_order(u, bonds)}
    return u


def bond_order(u, model_bonds: np.ndarray) -> np.ndarray:
    """For each bond of ``u.bonds``, its index in ``model_bonds`` (the file's order)."""
    model_bonds = np.asarray(model_bonds, np.int64).reshape(-1, 2)
    if not len(model_bonds):
        return np.zeros(0, np.int64)
    n = u.atoms.n_atoms
    keys = np.minimum(model_bonds[:, 0], model_bonds[:, 1]) * n + model_bonds.max(axis=1)
    ub = u.bonds.indices.astype(np.int64)
    wanted = np.minimum(ub[:, 0], ub[:, 1]) * n + ub.max(axis=1)
    order = np.argsort(keys, kind="stable")
    return order[np.searchsorted(keys[order], wanted)]


def universe_from_model(model: BeadModel, source: str = "model"):
    """A one-frame Universe of a bead model (unwrapped positions, SI)."""
    from MDAnalysis.coordinates.memory import MemoryReader

    u = _build(model.n_beads, model.fibre_ids, model.fibre_yarn, model.family_names,
               model.atom_types, [y.name for y in model.yarns], [y.family for y in model.yarns],
               model.masses, model.diameters, model.bonds, model.bond_types)
    lengths = model.box_hi - model.box_lo
    u.load_new(model.unwrapped_positions[None].astype(np.float32), format=MemoryReader,
               dimensions=np.array([*lengths, 90.0, 90.0, 90.0]))
    u.fabmd = {"path": source, "family_names": list(model.family_names),
               "periodic": list(model.periodic), "source": "model",
               "bond_order": bond_order(u, model.bonds)}
    return u


def load(path: str | Path, *, check_bonds: bool = True):
    """Open a result as an MDAnalysis ``Universe`` with bonds, fibres and yarns.

    Args:
        path: a run folder (its ``trajectory.h5``; without one, its ``final.data``
            or ``model.data`` as a single frame), a ``trajectory.h5`` file, or a
            fabmd LAMMPS data file (with its ``.json`` beside it).
        check_bonds: compare the bond count with the run folder's ``model.data``.

    Raises:
        InputError: nothing fabmd can read at ``path``, or the bond count differs
            from the data file's.
        TrajectoryFormatError: the trajectory is of an unknown format version.
    """
    path = Path(path)
    if not path.exists():
        raise InputError(f"no fabmd result at {path}")
    folder = path if path.is_dir() else path.parent
    if path.is_dir() and (path / TRAJECTORY_FILE).exists():
        u = universe_from_trajectory(path / TRAJECTORY_FILE)
    elif path.is_file() and path.suffix in (".h5", ".h5md", ".hdf5"):
        u = universe_from_trajectory(path)
    else:
        data = path if path.is_file() else next(
            (path / name for name in DATA_FILES if (path / name).exists()), None)
        if data is None or data.suffix != ".data":
            raise InputError(f"{path} holds no {TRAJECTORY_FILE} and no LAMMPS data file "
                             f"({', '.join(DATA_FILES)})")
        meta = data.with_suffix(".json")
        if not meta.exists():
            meta = folder / "model.json"
        u = universe_from_model(BeadModel.load(data, meta), source=str(data))
    reference = folder / "model.data"
    if check_bonds and reference.exists():
        expected = data_file_bond_count(reference)
        if len(u.bonds) != expected:
            raise InputError(f"{path}: {len(u.bonds)} bonds loaded but {reference} has "
                             f"{expected}; the trajectory does not belong to this run folder")
    return u


def select_family(u, family: str):
    """The beads of one yarn family (``u.select_atoms("resname <family>")``)."""
    families = getattr(u, "fabmd", {}).get("family_names")
    if families is not None and family not in families:
        raise InputError(f"family must be one of {families}, got {family!r}")
    return u.select_atoms(f"resname {family}")


def select_yarn(u, name: str):
    """The beads of one yarn by name (``u.select_atoms("segid <name>")``)."""
    group = u.select_atoms(f"segid {name}")
    if group.n_atoms == 0:
        raise InputError(f"no yarn named {name!r}; yarns: {' '.join(u.segments.segids[:20])}")
    return group


def bond_forces(u) -> np.ndarray | None:
    """Axial force [N] (> 0 in tension) of every bond of ``u.bonds`` (same order) in the
    current frame; None when the trajectory holds no bond forces."""
    value = u.trajectory.ts.data.get("bond_force")
    if value is None:
        return None
    order = getattr(u, "fabmd", {}).get("bond_order")
    value = np.asarray(value, float)
    return value if order is None else value[order]
