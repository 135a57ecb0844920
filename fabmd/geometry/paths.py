"""Yarn centrelines and virtual-fibre paths (loose, idealised geometry).

Every yarn lies in a vertical plane: warp and binder yarns in an x–z plane at
y = ``offset_m``, weft yarns in a y–z plane at x = ``offset_m``. Its height z(u)
along its own axis u is given by **nodes** — the crossings where it passes
above, below or between crossing yarns:

* at a node the yarn is level over ±``plateau_m`` (part of the crossed yarn's
  width);
* between nodes it moves from one height to the next along half a cosine
  wave (zero slope at both ends); with no plateau a plain weave is a sine wave;
* a yarn without nodes is straight (stuffer warps, 3D wefts).

The node pattern repeats with ``period_m`` (the unit cell); a tile of n unit
cells is the same function over n periods, so a periodic fabric has every yarn
continuous across the unit-cell boundary.

A virtual fibre sits at a fixed offset (across, through-thickness) in the yarn
section, which turns with the path: position = centreline + across·lateral +
through·normal, where lateral is the horizontal direction across the yarn and
normal the in-plane normal of the centreline. :func:`fibre_beads` places beads
along a fibre at a given chord length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError


@dataclass(frozen=True)
class YarnPath:
    """Centreline of one yarn (SI; see the module docstring).

    Args:
        name: e.g. ``"warp-3"``.
        family: ``"warp"``, ``"weft"`` or ``"binder"``.
        axis: 0 when the yarn runs along x, 1 along y.
        offset_m: the yarn plane's other in-plane coordinate (y for axis 0, x for 1).
        length_m: extent along the axis, from u = 0.
        period_m: the node pattern repeats with this period.
        node_u_m: node positions in [0, period).
        node_z_m: height at each node.
        plateau_m: level half-length at each node.
        z_m: height of a straight yarn (no nodes).
        level: layer (3D weft) or gap (3D warp and binder) index; -1 in 2D.
        cell_index: index of the unit-cell yarn this yarn copies (same shape).
    """

    name: str
    family: str
    axis: int
    offset_m: float
    length_m: float
    period_m: float
    node_u_m: tuple = ()
    node_z_m: tuple = ()
    plateau_m: tuple = ()
    z_m: float = 0.0
    level: int = -1
    cell_index: int = 0
    _ext: tuple = field(default=(), repr=False, compare=False)

    def __post_init__(self):
        n = np.asarray(self.node_u_m, float)
        z = np.asarray(self.node_z_m, float)
        p = np.broadcast_to(np.asarray(self.plateau_m, float), n.shape)
        if len(n) != len(z):
            raise ValueError("node_u_m and node_z_m differ in length")
        if len(n):
            order = np.argsort(n)
            n, z, p = n[order], z[order], p[order]
            ext_n = np.concatenate([[n[-1] - self.period_m], n, [n[0] + self.period_m]])
            ext_z = np.concatenate([[z[-1]], z, [z[0]]])
            ext_p = np.concatenate([[p[-1]], p, [p[0]]])
            room = (ext_n[1:] - ext_p[1:]) - (ext_n[:-1] + ext_p[:-1])
            if np.any(room <= 0):
                raise InputError(f"yarn {self.name} has no room to change level between "
                                 f"crossings: reduce fabric.plateau or increase the spacing")
            object.__setattr__(self, "_ext", (ext_n, ext_z, ext_p))

    @property
    def straight(self) -> bool:
        return not len(self.node_u_m)

    def profile(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Height z(u) and slope dz/du at positions ``u`` along the axis [m]."""
        u = np.asarray(u, float)
        if self.straight:
            return np.full(u.shape, float(self.z_m)), np.zeros(u.shape)
        ext_n, ext_z, ext_p = self._ext
        t = np.mod(u, self.period_m)
        breaks = np.column_stack([ext_n - ext_p, ext_n + ext_p]).ravel()
        idx = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, len(breaks) - 2)
        seg = idx // 2
        level = idx % 2 == 0
        nxt = np.minimum(seg + 1, len(ext_n) - 1)
        start = ext_n[seg] + ext_p[seg]
        span = np.where(level, 1.0, (ext_n[nxt] - ext_p[nxt]) - start)
        tau = np.clip((t - start) / span, 0.0, 1.0)
        dz_total = ext_z[nxt] - ext_z[seg]
        z = np.where(level, ext_z[seg], ext_z[seg] + dz_total * 0.5 * (1 - np.cos(np.pi * tau)))
        slope = np.where(level, 0.0, dz_total * 0.5 * np.pi / span * np.sin(np.pi * tau))
        return z, slope

    def junctions(self) -> np.ndarray:
        """Positions in [0, length] where a level stretch meets a transition [m]."""
        if self.straight:
            return np.zeros(0)
        ext_n, _, ext_p = self._ext
        base = np.mod(np.concatenate([ext_n - ext_p, ext_n + ext_p]), self.period_m)
        reps = np.arange(int(math.ceil(self.length_m / self.period_m)) + 1) * self.period_m
        allu = (base[None, :] + reps[:, None]).ravel()
        return np.unique(allu[(allu > 0) & (allu < self.length_m)])

    def max_curvature(self, samples_per_period: int = 4000) -> float:
        """Largest curvature of the centreline [1/m] (0 for a straight yarn)."""
        if self.straight:
            return 0.0
        u = np.linspace(0.0, self.period_m, samples_per_period + 1)
        ext_n, ext_z, ext_p = self._ext
        u = np.concatenate([u, np.mod(ext_n + ext_p, self.period_m),
                            np.mod(ext_n - ext_p, self.period_m)])
        z, s = self.profile(u)
        # z'' of the half-cosine at its ends is the largest: evaluate analytically
        t = np.mod(u, self.period_m)
        breaks = np.column_stack([ext_n - ext_p, ext_n + ext_p]).ravel()
        idx = np.clip(np.searchsorted(breaks, t, side="right") - 1, 0, len(breaks) - 2)
        seg = idx // 2
        nxt = np.minimum(seg + 1, len(ext_n) - 1)
        start = ext_n[seg] + ext_p[seg]
        span = np.where(idx % 2 == 0, 1.0, (ext_n[nxt] - ext_p[nxt]) - start)
        tau = np.clip((t - start) / span, 0.0, 1.0)
        curv = np.where(idx % 2 == 0, 0.0, (ext_z[nxt] - ext_z[seg]) * 0.5 * np.pi**2 / span**2
                        * np.cos(np.pi * tau))
        return float(np.max(np.abs(curv) / (1 + s * s) ** 1.5))

    def centreline(self, spacing_m: float) -> np.ndarray:
        """(k, 3) points along the centreline, about ``spacing_m`` apart [m]."""
        k = max(2, int(math.ceil(self.length_m / spacing_m)) + 1)
        u = np.linspace(0.0, self.length_m, k)
        z, _ = self.profile(u)
        return self._place(u, np.zeros_like(u), z)

    def _place(self, along: np.ndarray, across: np.ndarray, z: np.ndarray) -> np.ndarray:
        out = np.empty(along.shape + (3,))
        if self.axis == 0:
            out[..., 0], out[..., 1] = along, self.offset_m + across
        else:
            out[..., 0], out[..., 1] = self.offset_m + across, along
        out[..., 2] = z
        return out

    def translated(self, name: str, d_offset: float) -> YarnPath:
        """The same yarn moved sideways by ``d_offset`` [m]."""
        return YarnPath(name, self.family, self.axis, self.offset_m + d_offset, self.length_m,
                        self.period_m, self.node_u_m, self.node_z_m, self.plateau_m, self.z_m,
                        self.level, self.cell_index)


@dataclass
class FibreBeads:
    """Beads of one virtual fibre: positions (k, 3) [m] and their chord spacing [m]."""

    positions: np.ndarray
    spacing_m: float


def _chord_arc(along: np.ndarray, height: np.ndarray, spacing_m: float,
               periodic: bool) -> np.ndarray:
    """Arc length [m] from the first grid point of a fibre's line (``along``, ``height``
    [m]), corrected for curvature so that it measures chords of ``spacing_m``:
    chord = arc·(1 − κ²l²/24)."""
    da, dz = np.diff(along), np.diff(height)
    ds = np.hypot(da, dz)
    theta = np.unwrap(np.arctan2(dz, da))
    if periodic:
        turn = np.diff(np.concatenate([theta[-1:], theta, theta[:1]]))
        mean_ds = 0.5 * (np.concatenate([ds[-1:], ds]) + np.concatenate([ds, ds[:1]]))
    else:
        turn = np.concatenate([[0.0], np.diff(theta), [0.0]])
        mean_ds = 0.5 * (np.concatenate([ds[:1], ds]) + np.concatenate([ds, ds[-1:]]))
    kappa_node = np.abs(turn) / mean_ds
    kappa = 0.5 * (kappa_node[:-1] + kappa_node[1:])
    return np.concatenate([[0.0], np.cumsum(ds * (1.0 - kappa**2 * spacing_m**2 / 24.0))])


def fibre_beads(path: YarnPath, offsets: np.ndarray, spacing_m: float,
                periodic: bool, phases: np.ndarray | None = None) -> list[FibreBeads]:
    """Beads along every fibre of a yarn.

    Args:
        path: the yarn centreline.
        offsets: (n, 2) fibre offsets (across, through-thickness) in the section [m].
        spacing_m: wanted distance between neighbouring beads (the bond length).
        periodic: the fibre closes on itself over ``path.length_m`` (which must be a
            whole number of periods); its bead count is rounded so that the chord
            spacing is as close to ``spacing_m`` as possible, and returned.
        phases: (n,) where each fibre's first bead sits, in bead spacings from the
            path's start, in [0, 1) (default 0: the fibres of the yarn in register).

    Non-periodic fibres start at their phase (u = 0 by default) and get beads exactly
    ``spacing_m`` apart (chord) up to the end of the path. Beads are placed by arc length corrected
    for curvature (chord = arc·(1 − κ²l²/24)), so chords match to O(l⁴).
    """
    offsets = np.asarray(offsets, float).reshape(-1, 2)
    step = spacing_m / 4.0
    m = max(8, int(math.ceil(path.length_m / step)))
    # the slope is continuous but the curvature jumps where level stretches meet
    # transitions: grid points there keep the arc-length interpolation exact
    u = np.union1d(np.linspace(0.0, path.length_m, m + 1), path.junctions())
    z, slope = path.profile(u)
    norm = np.sqrt(1.0 + slope * slope)
    nx, nz = -slope / norm, 1.0 / norm  # in-plane normal (along, z)
    phases = np.zeros(len(offsets)) if phases is None else np.asarray(phases, float)
    out = []
    for (across, through), phase in zip(offsets, phases, strict=True):
        sigma = _chord_arc(u + through * nx, z + through * nz, spacing_m, periodic)
        total = sigma[-1]
        chord, targets = _first_targets(total, spacing_m, periodic, phase)
        if len(targets) < 2:
            raise InputError(f"yarn {path.name} is shorter than one bead spacing")

        def place(tg: np.ndarray, sigma=sigma, across=across, through=through) -> np.ndarray:
            ub = np.interp(tg, sigma, u)
            zb, sb = path.profile(ub)
            nb = np.sqrt(1.0 + sb * sb)
            return path._place(ub - through * sb / nb, np.full_like(ub, across),
                               zb + through / nb)

        pos = place(targets)
        for _ in range(REFINE_STEPS):  # make every chord the same length
            closing = pos[:1] + _period_shift(path) if periodic else pos[:0]
            chords = np.linalg.norm(np.diff(np.vstack([pos, closing]), axis=0), axis=1)
            if not np.all(chords > 0):  # the fibre's offset curve has a cusp
                raise InputError(f"yarn {path.name}: its fibre {1e3 * through:.3g} mm from the "
                                 f"centreline would fold (two of its beads coincide where the "
                                 f"yarn bends); reduce the yarn height or fabric.plateau, or "
                                 f"increase the spacing of the yarns it crosses")
            if periodic:
                chord = float(chords.mean())
            start = targets[0]  # the fibre's phase stays; the chords even out after it
            step_sigma = np.diff(np.append(targets, total + start if periodic
                                           else targets[-1:]))
            if not periodic:
                step_sigma = step_sigma[:-1]
            step_sigma *= chord / chords
            if periodic:
                step_sigma *= total / step_sigma.sum()
                targets = start + np.concatenate([[0.0], np.cumsum(step_sigma[:-1])])
            else:
                targets = start + np.concatenate([[0.0], np.cumsum(step_sigma)])
                targets = targets[targets <= total * (1 + 1e-12)]
            pos = place(targets)
        if periodic:
            closing = pos[:1] + _period_shift(path)
            chord = float(np.linalg.norm(np.diff(np.vstack([pos, closing]), axis=0),
                                         axis=1).mean())
        out.append(FibreBeads(pos, chord))
    return out


def _first_targets(total: float, spacing_m: float, periodic: bool, phase: float
                   ) -> tuple[float, np.ndarray]:
    """Chord and arc positions of a fibre's beads before the chords are evened out: from
    ``phase`` chords along; a periodic fibre gets a whole number of chords."""
    if periodic:
        n_beads = max(3, int(round(total / spacing_m)))
        chord = total / n_beads
        return chord, (np.arange(n_beads) + phase) * chord
    first = phase * spacing_m
    return spacing_m, first + np.arange(
        int(math.floor((total - first) / spacing_m + 1e-9)) + 1) * spacing_m


#: fixed-point passes that equalise chord lengths after placement by arc length
REFINE_STEPS = 3


def _period_shift(path: YarnPath) -> np.ndarray:
    shift = np.zeros((1, 3))
    shift[0, path.axis] = path.length_m
    return shift
