"""Yarn centrelines, their curvature, and crimp (SI).

* centreline of a yarn: the mean of its fibres at the same station, a station
  being a fraction of each fibre's arc length (0 = first bead, 1 = last);
* curvature κ = |r′ × r″| / |r′|³ along a path [1/m];
* crimp of a path: its length over the length of its end-to-end vector
  projected on the fabric plane, minus 1 (0 for a straight in-plane yarn).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from .frame import FabricFrame

#: normal of the fabric plane (crimp is measured against the in-plane projection)
FABRIC_NORMAL = (0.0, 0.0, 1.0)


def _path(path) -> np.ndarray:
    path = np.asarray(path, float)
    if path.ndim != 2 or path.shape[1] != 3 or len(path) < 2:
        raise InputError(f"a path must be an (n >= 2, 3) array of points, got shape "
                         f"{path.shape}")
    return path


def arc_length(path) -> np.ndarray:
    """Cumulative arc length at every point of a polyline [m] (starts at 0)."""
    path = _path(path)
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])


def path_length(path) -> float:
    """Length of a polyline [m]."""
    return float(arc_length(path)[-1])


def resample(path, stations: int | np.ndarray) -> np.ndarray:
    """Points at fractions of the arc length (``stations`` evenly spaced ones, or given)."""
    path = _path(path)
    u = np.linspace(0.0, 1.0, int(stations)) if np.isscalar(stations) else \
        np.asarray(stations, float)
    s = arc_length(path)
    if s[-1] <= 0:
        raise InputError("a path of zero length cannot be resampled")
    s = s / s[-1]
    return np.column_stack([np.interp(u, s, path[:, k]) for k in range(3)])


def centreline(paths: list[np.ndarray], stations: int = 100) -> np.ndarray:
    """Mean of several fibre paths at ``stations`` equal arc-length fractions.

    Paths that run the other way than the first are reversed first.
    """
    if not paths:
        raise InputError("centreline needs at least one fibre path")
    first = _path(paths[0])
    axis = first[-1] - first[0]
    total = np.zeros((int(stations), 3))
    for p in paths:
        p = _path(p)
        if np.dot(p[-1] - p[0], axis) < 0:
            p = p[::-1]
        total += resample(p, stations)
    return total / len(paths)


def curvature(path) -> np.ndarray:
    """Curvature κ at every point of a path [1/m] (second-order differences in arc length).

    The path should be sampled finely compared with its radius of curvature;
    the two end values are one-sided.
    """
    path = _path(path)
    if len(path) < 3:
        raise InputError("curvature needs at least 3 points")
    s = arc_length(path)
    d1 = np.gradient(path, s, axis=0)
    d2 = np.gradient(d1, s, axis=0)
    speed = np.linalg.norm(d1, axis=1)
    return np.linalg.norm(np.cross(d1, d2), axis=1) / speed**3


def crimp(path, normal=FABRIC_NORMAL) -> float:
    """Path length over the in-plane projected end-to-end length, minus 1."""
    path = _path(path)
    normal = np.asarray(normal, float)
    normal = normal / np.linalg.norm(normal)
    chord = path[-1] - path[0]
    chord = chord - np.dot(chord, normal) * normal
    projected = float(np.linalg.norm(chord))
    if projected <= 0:
        raise InputError("crimp: the path's ends coincide in the fabric plane")
    return path_length(path) / projected - 1.0


def yarn_centreline(frame: FabricFrame, yarn: str | int, stations: int | None = None
                    ) -> np.ndarray:
    """Centreline of one yarn (a closed, periodic yarn spans exactly one period).

    ``stations`` defaults to the bead count of the yarn's longest fibre.
    """
    paths = frame.yarn_paths(yarn)
    if stations is None:
        stations = max(len(p) for p in paths)
    return centreline(paths, max(3, int(stations)))


def yarn_centrelines(frame: FabricFrame, family: str | None = None,
                     stations: int | None = None) -> dict[str, np.ndarray]:
    """Centrelines of all yarns (of one family), by yarn name."""
    return {name: yarn_centreline(frame, name, stations) for name in frame.yarns(family)}


def crimp_by_yarn(frame: FabricFrame, family: str | None = None,
                  normal=FABRIC_NORMAL) -> dict[str, float]:
    """Crimp of every yarn's centreline (of one family), by yarn name."""
    return {name: crimp(line, normal)
            for name, line in yarn_centrelines(frame, family).items()}


def crimp_by_family(frame: FabricFrame, normal=FABRIC_NORMAL) -> dict[str, float]:
    """Mean yarn crimp of every family."""
    return {fam: float(np.mean(list(crimp_by_yarn(frame, fam, normal).values())))
            for fam in frame.families}
