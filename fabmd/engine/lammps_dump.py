"""Read the LAMMPS dumps fabmd's trajectory block writes.

* ``trajectory.bin`` — ``dump custom`` in LAMMPS's binary format (revision 2:
  every frame starts with the ``DUMPCUSTOM`` magic string, units, time and
  column names; then the per-atom values as doubles in one chunk per writing
  rank). See LAMMPS ``tools/binary2txt.cpp`` for the layout.
* ``bonds.dump`` — ``dump local`` text with ``ITEM: BONDS`` sections.

Both are read frame by frame, so a long trajectory never sits in memory whole.
Triclinic boxes (a sheared periodic cell) are read as the box itself (``box_lo``,
``box_hi`` of the untilted cell, as in a data file) and its ``tilt`` (xy, xz, yz);
LAMMPS writes the bounding box of the tilted cell, which is converted back.
:func:`truncate_dump` cuts a dump back to the frames before a step (a run resumed
from a checkpoint appends to it).
"""

from __future__ import annotations

import itertools
import re
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
    tilt: np.ndarray | None = None  # xy, xz, yz of a triclinic box [m]
    offset: int = -1  # where the frame starts and ends in its file (bytes; binary dumps)
    end_offset: int = -1

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


def box_from_bounds(lo_bound, hi_bound, tilt) -> tuple[np.ndarray, np.ndarray]:
    """The box (lo, hi) of a triclinic cell from the bounding box LAMMPS dumps write."""
    lo, hi = np.array(lo_bound, float), np.array(hi_bound, float)
    xy, xz, yz = (float(t) for t in tilt)
    lo[0] -= min(0.0, xy, xz, xy + xz)
    hi[0] -= max(0.0, xy, xz, xy + xz)
    lo[1] -= min(0.0, yz)
    hi[1] -= max(0.0, yz)
    return lo, hi


def iter_binary_dump(path: Path) -> Iterator[DumpFrame]:
    """Frames of a binary ``dump custom`` file (LAMMPS 2021 and later layout).

    A frame cut short at the end of the file (a run killed while writing) is
    dropped.
    """
    path = Path(path)
    columns: list[str] = []
    with open(path, "rb") as f:
        while True:
            offset = f.tell()
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
                tilt = np.array(_read(f, "<3d")) if triclinic else None
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
            lo, hi = np.array(box[0::2]), np.array(box[1::2])
            if tilt is not None:
                lo, hi = box_from_bounds(lo, hi, tilt)
            yield DumpFrame(step=int(step), time=time, box_lo=lo, box_hi=hi, boundary=boundary,
                            columns=list(columns) or [f"c{i}" for i in range(size_one)],
                            data=data.reshape(natoms, size_one), tilt=tilt, offset=offset,
                            end_offset=f.tell())


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
            tilt = None
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
                    words = item.split()[3:]
                    triclinic = words[:3] == ["xy", "xz", "yz"]
                    boundary = " ".join(words[3:] if triclinic else words)
                    tilt = np.zeros(3) if triclinic else None
                    for k in range(3):
                        values = [float(v) for v in f.readline().split()]
                        lo[k], hi[k] = values[:2]
                        if triclinic:
                            tilt[k] = values[2]
                    if triclinic:
                        lo, hi = box_from_bounds(lo, hi, tilt)
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
                            data=values.reshape(count, len(columns)), tilt=tilt)


def iter_dump(path: Path) -> Iterator[DumpFrame]:
    """Frames of a binary (``.bin``) or text dump."""
    path = Path(path)
    return iter_binary_dump(path) if path.suffix == ".bin" else iter_text_dump(path)


def truncate_dump(path: Path, step: int) -> int:
    """Cut a dump back to its frames before ``step`` (a frame cut short at its end goes
    too); returns the frames kept. A missing file is left alone (0)."""
    path = Path(path)
    if not path.exists():
        return 0
    kept, end = 0, 0
    if path.suffix == ".bin":
        for frame in iter_binary_dump(path):
            if frame.step >= step:
                break
            kept, end = kept + 1, frame.end_offset
    else:
        data = path.read_bytes()
        starts = [m.start() for m in re.finditer(rb"(?m)^ITEM: TIMESTEP\n", data)]
        for k, start in enumerate(starts):
            words = data[start:start + 64].split(b"\n")
            try:
                frame_step = int(words[1])
            except (IndexError, ValueError):
                break
            last = k + 1 == len(starts)
            if frame_step >= step or (last and not data.endswith(b"\n")):
                break
            kept, end = kept + 1, len(data) if last else starts[k + 1]
    with open(path, "r+b") as f:
        f.truncate(end)
    return kept
