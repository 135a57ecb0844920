"""3D woven architectures: straight weft and warp (stuffer) layers locked by binders.

Seen from the side (the x–z plane, warp direction x), a unit cell has
``weft_layers`` layers of weft yarns, each with ``columns`` weft yarns side by
side (weft column *c* at x = (c + ½)·weft spacing). The levels between the weft
layers are numbered as **gaps**: gap 0 is above the top weft layer, gap *k* lies
between weft layers *k* − 1 and *k*, gap ``weft_layers`` is below the bottom
layer. Straight stuffer warps lie in the gaps listed in ``warp_gaps`` (default:
every inner gap, 1 … L − 1).

Across the fabric (y) the unit cell has ``dents`` dents; dent *k* holds one stack
of stuffer warps at y = (k + ¼)·p and one plane of binders at y = (k + ¾)·p
(p: warp spacing, the pitch of the stacks). A binder is given by its gap at each
weft column (the general form): ``binder_paths[dent][binder][column]``.
Between columns it passes smoothly from one gap to the next. With
``separate_binders`` every binder of a dent has its own plane instead: the n
binders of dent *k* lie at y = (k + ¼ + (b + 1)/(n + 1))·p, evenly between the
dent's stuffer stack and the next (binder spacing p/(n + 1), set apart from the
stuffer spacing p); binders in different planes may cross each other. A dent
may then have no binder (an empty list: binders every n-th dent).

Named architectures (see the constructors):

* :meth:`Architecture3D.orthogonal` — binders go straight through the whole
  thickness between weft columns, over ``float_columns`` columns on each face;
* :meth:`Architecture3D.layer_to_layer` — angle interlock in which each binder
  links ``depth`` + 1 neighbouring weft layers (one binder per starting layer),
  any number of columns;
* :meth:`Architecture3D.through_thickness` — angle interlock in which binders
  cross the whole thickness diagonally, one gap per ``step`` columns; any number
  of columns (a cell that is not a whole number of binder periods spreads one
  period over the cell, rounding each column's gap), any number of binders per
  dent (side by side), binders in every ``binder_every``-th dent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError


@dataclass(frozen=True)
class Architecture3D:
    """A 3D woven unit cell (see the module docstring for gaps, dents, columns).

    Args:
        weft_layers: number of weft layers L (>= 1).
        binder_paths: per dent, a list of binders, each the list of its gap
            (0 … L) at every weft column; every binder has one entry per column.
        warp_gaps: gaps that hold a straight stuffer warp in every dent
            (default: the inner gaps 1 … L − 1).
        name: label used in outputs.
        allow_floats: accept a binder that stays in one gap (binds nothing).
        separate_binders: every binder of a dent in its own plane (see the module
            docstring); default: the binders of a dent share one plane.
    """

    weft_layers: int
    binder_paths: tuple
    warp_gaps: tuple | None = None
    name: str = "3d"
    allow_floats: bool = False
    separate_binders: bool = False

    def __post_init__(self):
        n_layers = inputs.positive_int("architecture.weft_layers", self.weft_layers)
        object.__setattr__(self, "weft_layers", n_layers)
        if not isinstance(self.separate_binders, bool):
            raise InputError(f"architecture.separate_binders must be true or false, "
                             f"got {self.separate_binders!r}")
        object.__setattr__(self, "binder_paths", _check_paths(
            self.binder_paths, n_layers, self.allow_floats, self.separate_binders))
        gaps = tuple(range(1, n_layers)) if self.warp_gaps is None else self.warp_gaps
        if not isinstance(gaps, list | tuple | np.ndarray):
            raise InputError(f"architecture.warp_gaps must be a list of gaps 0..{n_layers}, "
                             f"got {gaps!r}")
        clean = []
        for g in gaps:
            if isinstance(g, bool) or not isinstance(g, int | np.integer) \
                    or not 0 <= g <= n_layers:
                raise InputError(f"architecture.warp_gaps entries must be gaps 0..{n_layers} "
                                 f"(0 = above the top weft layer), got {g!r}")
            clean.append(int(g))
        if len(set(clean)) != len(clean):
            raise InputError(f"architecture.warp_gaps lists a gap twice: {clean}")
        object.__setattr__(self, "warp_gaps", tuple(sorted(clean)))

    # -- constructors ------------------------------------------------------------------
    @classmethod
    def orthogonal(cls, weft_layers: int = 3, float_columns: int = 1, dents: int = 2,
                   columns: int | None = None, warp_gaps=None,
                   binder_every: int = 1) -> Architecture3D:
        """Binders over ``float_columns`` weft columns on top, then the same below
        (in every ``binder_every``-th dent only)."""
        n_layers = inputs.positive_int("architecture.weft_layers", weft_layers)
        f = inputs.positive_int("architecture.float_columns", float_columns)
        dents = inputs.positive_int("architecture.dents", dents)
        period = 2 * f
        columns = _columns(columns, period)
        base = [0 if (c % period) < f else n_layers for c in range(columns)]
        every = inputs.positive_int("architecture.binder_every", binder_every)
        paths = [[_shift(base, (k % 2) * f)] if k % every == 0 else [] for k in range(dents)]
        return cls(n_layers, paths, warp_gaps, name=f"orthogonal (float {f})")

    @classmethod
    def layer_to_layer(cls, weft_layers: int = 4, depth: int = 1, step: int = 1,
                       dents: int = 2, columns: int | None = None,
                       warp_gaps=None, binder_every: int = 1) -> Architecture3D:
        """Angle interlock: binder *b* runs between gaps b and b + depth + 1.

        ``columns`` that are not a multiple of the period 2·(depth + 1)·step spread one
        period over the cell (each column's gap rounded); ``binder_every``: binders in
        every n-th dent only.
        """
        n_layers = inputs.positive_int("architecture.weft_layers", weft_layers)
        depth = inputs.positive_int("architecture.depth", depth)
        if depth >= n_layers:
            raise InputError(f"architecture.depth must be < weft_layers = {n_layers} (a binder "
                             f"links depth + 1 layers), got {depth}")
        step = inputs.positive_int("architecture.step", step)
        dents = inputs.positive_int("architecture.dents", dents)
        period = 2 * (depth + 1) * step
        if columns is None or (isinstance(columns, int) and columns % period == 0):
            columns = _columns(columns, period)
            wave = _triangle(depth + 1, step, columns)
        else:
            columns = inputs.positive_int("architecture.columns", columns, minimum=2)
            period = columns
            wave = _spread_triangle(depth + 1, columns)
        every = inputs.positive_int("architecture.binder_every", binder_every)
        paths = [[_shift([b + w for w in wave], (k * period) // dents)
                  for b in range(n_layers - depth)] if k % every == 0 else []
                 for k in range(dents)]
        return cls(n_layers, paths, warp_gaps, name=f"layer-to-layer angle interlock "
                                                    f"(depth {depth}, step {step})")

    @classmethod
    def through_thickness(cls, weft_layers: int = 4, step: int = 1, dents: int = 2,
                          columns: int | None = None, warp_gaps=None, binders: int = 1,
                          binder_every: int = 1) -> Architecture3D:
        """Angle interlock: binders cross all L layers diagonally.

        Args:
            weft_layers: weft layers L.
            step: columns per gap change.
            dents: stuffer stacks across the cell.
            columns: weft columns per cell; a multiple of the period 2·L·step keeps
                the exact triangle wave, any other number (>= 2) spreads one binder
                period over the cell (each column's gap rounded from the triangle).
            warp_gaps: gaps holding stuffers (default the inner ones).
            binders: binders per binding dent, side by side in their own planes
                when > 1, their phases spread evenly over the period.
            binder_every: binders in every n-th dent only (dent 0, n, 2n, ...).
        """
        n_layers = inputs.positive_int("architecture.weft_layers", weft_layers)
        step = inputs.positive_int("architecture.step", step)
        dents = inputs.positive_int("architecture.dents", dents)
        binders = inputs.positive_int("architecture.binders", binders)
        every = inputs.positive_int("architecture.binder_every", binder_every)
        period = 2 * n_layers * step
        if columns is None or (isinstance(columns, int) and columns % period == 0):
            columns = _columns(columns, period)
            wave = _triangle(n_layers, step, columns)
        else:
            columns = inputs.positive_int("architecture.columns", columns, minimum=2)
            period = columns
            wave = _spread_triangle(n_layers, columns)
        binding = [k for k in range(dents) if k % every == 0]
        total = len(binding) * binders
        paths = [[] for _ in range(dents)]
        for q, k in enumerate(k for k in binding for _ in range(binders)):
            shift = (k * period) // dents if binders == 1 and every == 1 \
                else (q * period) // total
            paths[k].append(_shift(wave, shift))
        separate = binders > 1 or every > 1
        return cls(n_layers, paths, warp_gaps, separate_binders=separate,
                   name=f"through-thickness angle interlock (step {step})")

    # -- derived -----------------------------------------------------------------------
    @property
    def columns(self) -> int:
        """Weft columns per unit cell."""
        return next(len(p) for dent in self.binder_paths for p in dent)

    @property
    def dents(self) -> int:
        return len(self.binder_paths)

    @property
    def n_binders(self) -> int:
        return sum(len(d) for d in self.binder_paths)

    @property
    def n_weft(self) -> int:
        return self.weft_layers * self.columns

    @property
    def n_warp(self) -> int:
        return len(self.warp_gaps) * self.dents

    @property
    def n_gaps(self) -> int:
        return self.weft_layers + 1

    def binder_gaps(self) -> set[int]:
        """Gaps a binder passes through at some column."""
        return {g for dent in self.binder_paths for path in dent for g in path}


def _columns(columns, period: int) -> int:
    if columns is None:
        return period
    columns = inputs.positive_int("architecture.columns", columns)
    if columns % period:
        raise InputError(f"architecture.columns must be a multiple of the binder period "
                         f"{period}, got {columns}")
    return columns


def _spread_triangle(height: int, columns: int) -> list[int]:
    """One triangle wave 0 → height → 0 spread over ``columns`` columns, rounded."""
    return [int(round(height * (1.0 - abs(1.0 - 2.0 * c / columns)))) for c in range(columns)]


def _triangle(height: int, step: int, columns: int) -> list[int]:
    """0, 1, …, height, …, 1 with each level held ``step`` columns, repeated."""
    period = 2 * height
    return [(q if q <= height else period - q) for q in
            ((c // step) % period for c in range(columns))]


def _shift(path: list[int], k: int) -> list[int]:
    k %= len(path)
    return list(path[-k:] + path[:-k]) if k else list(path)


def _check_paths(paths, n_layers: int, allow_floats: bool, separate: bool = False) -> tuple:
    where = "architecture.binder_paths"
    if not isinstance(paths, list | tuple) or not paths:
        raise InputError(f"{where} must be a list of dents, each a list of binders, each the "
                         f"list of its gap (0..{n_layers}) at every weft column; got {paths!r}")
    out = []
    columns = None
    for k, dent in enumerate(paths, start=1):
        if not isinstance(dent, list | tuple):
            raise InputError(f"{where}: dent {k} must be a list of binders, got {dent!r}")
        clean_dent = []
        for b, path in enumerate(dent, start=1):
            name = f"binder {b} of dent {k}"
            if not isinstance(path, list | tuple) or not path:
                raise InputError(f"{where}: {name} must be a list of gaps, one per weft "
                                 f"column, got {path!r}")
            if columns is None:
                columns = len(path)
            if len(path) != columns:
                raise InputError(f"{where}: {name} has {len(path)} columns but the first "
                                 f"binder has {columns}: every binder needs one gap per weft "
                                 f"column")
            for c, g in enumerate(path, start=1):
                if isinstance(g, bool) or not isinstance(g, int | np.integer) \
                        or not 0 <= g <= n_layers:
                    raise InputError(f"{where}: {name}, column {c} must be a gap 0..{n_layers} "
                                     f"(0 = above the top weft layer, {n_layers} = below the "
                                     f"bottom one), got {g!r}")
            if not allow_floats and min(path) == max(path):
                raise InputError(f"{where}: {name} stays in gap {path[0]} at every column and "
                                 f"binds nothing; change its path or set allow_floats = true")
            clean_dent.append(tuple(int(g) for g in path))
        for a in range(0 if separate else len(clean_dent)):  # separate planes may cross
            for b in range(a + 1, len(clean_dent)):
                pa, pb = np.array(clean_dent[a]), np.array(clean_dent[b])
                same = np.flatnonzero(pa == pb)
                if same.size:
                    raise InputError(f"{where}: binders {a + 1} and {b + 1} of dent {k} are both "
                                     f"in gap {pa[same[0]]} at column {same[0] + 1}; binders of "
                                     f"one dent need different gaps at every column")
                sign = np.sign(pa - pb)
                crossing = np.flatnonzero(sign != np.roll(sign, -1))
                if crossing.size:
                    c = crossing[0]
                    raise InputError(f"{where}: binders {a + 1} and {b + 1} of dent {k} cross "
                                     f"between columns {c + 1} and {(c + 1) % columns + 1}; "
                                     f"binders of one dent must keep their order")
        out.append(tuple(clean_dent))
    if columns is None:
        raise InputError(f"{where}: the architecture has no binder; give at least one (its "
                         f"path sets the number of weft columns)")
    return tuple(out)
