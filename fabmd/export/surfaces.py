"""Yarn surface meshes (closed triangle meshes of the reconstructed envelopes), their
watertightness check, and the interpenetration report between yarns (SI).

A yarn's surface is its envelope rings joined station to station, with a flat cap (a fan
about the ring's centre) at each end; a periodic yarn runs over exactly one period (its
last ring is the first shifted by the period) and is capped there too, so every yarn is
one closed, outward-oriented surface.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .voxel import VoxelMesh
from .yarns import YarnGeometry


def yarn_surface(yarn: YarnGeometry) -> tuple[np.ndarray, np.ndarray]:
    """Closed triangle mesh of a yarn: (points (p, 3) [m], triangles (t, 3) 0-based),
    outward normals (counter-clockwise seen from outside)."""
    rings = yarn.ring_points()
    centres = yarn.centres_m
    if yarn.closed:
        rings = np.concatenate([rings, rings[:1] + yarn.period_m])
        centres = np.vstack([centres, centres[:1] + yarn.period_m])
    n, m = rings.shape[:2]
    points = np.vstack([rings.reshape(-1, 3), centres[0], centres[-1]])
    start_cap, end_cap = n * m, n * m + 1
    s, k = np.meshgrid(np.arange(n - 1), np.arange(m), indexing="ij")
    s, k = s.ravel(), k.ravel()
    a, b = s * m + k, s * m + (k + 1) % m
    c, d = a + m, b + m
    tris = [np.column_stack([a, b, d]), np.column_stack([a, d, c])]
    k = np.arange(m)
    tris.append(np.column_stack([np.full(m, start_cap), (k + 1) % m, k]))
    last = (n - 1) * m
    tris.append(np.column_stack([np.full(m, end_cap), last + k, last + (k + 1) % m]))
    triangles = np.vstack(tris)
    if enclosed_volume(points, triangles) < 0:
        triangles = triangles[:, ::-1]
    return points, triangles


def enclosed_volume(points: np.ndarray, triangles: np.ndarray) -> float:
    """Signed volume enclosed by a closed triangle mesh (divergence theorem) [m³];
    positive when the triangles are oriented outward."""
    p = np.asarray(points, float)
    t = np.asarray(triangles, np.int64)
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def watertight(triangles: np.ndarray) -> dict:
    """Edge check of a triangle mesh: every undirected edge must belong to exactly two
    triangles, which run along it in opposite directions (consistent orientation).

    Returns ``{"edges", "boundary_or_nonmanifold_edges", "inconsistent_edges",
    "watertight"}``.
    """
    t = np.asarray(triangles, np.int64)
    directed = np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    lo, hi = directed.min(axis=1), directed.max(axis=1)
    forward = directed[:, 0] < directed[:, 1]
    key = lo * (int(t.max()) + 1) + hi
    uniq, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    n_forward = np.bincount(inverse, weights=forward, minlength=len(uniq))
    bad_count = int((counts != 2).sum())
    inconsistent = int(((counts == 2) & (n_forward != 1)).sum())
    return {"edges": int(len(uniq)), "boundary_or_nonmanifold_edges": bad_count,
            "inconsistent_edges": inconsistent,
            "watertight": bad_count == 0 and inconsistent == 0}


def write_surfaces(yarns: list[YarnGeometry], folder: Path) -> dict:
    """One STL per yarn (``<name>.stl``) and all yarns in ``yarn_surfaces.vtu`` (cell data
    ``yarn_id``); returns each yarn's enclosed volume [m³] and watertightness."""
    import meshio

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    all_points, all_tris, ids, report = [], [], [], {}
    offset = 0
    for y in yarns:
        pts, tris = yarn_surface(y)
        meshio.write(folder / f"{y.name}.stl", meshio.Mesh(pts, [("triangle", tris)]),
                     binary=True)
        check = watertight(tris)
        report[y.name] = {"volume_m3": enclosed_volume(pts, tris),
                          "triangles": int(len(tris)), "watertight": check["watertight"]}
        all_points.append(pts)
        all_tris.append(tris + offset)
        ids.append(np.full(len(tris), y.yarn_id, np.int32))
        offset += len(pts)
    if yarns:
        meshio.write(folder / "yarn_surfaces.vtu",
                     meshio.Mesh(np.vstack(all_points), [("triangle", np.vstack(all_tris))],
                                 cell_data={"yarn_id": [np.concatenate(ids)]}))
    return report


def interpenetration_report(mesh: VoxelMesh, yarns: list[YarnGeometry]) -> dict:
    """Volume shared by pairs of yarn envelopes, from the voxel centres inside both.

    Returns ``{"pairs": [{"yarns", "volume_m3", "fraction_of_smaller"}...] (largest
    first), "total_volume_m3", "fraction_of_yarn_volume"}``; the resolution is one voxel
    (``mesh.grid.voxel_volume_m3``).
    """
    volume = {y.yarn_id: y.volume_m3() for y in yarns}
    names = {y.yarn_id: y.name for y in yarns}
    dv = mesh.grid.voxel_volume_m3
    pairs = []
    for (a, b), count in sorted(mesh.overlap_voxels.items(), key=lambda kv: -kv[1]):
        v = count * dv
        pairs.append({"yarns": [names[a], names[b]], "volume_m3": v,
                      "fraction_of_smaller": v / min(volume[a], volume[b])})
    total = float(sum(p["volume_m3"] for p in pairs))
    yarn_total = float(sum(volume.values()))
    return {"pairs": pairs, "total_volume_m3": total,
            "fraction_of_yarn_volume": total / yarn_total if yarn_total else 0.0,
            "voxel_volume_m3": dv}
