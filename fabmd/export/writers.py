"""Write voxel meshes: VTU (meshio, for ParaView) and Abaqus ``.inp`` (with element sets
per yarn and matrix, fibre orientations as a ``*Distribution`` and periodic node sets).

Node and element numbering (both files): nodes of the (nx+1)·(ny+1)·(nz+1) grid with x
fastest, then y, then z; element e (1-based in Abaqus) is voxel e − 1 of
:meth:`VoxelGrid.centres`, node order as VTK_HEXAHEDRON / C3D8 (bottom face
counter-clockwise seen from +z, then the top face).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from .voxel import VoxelGrid, VoxelMesh

#: element sets and node sets are written this many labels a line (Abaqus allows 16)
_PER_LINE = 16


def grid_nodes(grid: VoxelGrid) -> np.ndarray:
    """(n_nodes, 3) node coordinates, x fastest [m]."""
    axes = [np.linspace(grid.lo_m[k], grid.hi_m[k], grid.counts[k] + 1) for k in range(3)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.column_stack([x.ravel(), y.ravel(), z.ravel()])


def grid_hexahedra(grid: VoxelGrid) -> np.ndarray:
    """(n_voxels, 8) 0-based node indices of every voxel (VTK / Abaqus C3D8 order)."""
    nx, ny, nz = grid.counts
    k, j, i = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()

    def node(a, b, c):
        return (c * (ny + 1) + b) * (nx + 1) + a

    return np.column_stack([node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k),
                            node(i, j + 1, k), node(i, j, k + 1), node(i + 1, j, k + 1),
                            node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)])


def write_vtu(mesh: VoxelMesh, path: Path) -> Path:
    """Voxel mesh as VTU: cell data ``yarn_id`` (0 = matrix), ``fibre_direction``
    (unit vector, 0 in the matrix), ``fibre_volume_fraction``."""
    import meshio

    cells = [("hexahedron", grid_hexahedra(mesh.grid))]
    data = {"yarn_id": [mesh.yarn_id.astype(np.int32)],
            "fibre_direction": [mesh.direction],
            "fibre_volume_fraction": [mesh.fibre_volume_fraction]}
    meshio.write(path, meshio.Mesh(grid_nodes(mesh.grid), cells, cell_data=data))
    return Path(path)


def abaqus_name(name: str) -> str:
    """An Abaqus label for a yarn name: upper case, letters, digits and underscores."""
    label = re.sub(r"[^A-Za-z0-9_]", "_", name).upper()
    return label if label[:1].isalpha() else f"Y_{label}"


def _labels(values: np.ndarray) -> list[str]:
    """Labels written ``_PER_LINE`` a line, comma separated."""
    v = np.asarray(values, np.int64)
    return [", ".join(str(x) for x in v[i:i + _PER_LINE]) for i in range(0, len(v), _PER_LINE)]


def periodic_node_sets(grid: VoxelGrid) -> dict[str, np.ndarray]:
    """1-based node labels of the faces (without their edges), edges (without their
    corners) and corners of the grid's box.

    Names: faces ``XMIN`` … ``ZMAX``; edges ``EDGE_<a>_<b>`` by the two faces they join
    (e.g. ``EDGE_YMIN_ZMIN`` runs along x); corners ``CORNER_<x><y><z>`` with each letter
    ``0`` (min) or ``1`` (max). Labels ascend, and because nodes are numbered x fastest
    the n-th label of a set and of its opposite set are the same point shifted by one
    period: the pairs for periodic boundary equations.
    """
    nx, ny, nz = grid.counts
    k, j, i = np.meshgrid(np.arange(nz + 1), np.arange(ny + 1), np.arange(nx + 1),
                          indexing="ij")
    ijk = [i.ravel(), j.ravel(), k.ravel()]
    label = np.arange(len(ijk[0])) + 1
    top = (nx, ny, nz)
    side = []  # per axis: -1 at min, +1 at max, 0 inside
    for a in range(3):
        s = np.zeros(len(label), np.int64)
        s[ijk[a] == 0] = -1
        s[ijk[a] == top[a]] = 1
        side.append(s)
    on = np.column_stack([s != 0 for s in side]).sum(axis=1)
    letters = "XYZ"
    sets: dict[str, np.ndarray] = {}
    for a in range(3):
        for sign, word in ((-1, "MIN"), (1, "MAX")):
            sets[f"{letters[a]}{word}"] = label[(side[a] == sign) & (on == 1)]
    for a in range(3):
        for b in range(a + 1, 3):
            for sa, wa in ((-1, "MIN"), (1, "MAX")):
                for sb, wb in ((-1, "MIN"), (1, "MAX")):
                    sel = (side[a] == sa) & (side[b] == sb) & (on == 2)
                    sets[f"EDGE_{letters[a]}{wa}_{letters[b]}{wb}"] = label[sel]
    for cx in (-1, 1):
        for cy in (-1, 1):
            for cz in (-1, 1):
                sel = (side[0] == cx) & (side[1] == cy) & (side[2] == cz)
                name = "CORNER_" + "".join("0" if c < 0 else "1" for c in (cx, cy, cz))
                sets[name] = label[sel]
    return sets


def transverse_axis(directions: np.ndarray) -> np.ndarray:
    """A unit vector normal to each direction (the local 2-axis): z × a, or y × a for a
    direction within 18° of z."""
    a = np.asarray(directions, float)
    ref = np.tile([0.0, 0.0, 1.0], (len(a), 1))
    ref[np.abs(a[:, 2]) > 0.95] = [0.0, 1.0, 0.0]
    b = np.cross(ref, a)
    return b / np.linalg.norm(b, axis=1, keepdims=True)


def write_abaqus(mesh: VoxelMesh, path: Path, element_type: str = "C3D8R") -> Path:
    """Voxel mesh as an Abaqus input file.

    Contents: ``*Node`` (m), ``*Element``; ``*Elset`` per yarn (its name via
    :func:`abaqus_name`), ``YARNS`` (all yarn voxels) and ``MATRIX``; ``*Nset`` for the
    periodic faces, edges and corners (:func:`periodic_node_sets`); the fibre direction
    of every yarn element as ``*Distribution`` ``FIBRE_DIRECTIONS`` (local 1-axis = fibre
    direction, the point giving the 1-2 plane from :func:`transverse_axis`), used by
    ``*Orientation`` ``FIBRE_ORIENTATION``; ``*Solid Section`` for ``YARNS`` (with the
    orientation) and ``MATRIX`` referring to materials ``YARN`` and ``MATRIX``, which the
    user defines (no properties are written: fabmd does not know the resin). The fibre
    volume fraction per element goes to ``<stem>_elements.csv`` beside the file.
    """
    path = Path(path)
    nodes = grid_nodes(mesh.grid)
    hexes = grid_hexahedra(mesh.grid) + 1
    elements = np.arange(1, len(hexes) + 1)
    yarn_el = elements[mesh.yarn_id > 0]
    lines = ["*Heading", f"** fabmd voxel mesh {mesh.grid.counts} voxels, SI units (m)",
             "** element sets per yarn, YARNS, MATRIX; periodic node sets; fibre orientation",
             "*Node"]
    lines += [f"{n}, {x:.9e}, {y:.9e}, {z:.9e}"
              for n, (x, y, z) in zip(range(1, len(nodes) + 1), nodes, strict=True)]
    lines.append(f"*Element, type={element_type}")
    lines += [f"{e}, " + ", ".join(str(v) for v in h)
              for e, h in zip(elements, hexes, strict=True)]
    for k, name in enumerate(mesh.yarn_names, start=1):
        sel = elements[mesh.yarn_id == k]
        if len(sel):
            lines.append(f"*Elset, elset={abaqus_name(name)}")
            lines += _labels(sel)
    for set_name, sel in (("YARNS", yarn_el), ("MATRIX", elements[mesh.yarn_id == 0])):
        if len(sel):
            lines.append(f"*Elset, elset={set_name}")
            lines += _labels(sel)
    for set_name, sel in periodic_node_sets(mesh.grid).items():
        if len(sel):
            lines.append(f"*Nset, nset={set_name}")
            lines += _labels(sel)
    if len(yarn_el):
        a = mesh.direction[mesh.yarn_id > 0]
        b = transverse_axis(a)
        lines += ["*Distribution Table, name=FIBRE_DIRECTIONS_TABLE", "COORD3D, COORD3D",
                  "*Distribution, name=FIBRE_DIRECTIONS, location=ELEMENT, "
                  "table=FIBRE_DIRECTIONS_TABLE",
                  ", 1., 0., 0., 0., 1., 0."]
        lines += [f"{e}, " + ", ".join(f"{v:.6f}" for v in (*ai, *bi))
                  for e, ai, bi in zip(yarn_el, a, b, strict=True)]
        # data lines: the distribution, then no additional rotation (about local 1, 0 deg)
        lines += ["*Orientation, name=FIBRE_ORIENTATION, system=RECTANGULAR, "
                  "definition=COORDINATES",
                  "FIBRE_DIRECTIONS", "1, 0.",
                  "*Solid Section, elset=YARNS, material=YARN, orientation=FIBRE_ORIENTATION",
                  ","]
    if (mesh.yarn_id == 0).any():
        lines += ["*Solid Section, elset=MATRIX, material=MATRIX", ","]
    lines += ["** define *Material, name=YARN (1 = fibre direction) and name=MATRIX here"]
    path.write_text("\n".join(lines) + "\n")
    write_element_table(mesh, path.with_name(f"{path.stem}_elements.csv"))
    return path


def write_element_table(mesh: VoxelMesh, path: Path) -> Path:
    """CSV, one row per element: element, yarn_id, yarn, direction x/y/z,
    fibre_volume_fraction."""
    names = ["matrix", *mesh.yarn_names]
    rows = ["element,yarn_id,yarn,direction_x,direction_y,direction_z,fibre_volume_fraction"]
    rows += [f"{e},{y},{names[y]},{d[0]:.6f},{d[1]:.6f},{d[2]:.6f},{f:.6f}"
             for e, y, d, f in zip(range(1, len(mesh.yarn_id) + 1), mesh.yarn_id,
                                   mesh.direction, mesh.fibre_volume_fraction, strict=True)]
    Path(path).write_text("\n".join(rows) + "\n")
    return Path(path)


def read_distribution(path: Path) -> dict[int, np.ndarray]:
    """The ``FIBRE_DIRECTIONS`` distribution of an ``.inp`` written here: element → (6,)
    (fibre direction, transverse point); for checks and tests."""
    out: dict[int, np.ndarray] = {}
    reading = False
    for line in Path(path).read_text().splitlines():
        if line.startswith("*"):
            reading = line.lower().startswith("*distribution,")
            continue
        if reading and not line.startswith(","):
            parts = line.split(",")
            out[int(parts[0])] = np.array([float(v) for v in parts[1:7]])
    return out
