"""2D weave matrices.

A weave is the repeat of warp × weft crossings: ``matrix[i][j]`` is 1 where warp
yarn *i* (row, an end) lies above weft yarn *j* (column, a pick), 0 where it lies
below. Plain = ``[[1, 0], [0, 1]]``.

* :meth:`Weave.plain`
* :meth:`Weave.twill` — ``up``/``down`` twill: warp *i* is up over ``up`` picks
  then down under ``down`` picks, each end shifted by ``shift`` picks;
* :meth:`Weave.satin` — ``n``-end satin: one warp-up per row, shifted by ``move``
  (coprime with n, 2 <= move <= n − 2);
* :meth:`Weave.basket` — ``n`` × ``m`` basket: plain weave with groups of ``n``
  ends and ``m`` picks working together;
* :meth:`Weave.from_matrix` — any 0/1 matrix.

A yarn whose row (or column) is all 1 or all 0 never interlaces: it floats loose
on one face. That is refused unless ``allow_floats=True``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import inputs
from ..errors import InputError


@dataclass(frozen=True)
class Weave:
    """A 2D weave repeat.

    Args:
        matrix: rows = warp yarns (ends), columns = weft yarns (picks); 1 where
            the warp is on top. Lists, tuples or a numpy array of 0/1.
        name: label used in outputs.
        allow_floats: accept yarns that never interlace.
    """

    matrix: tuple
    name: str = "matrix"
    allow_floats: bool = False

    def __post_init__(self):
        object.__setattr__(self, "matrix", _check_matrix(self.matrix, self.allow_floats))

    # -- constructors ------------------------------------------------------------------
    @classmethod
    def plain(cls) -> Weave:
        return cls(((1, 0), (0, 1)), name="plain")

    @classmethod
    def twill(cls, up: int = 2, down: int = 2, shift: int = 1) -> Weave:
        up = inputs.positive_int("weave.up", up)
        down = inputs.positive_int("weave.down", down)
        n = up + down
        shift = inputs.positive_int("weave.shift", shift)
        if math.gcd(shift, n) != 1 or shift >= n:
            raise InputError(f"weave.shift must be coprime with up + down = {n} and < {n}, "
                             f"got {shift}")
        m = [[1 if (j - i * shift) % n < up else 0 for j in range(n)] for i in range(n)]
        return cls(m, name=f"twill {up}/{down}")

    @classmethod
    def satin(cls, n: int = 5, move: int | None = None) -> Weave:
        n = inputs.positive_int("weave.n", n, minimum=5)
        allowed = [k for k in range(2, n - 1) if math.gcd(k, n) == 1]
        if not allowed:
            raise InputError(f"weave.n = {n} has no regular satin move (a move coprime with "
                             f"{n} in 2..{n - 2}); use n = 5, 7, 8, 9, 10, ...")
        if move is None:
            move = allowed[0]
        if isinstance(move, bool) or not isinstance(move, int) or move not in allowed:
            raise InputError(f"weave.move must be coprime with n = {n} and in 2..{n - 2} "
                             f"(allowed: {', '.join(map(str, allowed))}), got {move!r}")
        m = [[1 if j == (i * move) % n else 0 for j in range(n)] for i in range(n)]
        return cls(m, name=f"satin {n} (move {move})")

    @classmethod
    def basket(cls, n: int = 2, m: int | None = None) -> Weave:
        n = inputs.positive_int("weave.n", n)
        m = n if m is None else inputs.positive_int("weave.m", m)
        mat = [[1 if (i // n) == (j // m) else 0 for j in range(2 * m)] for i in range(2 * n)]
        return cls(mat, name=f"basket {n}x{m}")

    @classmethod
    def from_matrix(cls, matrix, allow_floats: bool = False, name: str = "matrix") -> Weave:
        return cls(matrix, name=name, allow_floats=allow_floats)

    # -- derived -----------------------------------------------------------------------
    @property
    def array(self) -> np.ndarray:
        """The matrix as an (n_warp, n_weft) int array."""
        return np.array(self.matrix, dtype=np.int64)

    @property
    def n_warp(self) -> int:
        return len(self.matrix)

    @property
    def n_weft(self) -> int:
        return len(self.matrix[0])


def _check_matrix(matrix, allow_floats: bool) -> tuple:
    if isinstance(matrix, np.ndarray):
        matrix = matrix.tolist()
    if not isinstance(matrix, list | tuple) or not matrix:
        raise InputError(f"weave.matrix must be a non-empty list of rows of 0/1 "
                         f"(one row per warp yarn), got {matrix!r}")
    rows = []
    for i, row in enumerate(matrix, start=1):
        if not isinstance(row, list | tuple) or not row:
            raise InputError(f"weave.matrix row {i} must be a non-empty list of 0/1, "
                             f"got {row!r}")
        if len(row) != len(matrix[0]):
            raise InputError(f"weave.matrix row {i} has {len(row)} entries but row 1 has "
                             f"{len(matrix[0])}: every row (a warp yarn) needs one entry "
                             f"per weft yarn")
        for j, v in enumerate(row, start=1):
            if isinstance(v, bool) or v not in (0, 1):
                raise InputError(f"weave.matrix row {i}, column {j} must be 0 or 1 "
                                 f"(1 = warp on top), got {v!r}")
        rows.append(tuple(int(v) for v in row))
    a = np.array(rows)
    if not allow_floats:
        for i, row in enumerate(a, start=1):
            if row.min() == row.max():
                side = "above" if row[0] else "below"
                raise InputError(f"weave.matrix: warp yarn {i} (row {i}) never interlaces: it "
                                 f"stays {side} every weft yarn; change the row or set "
                                 f"allow_floats = true")
        for j, col in enumerate(a.T, start=1):
            if col.min() == col.max():
                side = "below" if col[0] else "above"
                raise InputError(f"weave.matrix: weft yarn {j} (column {j}) never interlaces: "
                                 f"it stays {side} every warp yarn; change the column or set "
                                 f"allow_floats = true")
    return tuple(rows)
