"""Read the LAMMPS dumps fabmd's trajectory block writes.

* ``trajectory.bin`` — ``dump custom`` in LAMMPS's binary format (revision 2:
  every frame starts with the ``DUMPCUSTOM`` magic string, units, time and
  column names; then the per-atom values as doubles in one chunk per writing
  rank). See LAMMPS ``tools/binary2txt.cpp`` for the layout.
* ``bonds.dump`` — ``dump local`` text with ``ITEM: BONDS`` sections.

Both are read frame by frame, so a long trajectory never sits in memory whole.
"""

from __future__ import annotations

import itertools
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError

_BOUNDARY = {0: "p", 1: "f", 2: "s", 3: "m"}


@dataclass
class DumpFrame:
    """One frame of a LAMMPS dump.

    ``data`` holds one row per atom (or bond) and one column per name in ``columns``.
    """

    step: int
    time: float | None
    box_lo: np.ndarray
    box_hi: np.ndarray
    boundary: str
    columns: list[str]
    data: np.ndarray

    def column(self, name: str) -> np.ndarray:
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise InputError(f"dump frame at step {self.step} has no column {name!r} "
                             f"(columns: {' '.join(self.columns)})") from None


def _read(f, fmt: str):
    size = struct.calcsize(fmt)
    raw = f.read(size)
    if len(raw) < size:
        raise EOFError
    return struct.unpack(fmt, raw)


def iter_binary_dump(path: Path) -> Iterator[DumpFrame]:
    """Frames of a binary ``dump custom`` file (LAMMPS 2021 and later layout).

    A frame cut short at the end of the file (a run killed while writing) is
    dropped.
    """
    path = Path(path)
    columns: list[str] = []
    with open(path, "rb") as f:
        while True:
            try:
                (step,) = _read(f, "<q")
                magic = revision = None
                if step < 0:
                    magic = f.read(-step).decode()
                    endian, revision = _read(f, "<ii")
                    if endian != 1:
                        raise InputError(f"{path}: written on a machine of other byte order")
                    (step,) = _read(f, "<q")
                (natoms,) = _read(f, "<q")
                (triclinic,) = _read(f, "<i")
                bounds = _read(f, "<6i")
                box = _read(f, "<6d")
                if triclinic:
                    raise InputError(f"{path}: triclinic boxes are not supported")
                (size_one,) = _read(f, "<i")
                time = None
                if magic is not None and revision > 1:
                    (n,) = _read(f, "<i")
                    f.read(n)  # unit style
                    (flag,) = _read(f, "<b")
                    if flag:
                        (time,) = _read(f, "<d")
                    (n,) = _read(f, "<i")
                    columns = f.read(n).decode().split()
                (nchunk,) = _read(f, "<i")
                parts = []
                for _ in range(nchunk):
                    (n,) = _read(f, "<i")
                    chunk = np.fromfile(f, dtype="<f8", count=n)
                    if len(chunk) < n:
                        raise EOFError
                    parts.append(chunk)
            except EOFError:  # end of file, or a frame cut short by a run that stopped
                return
            data = np.concatenate(parts) if parts else np.zeros(0)
            if data.size != natoms * size_one:
                raise InputError(f"{path}: frame at step {step} holds {data.size} values, "
                                 f"expected {natoms} x {size_one}")
            boundary = " ".join(_BOUNDARY.get(bounds[2 * k], "?") + _BOUNDARY.get(
                bounds[2 * k + 1], "?") for k in range(3))
            yield DumpFrame(step=int(step), time=time, box_lo=np.array(box[0::2]),
                            box_hi=np.array(box[1::2]), boundary=boundary,
                            columns=list(columns) or [f"c{i}" for i in range(size_one)],
                            data=data.reshape(natoms, size_one))


def iter_text_dump(path: Path) -> Iterator[DumpFrame]:
    """Frames of a text dump (``dump custom`` or ``dump local``; orthogonal box)."""
    path = Path(path)
    with open(path) as f:
        while True:
            step = None
            time = None
            count = None
            lo = np.zeros(3)
            hi = np.zeros(3)
            boundary = ""
            columns: list[str] = []
            line = f.readline()
            if not line:
                return
            while line:
                item = line.strip()
                if item == "ITEM: TIME":
                    time = float(f.readline())
                elif item == "ITEM: TIMESTEP":
                    step = int(f.readline())
                elif item.startswith("ITEM: NUMBER OF"):
                    count = int(f.readline())
                elif item.startswith("ITEM: BOX BOUNDS"):
                    boundary = " ".join(item.split()[3:])
                    for k in range(3):
                        lo[k], hi[k] = (float(v) for v in f.readline().split()[:2])
                elif item.startswith("ITEM: ") and step is not None and count is not None:
                    columns = item.split()[2:]
                    break
                line = f.readline()
            if step is None or count is None or not columns:
                return
            lines = list(itertools.islice(f, count))
            if len(lines) < count or count and not lines[-1].endswith("\n"):
                return  # the last frame was cut short
            values = np.array("".join(lines).split(), dtype=float)
            if values.size != count * len(columns):
                return  # cut short
            yield DumpFrame(step=step, time=time, box_lo=lo.copy(), box_hi=hi.copy(),
                            boundary=boundary, columns=columns,
                            data=values.reshape(count, len(columns)))


def iter_dump(path: Path) -> Iterator[DumpFrame]:
    """Frames of a binary (``.bin``) or text dump."""
    path = Path(path)
    return iter_binary_dump(path) if path.suffix == ".bin" else iter_text_dump(path)
