"""ParaView files of a trajectory: one VTU per frame (meshio) and a ``.pvd`` series.

Every bond is a line cell between two bead points, so a fibre is drawn as a
polyline; positions are unwrapped (a periodic fibre is not torn at the box
face; the one bond that closes it across the box is left out of the drawing).

Point data: ``yarn_id``, ``fibre_id``, ``family`` (code = LAMMPS atom type, see
the comment in the ``.pvd`` for names), ``diameter_m`` and, when stored,
``velocity_m_s``. Cell (bond) data, when stored: ``bond_force_n`` (> 0 in
tension). Open ``trajectory.pvd`` in ParaView (File → Open) and press Play;
colour by ``bond_force_n`` or ``yarn_id``; a Point Gaussian representation
scaled by ``diameter_m`` shows the beads. Files are written for viewing:
coordinates and values in single precision (``trajectory.h5`` keeps double).
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

import numpy as np

from ..model.bead_model import BeadModel

PVD_FILE = "trajectory.pvd"
PARAVIEW_DIR = "paraview"


def drawn_bonds(model: BeadModel, positions: np.ndarray, box_lo, box_hi) -> np.ndarray:
    """Indices of the bonds to draw: the fibre bonds (not cohesion links) but those spanning
    half a periodic box or more."""
    bonds = model.bonds
    keep = model.fibre_bond_mask()
    if not len(bonds) or not any(model.periodic):
        return np.flatnonzero(keep)
    d = np.abs(positions[bonds[:, 1]] - positions[bonds[:, 0]])
    lengths = np.asarray(box_hi, float) - np.asarray(box_lo, float)
    for k in range(3):
        if model.periodic[k]:
            keep &= d[:, k] < 0.5 * lengths[k]
    return np.flatnonzero(keep)


class ParaViewSeries:
    """Write frames as ``<folder>/paraview/frame_NNNNN.vtu`` and ``<folder>/trajectory.pvd``."""

    def __init__(self, folder: Path, model: BeadModel, pvd_name: str = PVD_FILE,
                 subfolder: str = PARAVIEW_DIR):
        self.folder = Path(folder)
        self.pvd = self.folder / pvd_name
        self.subfolder = subfolder
        (self.folder / subfolder).mkdir(parents=True, exist_ok=True)
        for old in (self.folder / subfolder).glob("frame_*.vtu"):  # of an earlier conversion
            old.unlink()
        self.model = model
        self.entries: list[tuple[float, str]] = []
        self.bytes = 0
        self._point_static = {
            "yarn_id": model.yarn_ids.astype(np.int32),
            "fibre_id": model.fibre_ids.astype(np.int32),
            "family": model.atom_types.astype(np.int8),
            "diameter_m": model.diameters.astype(np.float32),
        }

    def append(self, frame) -> Path:
        """Write one frame (an object with ``positions``, ``time``, box and optional extras)."""
        import meshio

        keep = drawn_bonds(self.model, frame.positions, frame.box_lo, frame.box_hi)
        cell_data = {}
        if frame.bond_force is not None:
            cell_data["bond_force_n"] = [np.asarray(frame.bond_force, np.float32)[keep]]
        point_data = dict(self._point_static)
        if frame.velocities is not None:
            point_data["velocity_m_s"] = np.asarray(frame.velocities, np.float32)
        mesh = meshio.Mesh(np.asarray(frame.positions, np.float32),
                           [("line", self.model.bonds[keep].astype(np.int32))],
                           point_data=point_data, cell_data=cell_data)
        name = f"{self.subfolder}/frame_{len(self.entries):05d}.vtu"
        path = self.folder / name
        meshio.write(path, mesh, file_format="vtu", binary=True, compression="zlib")
        self.bytes += path.stat().st_size
        time = float(frame.time) if np.isfinite(frame.time) else float(len(self.entries))
        self.entries.append((time, name))
        return path

    def close(self) -> int:
        """Write the ``.pvd`` collection; returns the bytes written (VTU files + pvd)."""
        families = ", ".join(f"{i} = {name}" for i, name in
                             enumerate(self.model.family_names, start=1))
        lines = ['<?xml version="1.0"?>',
                 f"<!-- fabmd trajectory: time in s, lengths in m, forces in N; "
                 f"family codes: {escape(families)} -->",
                 '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
                 "  <Collection>"]
        lines += [f'    <DataSet timestep="{t:.10g}" group="" part="0" file={quoteattr(n)}/>'
                  for t, n in self.entries]
        lines += ["  </Collection>", "</VTKFile>", ""]
        self.pvd.write_text("\n".join(lines))
        return self.bytes + self.pvd.stat().st_size


def export_paraview(trajectory: Path, folder: Path | None = None) -> Path:
    """ParaView series of an existing ``trajectory.h5`` (into its folder by default)."""
    from ..analysis.trajectory_file import Frame, open_trajectory, read_lengths, read_model

    trajectory = Path(trajectory)
    folder = Path(folder) if folder is not None else trajectory.parent
    model = read_model(trajectory, 0)
    series = ParaViewSeries(folder, model)
    with open_trajectory(trajectory) as f:
        part = f["particles/all"]
        obs = f["observables"]
        for i in range(part["position/value"].shape[0]):
            lo = read_lengths(obs["box_offset/value"], i)
            series.append(Frame(
                step=int(part["position/step"][i]), time=float(part["position/time"][i]),
                box_lo=lo, box_hi=lo + read_lengths(part["box/edges/value"], i),
                positions=read_lengths(part["position/value"], i),
                velocities=part["velocity/value"][i] if "velocity" in part else None,
                bond_force=obs["bond_force/value"][i] if "bond_force" in obs else None))
    series.close()
    return series.pvd
