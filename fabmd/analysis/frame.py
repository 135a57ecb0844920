"""One state of a fabric: unwrapped bead positions with fibre and yarn identity."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError


@dataclass
class FabricFrame:
    """Bead positions of one frame and who they belong to (SI).

    Beads of a fibre are contiguous and ordered along it (the bead-model
    invariant); ``fibre_ids`` are 1-based, ``fibre_yarn[f - 1]`` is the 1-based
    yarn of fibre ``f``. Positions are unwrapped: a periodic fibre runs from its
    first to its last bead without a jump; ``closed`` marks fibres whose last
    bead is bonded back to the first across the box (one full period).

    Args:
        positions: (N, 3) bead positions [m].
        fibre_ids: (N,) fibre id of every bead.
        fibre_yarn: (n_fibres,) yarn id of every fibre.
        yarn_names: name of every yarn (e.g. ``"warp-3"``).
        yarn_families: family of every yarn (e.g. ``"warp"``).
        box_lo, box_hi: box corners [m].
        periodic: periodicity of x, y, z.
        diameters: (N,) bead diameters [m] (optional).
        closed: (n_fibres,) bool, fibre closes across the box (default: none).
        time_s: time of the frame [s].
        step: time step of the frame (None when unknown).
        tilt: (xy, xz, yz) tilt factors of a triclinic box (a sheared periodic cell) [m];
            the box vectors are then (lx, 0, 0), (xy, ly, 0), (xz, yz, lz) with
            (lx, ly, lz) = box_hi − box_lo. None: an orthogonal box.
    """

    positions: np.ndarray
    fibre_ids: np.ndarray
    fibre_yarn: np.ndarray
    yarn_names: list[str]
    yarn_families: list[str]
    box_lo: np.ndarray
    box_hi: np.ndarray
    periodic: tuple[bool, bool, bool] = (False, False, False)
    diameters: np.ndarray | None = None
    closed: np.ndarray | None = None
    time_s: float = 0.0
    step: int | None = None
    tilt: np.ndarray | None = None
    _starts: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        self.positions = np.asarray(self.positions, float).reshape(-1, 3)
        self.fibre_ids = np.asarray(self.fibre_ids, np.int64).reshape(-1)
        self.fibre_yarn = np.asarray(self.fibre_yarn, np.int64).reshape(-1)
        self.box_lo = np.asarray(self.box_lo, float).reshape(3)
        self.box_hi = np.asarray(self.box_hi, float).reshape(3)
        self.periodic = tuple(bool(p) for p in self.periodic)
        self.yarn_names = [str(n) for n in self.yarn_names]
        self.yarn_families = [str(f) for f in self.yarn_families]
        if len(self.fibre_ids) != len(self.positions):
            raise InputError("fabric frame: one fibre id per bead needed")
        if len(self.yarn_names) != len(self.yarn_families):
            raise InputError("fabric frame: one family per yarn needed")
        if np.any(np.diff(self.fibre_ids) < 0):
            raise InputError("fabric frame: beads must be ordered by fibre id")
        n = len(self.fibre_yarn)
        self._starts = np.searchsorted(self.fibre_ids, np.arange(1, n + 2))
        self.closed = (np.zeros(n, bool) if self.closed is None
                       else np.asarray(self.closed, bool).reshape(n))
        if self.tilt is not None:
            self.tilt = np.asarray(self.tilt, float).reshape(3)
        if self.diameters is not None:
            self.diameters = np.broadcast_to(np.asarray(self.diameters, float),
                                             (len(self.positions),)).copy()

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def from_model(cls, model, time_s: float = 0.0) -> FabricFrame:
        """A frame of a :class:`~fabmd.model.bead_model.BeadModel` (unwrapped positions)."""
        return cls(positions=model.unwrapped_positions, fibre_ids=model.fibre_ids,
                   fibre_yarn=model.fibre_yarn, yarn_names=[y.name for y in model.yarns],
                   yarn_families=[y.family for y in model.yarns], box_lo=model.box_lo,
                   box_hi=model.box_hi, periodic=model.periodic, diameters=model.diameters,
                   closed=closed_fibres(model.fibre_ids, len(model.fibre_yarn), model.bonds),
                   time_s=time_s)

    @classmethod
    def from_trajectory(cls, path: Path, frame: int = -1) -> FabricFrame:
        """Frame ``frame`` of a ``trajectory.h5`` (or of a run folder's)."""
        from .trajectory_file import open_trajectory, read_model, read_tilt, trajectory_path

        path = trajectory_path(path)
        with open_trajectory(path) as f:
            time_s = float(f["particles/all/position/time"][frame])
            step = int(f["particles/all/position/step"][frame])
        return dataclasses.replace(cls.from_model(read_model(path, frame), time_s=time_s),
                                   step=step, tilt=read_tilt(path, frame))

    @classmethod
    def iter_trajectory(cls, path: Path) -> Iterator[FabricFrame]:
        """Every frame of a ``trajectory.h5`` (or of a run folder's), in order; the
        identity is read once, then one frame's positions and box at a time."""
        from .trajectory_file import open_trajectory, read_lengths, trajectory_path

        path = trajectory_path(path)
        base = cls.from_trajectory(path, 0)
        with open_trajectory(path) as f:
            part = f["particles/all"]
            position = part["position"]
            edges = part["box/edges/value"]
            offset = f["observables/box_offset/value"]
            tilt = f["observables"].get("box_tilt")
            for i in range(position["value"].shape[0]):
                lo = read_lengths(offset, i)
                yield dataclasses.replace(
                    base, positions=read_lengths(position["value"], i), box_lo=lo,
                    box_hi=lo + read_lengths(edges, i),
                    time_s=float(position["time"][i]), step=int(position["step"][i]),
                    tilt=None if tilt is None else read_lengths(tilt["value"], i))

    @classmethod
    def from_universe(cls, u) -> FabricFrame:
        """The current frame of a universe made by :func:`fabmd.load`."""
        info = getattr(u, "fabmd", {})
        segments = u.segments
        families = [str(r.resname) for r in (s.residues[0] for s in segments)]
        ts = u.trajectory.ts
        offset = ts.data.get("box_offset")
        # lx, ly, lz (of the untilted cell, for a sheared one) and the tilt
        box = ts.triclinic_dimensions if ts.dimensions is not None else np.eye(3)
        lengths = np.diag(box)
        tilt = ts.data.get("box_tilt")
        lo = np.zeros(3) if offset is None else np.asarray(offset, float)
        resindex = u.atoms.resindices
        fibre_yarn = u.residues.segindices + 1
        bonds = u.bonds.indices if hasattr(u, "bonds") else np.zeros((0, 2), np.int64)
        frame = cls(positions=u.atoms.positions.astype(float), fibre_ids=resindex + 1,
                    fibre_yarn=fibre_yarn, yarn_names=list(segments.segids),
                    yarn_families=families, box_lo=lo, box_hi=lo + lengths,
                    periodic=tuple(info.get("periodic", (False, False, False))),
                    diameters=2.0 * u.atoms.radii if hasattr(u.atoms, "radii") else None,
                    closed=closed_fibres(resindex + 1, len(fibre_yarn), bonds),
                    time_s=float(ts.time),
                    step=int(ts.data["step"]) if "step" in ts.data else None,
                    tilt=None if tilt is None else np.asarray(tilt, float))
        return frame

    # -- queries --------------------------------------------------------------------------
    @property
    def n_fibres(self) -> int:
        return len(self.fibre_yarn)

    @property
    def families(self) -> list[str]:
        """Yarn families present, in order of first appearance."""
        return list(dict.fromkeys(self.yarn_families))

    @property
    def box_lengths(self) -> np.ndarray:
        return self.box_hi - self.box_lo

    def box_vectors(self) -> np.ndarray:
        """(3, 3) rows: the box's edge vectors a, b, c (tilted for a sheared cell) [m]."""
        lx, ly, lz = self.box_lengths
        xy, xz, yz = self.tilt if self.tilt is not None else (0.0, 0.0, 0.0)
        return np.array([[lx, 0.0, 0.0], [xy, ly, 0.0], [xz, yz, lz]])

    def minimum_image(self, d: np.ndarray) -> np.ndarray:
        """Vectors ``d`` (n, 3) shifted by whole periods to their nearest image [m]."""
        d = np.array(d, float).reshape(-1, 3)
        vectors, lengths = self.box_vectors(), self.box_lengths
        for k in (2, 1, 0):  # z, y, x: each vector of a triclinic box moves only the axes
            if self.periodic[k]:  # at and before its own
                d -= np.round(d[:, k] / lengths[k])[:, None] * vectors[k]
        return d

    def wrap(self, points: np.ndarray) -> np.ndarray:
        """Points (n, 3) shifted by whole periods into the box (the tilted cell) [m]."""
        p = np.array(points, float).reshape(-1, 3)
        vectors, lengths = self.box_vectors(), self.box_lengths
        for k in (2, 1, 0):
            if self.periodic[k]:
                p -= np.floor((p[:, k] - self.box_lo[k]) / lengths[k])[:, None] * vectors[k]
        return p

    def yarn_id(self, yarn: str | int) -> int:
        """1-based id of a yarn given by name or id."""
        if isinstance(yarn, str):
            try:
                return self.yarn_names.index(yarn) + 1
            except ValueError:
                raise InputError(f"no yarn named {yarn!r}") from None
        if not 1 <= int(yarn) <= len(self.yarn_names):
            raise InputError(f"yarn id must be 1..{len(self.yarn_names)}, got {yarn}")
        return int(yarn)

    def yarns(self, family: str | None = None) -> list[str]:
        """Names of the yarns (of one family)."""
        if family is not None and family not in self.yarn_families:
            raise InputError(f"family must be one of {self.families}, got {family!r}")
        return [n for n, f in zip(self.yarn_names, self.yarn_families, strict=True)
                if family is None or f == family]

    def fibre_beads(self, fibre: int) -> slice:
        """Bead indices of fibre ``fibre`` (1-based id)."""
        return slice(int(self._starts[fibre - 1]), int(self._starts[fibre]))

    def fibre_path(self, fibre: int, close: bool = True) -> np.ndarray:
        """(n, 3) bead positions along a fibre; a closed fibre gets its first bead again,
        shifted by one period, at the end (so the path spans exactly one period)."""
        path = self.positions[self.fibre_beads(fibre)]
        if close and self.closed[fibre - 1] and len(path) > 2:
            step = self.minimum_image(path[0] - path[-1])[0]
            path = np.vstack([path, path[-1] + step])
        return path

    def fibres_of_yarn(self, yarn: str | int) -> list[int]:
        """Fibre ids (1-based) of a yarn."""
        return (np.flatnonzero(self.fibre_yarn == self.yarn_id(yarn)) + 1).tolist()

    def yarn_paths(self, yarn: str | int, close: bool = True) -> list[np.ndarray]:
        """Paths of the fibres of one yarn."""
        return [self.fibre_path(f, close) for f in self.fibres_of_yarn(yarn)]

    def fibre_diameter(self, yarn: str | int | None = None) -> float:
        """Median bead diameter (of one yarn) [m]; 0 when unknown."""
        if self.diameters is None:
            return 0.0
        if yarn is None:
            return float(np.median(self.diameters))
        beads = np.concatenate([np.arange(len(self.positions))[self.fibre_beads(f)]
                                for f in self.fibres_of_yarn(yarn)])
        return float(np.median(self.diameters[beads]))


def closed_fibres(fibre_ids: np.ndarray, n_fibres: int, bonds: np.ndarray) -> np.ndarray:
    """Which fibres have a bond from their last bead back to their first."""
    fibre_ids = np.asarray(fibre_ids, np.int64)
    starts = np.searchsorted(fibre_ids, np.arange(1, n_fibres + 1), side="left")
    stops = np.searchsorted(fibre_ids, np.arange(1, n_fibres + 1), side="right") - 1
    bonds = np.asarray(bonds, np.int64).reshape(-1, 2)
    if not len(bonds):
        return np.zeros(n_fibres, bool)
    n = int(max(len(fibre_ids), bonds.max() + 1))
    keys = np.minimum(bonds[:, 0], bonds[:, 1]) * n + np.maximum(bonds[:, 0], bonds[:, 1])
    return (stops - starts >= 2) & np.isin(starts * n + stops, keys)
