"""VTU files of fibre and yarn polylines that ParaView opens (via meshio).

* ``fibres.vtu`` — every bond as a line cell between bead points; cell data
  ``yarn_id``, ``fibre_id``, ``family`` (integer code = atom type), ``bond_type``;
  point data ``diameter_m`` (use it to scale a sphere glyph), ``family``,
  ``yarn_id``.
* ``yarns.vtu`` — yarn centrelines (mean of the yarn's beads in slices along its
  axis) as line cells; cell data ``yarn_id`` and ``family``.

The family legend is stored as field data ``family_<name>`` = code (e.g.
``family_warp = 1``). Periodic models are written unwrapped (continuous across
the box face); the bond that closes a periodic fibre across the box is left out.
Only rank 0 writes.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from ..engine import mpi
from ..model.bead_model import BeadModel


def _legend(model: BeadModel) -> dict[str, np.ndarray]:
    return {f"family_{name}": np.array([k], dtype=np.int32)
            for k, name in enumerate(model.family_names, start=1)}


def _write(path: Path, mesh, field_data: dict[str, np.ndarray]) -> None:
    """meshio's VTU writer, plus the dataset's FieldData (meshio 5.3 leaves it out)."""
    import meshio

    path = Path(path)
    tmp = path.with_name(path.name + ".part")
    meshio.write(tmp, mesh, file_format="vtu", binary=True)
    arrays = "".join(
        f'<DataArray type="Int32" Name="{name}" NumberOfTuples="{len(v)}" format="ascii">'
        f'{" ".join(str(int(x)) for x in v)}</DataArray>\n' for name, v in field_data.items())
    block = f"<FieldData>\n{arrays}</FieldData>\n"
    with open(tmp, "rb") as src, open(path, "wb") as dst:
        for line in src:
            dst.write(line)
            if line.strip() == b"<UnstructuredGrid>":
                dst.write(block.encode("ascii"))
                break
        shutil.copyfileobj(src, dst)
    tmp.unlink()


def _open_bonds(model: BeadModel) -> np.ndarray:
    """Fibre bonds whose unwrapped length is that of a bond (not closing across the box);
    cohesion links are not drawn."""
    pos = model.unwrapped_positions
    if not model.n_bonds:
        return np.zeros(0, bool)
    d = np.linalg.norm(pos[model.bonds[:, 1]] - pos[model.bonds[:, 0]], axis=1)
    longest = max(bt.rest_length_m for bt in model.fibre_bond_types())
    return (d < 3.0 * max(longest, float(model.diameters.max()))) & model.fibre_bond_mask()


def write_fibres_vtu(model: BeadModel, path: Path) -> Path | None:
    """Write the bead chains of ``model`` as line cells (see module docstring)."""
    if not mpi.is_root():
        return None
    import meshio

    keep = _open_bonds(model)
    bonds = model.bonds[keep]
    yarn = model.yarn_ids
    mesh = meshio.Mesh(
        points=model.unwrapped_positions,
        cells=[("line", bonds.astype(np.int64))],
        point_data={"diameter_m": model.diameters, "family": model.atom_types.astype(np.int32),
                    "yarn_id": yarn.astype(np.int32)},
        cell_data={"yarn_id": [yarn[bonds[:, 0]].astype(np.int32)],
                   "fibre_id": [model.fibre_ids[bonds[:, 0]].astype(np.int32)],
                   "family": [model.atom_types[bonds[:, 0]].astype(np.int32)],
                   "bond_type": [model.bond_types[keep].astype(np.int32)]},
    )
    _write(path, mesh, _legend(model))
    return Path(path)


def yarn_centrelines(model: BeadModel, axis_of: dict[str, int] | None = None
                     ) -> list[np.ndarray]:
    """Centreline of every yarn [m]: mean bead position in slices along the yarn's axis.

    Args:
        axis_of: family → axis the yarns run along (0 = x, 1 = y); default from
            ``model.info["yarn_axis"]``, else warp/binder along x and weft along y.
    """
    axis_of = axis_of or model.info.get("yarn_axis") or {"warp": 0, "binder": 0, "weft": 1}
    pos = model.unwrapped_positions
    yid = model.yarn_ids
    order = np.argsort(yid, kind="stable")
    bounds = np.searchsorted(yid[order], np.arange(1, len(model.yarns) + 2))
    out = []
    for k, y in enumerate(model.yarns):
        idx = order[bounds[k]:bounds[k + 1]]
        p = pos[idx]
        ax = int(axis_of.get(y.family, 0))
        step = 2.0 * float(model.diameters[idx].max())
        u = p[:, ax]
        b = np.floor((u - u.min()) / step).astype(np.int64)
        nb = int(b.max()) + 1
        cnt = np.bincount(b, minlength=nb)
        ok = cnt > 0
        line = np.column_stack([np.bincount(b, weights=p[:, j], minlength=nb)[ok] / cnt[ok]
                                for j in range(3)])
        out.append(line)
    return out


def write_yarns_vtu(model: BeadModel, path: Path) -> Path | None:
    """Write yarn centrelines as line cells (see module docstring)."""
    if not mpi.is_root():
        return None
    import meshio

    lines = yarn_centrelines(model)
    points = np.vstack(lines)
    start = np.concatenate([[0], np.cumsum([len(x) for x in lines])[:-1]])
    cells, yarn_id, family = [], [], []
    codes = {n: k for k, n in enumerate(model.family_names, start=1)}
    for k, (line, s) in enumerate(zip(lines, start, strict=True)):
        m = len(line) - 1
        if m < 1:
            continue
        cells.append(np.column_stack([np.arange(s, s + m), np.arange(s + 1, s + m + 1)]))
        yarn_id.append(np.full(m, k + 1, np.int32))
        family.append(np.full(m, codes[model.yarns[k].family], np.int32))
    mesh = meshio.Mesh(points=points, cells=[("line", np.vstack(cells))],
                       cell_data={"yarn_id": [np.concatenate(yarn_id)],
                                  "family": [np.concatenate(family)]})
    _write(path, mesh, _legend(model))
    return Path(path)
