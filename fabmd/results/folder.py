"""Run folders: one per run, never silently overwritten.

A run folder holds the resolved scene (``scene.json``), the LAMMPS input and
log, the data file, ``curve.csv``, ``summary.json`` and plots. It is marked by a
``.fabmd-run`` file; ``overwrite=True`` replaces only folders that carry the
mark (or are empty), so a typo can never wipe an unrelated folder.

Under ``mpirun`` rank 0 decides and creates; the path or the error reaches
every rank, so all ranks act alike.
"""

from __future__ import annotations

import csv
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..engine import mpi
from ..errors import OutputExists

MARKER = ".fabmd-run"


def _prepare_on_root(path: Path | None, overwrite: bool, prefix: str) -> Path:
    if path is None:
        return Path(tempfile.mkdtemp(prefix=f"fabmd-{prefix}-"))
    path = Path(path).resolve()
    if path.exists() and (not path.is_dir() or any(path.iterdir())):
        if not overwrite:
            raise OutputExists(f"results folder {path} exists already; choose another --out "
                               f"or pass --overwrite (overwrite=True) to replace it")
        if not path.is_dir() or not (path / MARKER).exists():
            raise OutputExists(f"{path} exists and is not a fabmd results folder (no {MARKER}); "
                               f"fabmd will not delete it even with --overwrite")
        shutil.rmtree(path)
    path.mkdir(parents=True, exist_ok=True)
    return path


def prepare_run_folder(path: Path | None, overwrite: bool = False,
                       prefix: str = "run") -> Path:
    """Create the run folder (a temporary one if ``path`` is None) and mark it.

    Raises:
        OutputExists: the folder exists and ``overwrite`` is False, or it is not
            a fabmd folder.
    """
    message = ""
    if mpi.is_root():
        try:
            folder = _prepare_on_root(path, overwrite, prefix)
            (folder / MARKER).write_text("fabmd run folder\n")
            message = "OK:" + str(folder)
        except OutputExists as exc:
            message = "ERR:" + str(exc)
    message = mpi.bcast_text(message)
    if message.startswith("ERR:"):
        raise OutputExists(message[4:])
    return Path(message[3:])


def write_json(path: Path, obj) -> None:
    """Write JSON on rank 0 (numpy values converted)."""
    if mpi.is_root():
        Path(path).write_text(json.dumps(obj, indent=2, default=_jsonable) + "\n")


def _jsonable(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def write_csv(path: Path, columns: dict[str, np.ndarray]) -> None:
    """Write named columns (names carry units, e.g. ``force_n``) on rank 0."""
    if not mpi.is_root():
        return
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], float) for n in names])
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(names)
        for row in data:
            writer.writerow([f"{v:.10g}" for v in row])


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """Read a ``curve.csv`` back into named columns."""
    with open(path) as f:
        names = next(csv.reader(f))
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {n: data[:, i] for i, n in enumerate(names)}


def _unique_steps(names: list[str], data: np.ndarray) -> np.ndarray:
    """Rows with a repeated ``step`` (a run set up again prints its first step twice)
    are dropped, keeping the last."""
    if "step" not in names or len(data) == 0:
        return data
    steps = data[:, names.index("step")]
    _, last = np.unique(steps[::-1], return_index=True)
    keep = np.sort(len(steps) - 1 - last)
    return data[keep]


def read_print_file(path: Path) -> dict[str, np.ndarray]:
    """Read a LAMMPS ``fix print`` file whose title line is ``# name1 name2 ...``."""
    lines = Path(path).read_text().splitlines()
    names = lines[0].lstrip("#").split()
    rows = [line.split() for line in lines[1:] if line.strip() and not line.startswith("#")]
    data = _unique_steps(names, np.array(rows, dtype=float).reshape(-1, len(names)))
    return {n: data[:, i] for i, n in enumerate(names)}


def read_ave_time(path: Path) -> dict[str, np.ndarray]:
    """Read a LAMMPS ``fix ave/time`` file whose ``title2`` line names the columns."""
    lines = Path(path).read_text().splitlines()
    names = lines[1].lstrip("#").split()
    rows = [line.split() for line in lines if line.strip() and not line.startswith("#")]
    data = _unique_steps(names, np.array(rows, dtype=float).reshape(-1, len(names)))
    return {n: data[:, i] for i, n in enumerate(names)}
