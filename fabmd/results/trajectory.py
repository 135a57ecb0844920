"""Trajectories in the H5MD layout: ``trajectory.h5`` in every run folder.

LAMMPS here has no H5MD dump, so a protocol's outputs block
(:class:`fabmd.scene.outputs.TrajectoryOutput`) makes LAMMPS write a sorted
binary dump (``trajectory.bin``) and a bond dump (``bonds.dump``) on rank 0;
after the run :func:`finalise` (rank 0 only) turns them into ``trajectory.h5``
and the ParaView series ``trajectory.pvd`` + ``paraview/frame_*.vtu``. The
dumps stay beside them for OVITO.

The file's layout and its readers: :mod:`fabmd.analysis.trajectory_file`.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..analysis.trajectory_file import (  # noqa: F401 - the reader's names, as before
    _LENGTH_UNITS_PER_M,
    BASE_VERSION,
    FORMAT,
    FORMAT_VERSION,
    H5MD_VERSION,
    LENGTH_SCALE_M,
    LENGTH_UNIT,
    TRAJECTORY_FILE,
    UNITS_MODULE_VERSION,
    Frame,
    TrajectoryFormatError,
    check_format,
    format_version,
    frame_count,
    length_scale_m,
    open_trajectory,
    read_lengths,
    read_model,
    read_tilt,
    trajectory_path,
)
from ..engine import mpi
from ..errors import InputError
from ..model.bead_model import BeadModel
from ..scene.outputs import BOND_DUMP_FILE, DUMP_FILE
from .paraview import PARAVIEW_DIR, PVD_FILE  # noqa: F401 - file names of a run folder

#: gzip (readable by every HDF5 build, ParaView and h5py alike) after byte shuffling;
#: level 1: higher levels cost more time and gain little on floating-point data
COMPRESSION = {"compression": "gzip", "compression_opts": 1, "shuffle": True}


class TrajectoryWriter:
    """Write frames of one bead model into an H5MD file (serial; call on rank 0).

    The file is written as ``<path>.part`` and renamed when closed, so a reader
    never sees half a file.

    Args:
        path: the ``.h5`` file to write.
        model: the bead model (topology, yarns, families, masses, diameters).
        velocities: frames carry velocities.
        bond_data: frames carry bond forces.
    """

    def __init__(self, path: Path, model: BeadModel, *, velocities: bool = False,
                 bond_data: bool = False):
        import h5py

        from ..version import __version__

        self.path = Path(path)
        self.partial = self.path.with_name(self.path.name + ".part")
        self.model = model
        self.velocities = velocities
        self.bond_data = bond_data and model.n_bonds > 0
        n, nb = model.n_beads, model.n_bonds
        self.n_frames = 0
        f = self.file = h5py.File(self.partial, "w")
        f.attrs["fabmd_format"] = FORMAT
        f.attrs["fabmd_format_version"] = BASE_VERSION
        h5md = f.create_group("h5md")
        h5md.attrs["version"] = np.array(H5MD_VERSION, dtype=np.int32)
        author = h5md.create_group("author")
        author.attrs["name"], email = file_author()
        if email:
            author.attrs["email"] = email
        units = h5md.create_group("modules/units")
        units.attrs["version"] = np.array(UNITS_MODULE_VERSION, dtype=np.int32)
        units.attrs["system"] = "SI"
        f.attrs["length_unit"] = LENGTH_UNIT
        f.attrs["length_scale_m"] = LENGTH_SCALE_M
        creator = h5md.create_group("creator")
        creator.attrs["name"] = "fabmd"
        creator.attrs["version"] = __version__

        part = f.create_group("particles/all")
        self.step = f.create_dataset("step", shape=(0,), maxshape=(None,), dtype=np.int64,
                                     chunks=(1024,))
        self.time = f.create_dataset("time", shape=(0,), maxshape=(None,), dtype=np.float64,
                                     chunks=(1024,))
        self.time.attrs["unit"] = "s"
        box = part.create_group("box")
        box.attrs["dimension"] = np.int32(3)
        box.attrs["boundary"] = np.array(["periodic" if p else "none" for p in model.periodic],
                                         dtype=h5py.string_dtype())
        self.edges = self._element(box, "edges", (3,), LENGTH_UNIT, compress=False)
        self.position = self._element(part, "position", (n, 3), LENGTH_UNIT)
        self.velocity = (self._element(part, "velocity", (n, 3), "m s-1") if velocities
                         else None)
        for name, values, unit in (("species", model.atom_types, None),
                                   ("fibre_id", model.fibre_ids, None),
                                   ("yarn_id", model.yarn_ids, None),
                                   ("mass", model.masses, "kg"),
                                   ("diameter", model.diameters, LENGTH_UNIT)):
            dtype = np.int32 if unit is None else np.float64
            values = np.asarray(values, dtype=dtype)
            if unit == LENGTH_UNIT:
                values = values * _LENGTH_UNITS_PER_M[LENGTH_UNIT]
            d = part.create_dataset(name, data=values)
            if unit:
                d.attrs["unit"] = unit
        bonds = f.create_group("connectivity").create_dataset(
            "bonds", data=np.asarray(model.bonds, np.int32).reshape(-1, 2))
        bonds.attrs["particles_group"] = part.ref
        obs = self.observables = f.create_group("observables")
        self.offset = self._element(obs, "box_offset", (3,), LENGTH_UNIT, compress=False)
        self.tilt = None  # created by the first frame of a tilted box
        if self.bond_data:
            self.bond_force = self._element(obs, "bond_force", (nb,), "N")
            self.bond_force.attrs["sign"] = "positive in tension"
        params = f.create_group("parameters/fabmd")
        params.attrs["family_names"] = np.array(model.family_names, dtype=h5py.string_dtype())
        params.attrs["yarn_names"] = np.array([y.name for y in model.yarns],
                                              dtype=h5py.string_dtype())
        params.attrs["yarn_families"] = np.array([y.family for y in model.yarns],
                                                 dtype=h5py.string_dtype())
        params.attrs["model_json"] = json.dumps(model.metadata())
        params.create_dataset("fibre_yarn", data=np.asarray(model.fibre_yarn, np.int32))
        params.create_dataset("bond_type", data=np.asarray(model.bond_types, np.int32))
        # step and time live on through the hard links of the elements
        del f["step"], f["time"]

    def _element(self, group, name: str, shape: tuple[int, ...], unit: str,
                 compress: bool = True):
        """A time-dependent H5MD element: hard links to step and time, plus value."""
        g = group.create_group(name)
        g["step"] = self.step
        g["time"] = self.time
        chunk_rows = shape[0] if len(shape) == 1 else min(shape[0], 1 << 16)
        chunks = (1, chunk_rows) + tuple(shape[1:])
        options = COMPRESSION if compress and np.prod(shape) > 64 else {}
        value = g.create_dataset("value", shape=(0,) + shape, maxshape=(None,) + shape,
                                 dtype=np.float64, chunks=chunks, **options)
        value.attrs["unit"] = unit
        return value

    def append(self, step: int, time: float, box_lo, box_hi, positions, velocities=None,
               bond_force=None, tilt=None) -> None:
        """Add one frame (positions unwrapped, SI; ``tilt``: xy, xz, yz of a triclinic box)."""
        i = self.n_frames
        if tilt is not None and self.tilt is None:
            self.tilt = self._element(self.observables, "box_tilt", (3,), LENGTH_UNIT,
                                      compress=False)
            self.tilt.resize(i, axis=0)  # earlier frames (none, in practice): untilted
        self.n_frames += 1
        self.step.resize((i + 1,))
        self.time.resize((i + 1,))
        self.step[i] = step
        self.time[i] = time
        box_lo = np.asarray(box_lo, float)
        per_m = _LENGTH_UNITS_PER_M[LENGTH_UNIT]
        for ds, value, scale in ((self.edges, np.asarray(box_hi, float) - box_lo, per_m),
                                 (self.offset, box_lo, per_m),
                                 (self.position, positions, per_m),
                                 (self.velocity, velocities, 1.0)):
            if ds is None:
                continue
            if value is None:
                raise InputError(f"frame {i}: {ds.name} was announced but not given")
            ds.resize(i + 1, axis=0)
            ds[i] = np.asarray(value, float) * scale
        if self.bond_data:
            self.bond_force.resize(i + 1, axis=0)
            self.bond_force[i] = np.nan if bond_force is None else bond_force
        if self.tilt is not None:
            self.tilt.resize(i + 1, axis=0)
            self.tilt[i] = 0.0 if tilt is None else np.asarray(tilt, float) * per_m

    def close(self) -> Path:
        """Close and move the file into place; returns its path."""
        if self.file:
            self.file.close()
            self.file = None
            os.replace(self.partial, self.path)
        return self.path

    def abort(self) -> None:
        """Close and delete the partial file."""
        if self.file:
            self.file.close()
            self.file = None
        self.partial.unlink(missing_ok=True)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            self.close()
        else:
            self.abort()


def _bond_index(model: BeadModel) -> tuple[np.ndarray, np.ndarray]:
    """Sorted pair keys of the model's bonds and the bond index of each key."""
    a, b = model.bonds[:, 0], model.bonds[:, 1]
    keys = np.minimum(a, b) * model.n_beads + np.maximum(a, b)
    order = np.argsort(keys, kind="stable")
    return keys[order], order


def frames_from_dumps(model: BeadModel, dump: Path, bond_dump: Path | None = None
                      ) -> Iterator[Frame]:
    """Frames of a run's dumps, with bond data put into the model's bond order."""
    from ..engine.lammps_dump import iter_dump

    bond_frames = iter_dump(bond_dump) if bond_dump is not None else None
    keys, order = _bond_index(model) if bond_dump is not None else (None, None)
    pending = None
    n = model.n_beads
    last_step = None
    for fr in iter_dump(dump):
        if fr.step == last_step:  # a step written twice (a run set up again): once only
            continue
        last_step = fr.step
        if fr.data.shape[0] != n:
            raise InputError(f"{dump}: frame at step {fr.step} has {fr.data.shape[0]} beads, "
                             f"the model {n}")
        ids = fr.column("id").astype(np.int64)
        if not np.array_equal(ids, np.arange(1, n + 1)):
            rows = np.argsort(ids)
            fr.data = fr.data[rows]
        if "xu" in fr.columns:
            pos = np.column_stack([fr.column(c) for c in ("xu", "yu", "zu")])
        else:  # wrapped positions and image flags
            image = np.column_stack([fr.column(c) for c in ("ix", "iy", "iz")])
            pos = (np.column_stack([fr.column(c) for c in ("x", "y", "z")])
                   + image * (fr.box_hi - fr.box_lo))
        vel = (np.column_stack([fr.column(c) for c in ("vx", "vy", "vz")])
               if "vx" in fr.columns else None)
        frame = Frame(step=fr.step, time=fr.time if fr.time is not None else np.nan,
                      box_lo=fr.box_lo, box_hi=fr.box_hi, positions=pos, velocities=vel,
                      tilt=fr.tilt)
        if bond_frames is not None:
            while pending is None or pending.step < fr.step:
                pending = next(bond_frames, None)
                if pending is None:
                    break
            if pending is not None and pending.step == fr.step:
                frame.bond_force = _bonds_in_model_order(model, keys, order, pending)
        yield frame


def _bonds_in_model_order(model, keys, order, fr) -> np.ndarray:
    a = fr.column("batom1").astype(np.int64) - 1
    b = fr.column("batom2").astype(np.int64) - 1
    k = np.minimum(a, b) * model.n_beads + np.maximum(a, b)
    where = np.searchsorted(keys, k)
    where = np.clip(where, 0, len(keys) - 1)
    found = keys[where] == k
    force = np.full(model.n_bonds, np.nan)
    # compute bond/local reports -dE/dr: negative when the bond pulls, so tension = -force
    force[order[where[found]]] = -fr.column("force")[found]
    return force


def write_trajectory(path: Path, model: BeadModel, frames, *, velocities: bool = False,
                     bond_data: bool = False, paraview_dir: Path | None = None) -> dict:
    """Write ``frames`` into an H5MD file (and a ParaView series if ``paraview_dir``).

    Returns a dict of what was written: frames, sizes in bytes, seconds spent.
    """
    import time as _time

    from .paraview import ParaViewSeries

    t0 = _time.perf_counter()
    pv = ParaViewSeries(paraview_dir, model) if paraview_dir is not None else None
    with TrajectoryWriter(path, model, velocities=velocities, bond_data=bond_data) as w:
        for fr in frames:
            w.append(fr.step, fr.time, fr.box_lo, fr.box_hi, fr.positions, fr.velocities,
                     fr.bond_force, fr.tilt)
            if pv is not None:
                pv.append(fr)
        n_frames = w.n_frames
    report = {"frames": n_frames, "trajectory_bytes": Path(path).stat().st_size}
    if pv is not None:
        report["paraview_bytes"] = pv.close()
        report["paraview"] = str(pv.pvd)
    report["convert_s"] = _time.perf_counter() - t0
    return report


def finalise(run_dir: Path, *, paraview: bool = True, model: BeadModel | None = None
             ) -> Path | None:
    """Turn a finished run's LAMMPS dumps into ``trajectory.h5`` (+ ParaView files).

    Call it on every rank after the run: rank 0 converts, the others wait. A
    run folder without ``trajectory.bin`` (trajectory switched off) is left as
    it is. Writes ``trajectory.json`` (frames, sizes, seconds) beside it.

    Args:
        run_dir: the run folder (holds ``model.data``/``model.json`` and the dumps).
        paraview: also write ``trajectory.pvd`` and ``paraview/frame_*.vtu``.
        model: the bead model run (default: read from the run folder).

    Returns:
        The path of ``trajectory.h5`` on every rank, or None when there is no dump.
    """
    run_dir = Path(run_dir)
    message = ""
    error: Exception | None = None
    if mpi.is_root():
        try:
            message = _finalise_on_root(run_dir, paraview, model)
        except Exception as exc:  # noqa: BLE001 - every rank must hear of it, then re-raised
            error = exc
            message = f"ERR:cannot write the trajectory of {run_dir}: {exc}"
    message = mpi.bcast_text(message)
    if error is not None:
        raise error
    if message.startswith("ERR:"):
        raise InputError(message[4:])
    return Path(message) if message else None


def salvage(run_dir: Path, *, paraview: bool = True, model: BeadModel | None = None
            ) -> Path | None:
    """:func:`finalise` for a run that failed: convert what the dumps hold, never raise.

    Call it on every rank before re-raising the run's error, so the frames up to a
    blow-up can be looked at.
    """
    try:
        return finalise(run_dir, paraview=paraview, model=model)
    except Exception:  # noqa: BLE001 - best effort; the caller re-raises the run's error
        return None


def _finalise_on_root(run_dir: Path, paraview: bool, model: BeadModel | None) -> str:
    dump = run_dir / DUMP_FILE
    if not dump.exists():
        return ""
    if model is None:
        model = BeadModel.load(run_dir / "model.data", run_dir / "model.json")
    bond_dump = run_dir / BOND_DUMP_FILE
    bond_dump = bond_dump if bond_dump.exists() and model.n_bonds else None
    velocities = _has_velocities(dump)
    report = write_trajectory(run_dir / TRAJECTORY_FILE, model,
                              frames_from_dumps(model, dump, bond_dump), velocities=velocities,
                              bond_data=bond_dump is not None,
                              paraview_dir=run_dir if paraview else None)
    report["dump_bytes"] = dump.stat().st_size + (bond_dump.stat().st_size if bond_dump
                                                  else 0)
    report.update(n_beads=model.n_beads, n_bonds=model.n_bonds, format=FORMAT,
                  format_version=format_version(run_dir / TRAJECTORY_FILE))
    (run_dir / "trajectory.json").write_text(json.dumps(report, indent=2) + "\n")
    return str(run_dir / TRAJECTORY_FILE)


def _has_velocities(dump: Path) -> bool:
    from ..engine.lammps_dump import iter_dump

    first = next(iter_dump(dump), None)
    return first is not None and "vx" in first.columns


def write_snapshot(model: BeadModel, path: Path, *, step: int = 0, time_s: float = 0.0,
                   paraview_dir: Path | None = None) -> Path:
    """A one-frame trajectory of a bead model (e.g. a generated fabric before any run)."""
    frame = Frame(step=step, time=time_s, box_lo=model.box_lo, box_hi=model.box_hi,
                  positions=model.unwrapped_positions)
    write_trajectory(Path(path), model, [frame], paraview_dir=paraview_dir)
    return Path(path)


def file_author() -> tuple[str, str]:
    """(name, email) of the person writing: ``$FABMD_AUTHOR`` / ``$FABMD_AUTHOR_EMAIL``,
    else the login name (H5MD asks for the author, not the program)."""
    import getpass

    name = os.environ.get("FABMD_AUTHOR", "").strip()
    if not name:
        try:
            name = getpass.getuser()
        except Exception:  # noqa: BLE001 - no login name (some containers): say so
            name = "unknown"
    return name, os.environ.get("FABMD_AUTHOR_EMAIL", "").strip()
