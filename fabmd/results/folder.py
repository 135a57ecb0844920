"""Run folders: one per run, never silently overwritten.

A run folder holds the resolved scene (``scene.json``), the LAMMPS input and
log, the data file, ``curve.csv``, ``summary.json`` and plots. It is marked by a
``.fabmd-run`` file; ``overwrite=True`` replaces only folders that carry the
mark (or are empty), so a typo can never wipe an unrelated folder.

Nothing is lost: :func:`begin_run` / :func:`finish_run` / :func:`abandon_run` make a run
that replaces an existing folder write into the sibling ``<folder>.partial`` and swap it
in only when it succeeded; a failure leaves the old folder as it was and keeps the failed
attempt, with ``failure.json``, in ``<folder>.failed`` (an interrupted one stays in
``<folder>.partial`` for ``--resume``).

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
    if path.exists() and (not path.is_dir() or not _only_marker(path)):
        _check_replaceable(path, overwrite)
        shutil.rmtree(path)
    path.mkdir(parents=True, exist_ok=True)
    return path


def _only_marker(path: Path) -> bool:
    """Empty, or holding only the mark (a folder :func:`begin_run` made for this run)."""
    return all(p.name == MARKER for p in path.iterdir())


def prepare_run_folder(path: Path | None, overwrite: bool = False,
                       prefix: str = "run") -> Path:
    """Create the run folder (a temporary one if ``path`` is None) and mark it.

    Raises:
        OutputExists: the folder exists and ``overwrite`` is False, or it is not
            a fabmd folder.
    """
    return _marked_on_root(lambda: _prepare_on_root(path, overwrite, prefix))


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


# -- replacing a folder only when the new run succeeded ----------------------------------
PARTIAL = ".partial"
FAILED = ".failed"


def sibling(path: Path, suffix: str) -> Path:
    """``<path><suffix>`` beside ``path`` (``runs/t`` -> ``runs/t.partial``)."""
    path = Path(path).resolve()
    return path.with_name(path.name + suffix)


def is_finished(path: Path) -> bool:
    """A pipeline folder whose last stage finished: it holds its ``summary.json``."""
    return (Path(path) / MARKER).exists() and (Path(path) / "summary.json").exists()


def _remove_ours(path: Path) -> None:
    """Remove a folder fabmd made (marked); refuse anything else."""
    if not path.exists():
        return
    if not path.is_dir() or not (path / MARKER).exists():
        raise OutputExists(f"{path} is in the way and is not a fabmd folder (no {MARKER}); "
                           f"move it away")
    shutil.rmtree(path)


def _check_replaceable(path: Path, overwrite: bool) -> None:
    """Raise :class:`OutputExists` unless ``overwrite`` and ``path`` is a fabmd folder."""
    if not overwrite:
        raise OutputExists(f"results folder {path} exists already; choose another --out "
                           f"or pass --overwrite (overwrite=True) to replace it")
    if not path.is_dir() or not (path / MARKER).exists():
        raise OutputExists(f"{path} exists and is not a fabmd results folder (no {MARKER}); "
                           f"fabmd will not delete it even with --overwrite")


def _begin_on_root(path: Path, overwrite: bool, prefix: str) -> Path:
    if not path.exists() or (path.is_dir() and _only_marker(path)):
        return _prepare_on_root(path, False, prefix)
    _check_replaceable(path, overwrite)
    work = sibling(path, PARTIAL)
    _remove_ours(work)  # a stale attempt of an earlier replacement
    work.mkdir(parents=True)
    return work


def begin_run(path: Path, overwrite: bool = False, prefix: str = "run") -> Path:
    """The folder a run that may replace ``path`` writes into (marked).

    ``path`` itself when nothing is there; ``<path>.partial`` when ``path`` holds a
    fabmd folder and ``overwrite`` is True (the old folder stays until
    :func:`finish_run`).

    Raises:
        OutputExists: ``path`` exists and ``overwrite`` is False, or it is not a
            fabmd folder.
    """
    return _marked_on_root(lambda: _begin_on_root(Path(path).resolve(), overwrite, prefix))


def _marked_on_root(make) -> Path:
    """Run ``make()`` (returns a folder) on rank 0, mark the folder as fabmd's, and give
    every rank its path, or raise rank 0's :class:`OutputExists` on every rank."""
    message = ""
    if mpi.is_root():
        try:
            folder = make()
            (folder / MARKER).write_text("fabmd run folder\n")
            message = "OK:" + str(folder)
        except OutputExists as exc:
            message = "ERR:" + str(exc)
    message = mpi.bcast_text(message)
    if message.startswith("ERR:"):
        raise OutputExists(message[4:])
    return Path(message[3:])


def _retarget(obj, old: str, new: str):
    """``obj`` (JSON-like) with the path prefix ``old`` of every string made ``new``."""
    if isinstance(obj, str):
        return new + obj[len(old):] if obj.startswith(old) else obj
    if isinstance(obj, dict):
        return {k: _retarget(v, old, new) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return type(obj)(_retarget(v, old, new) for v in obj)
    return obj


def finish_run(path: Path, work: Path, summary=None):
    """Put a successful run in ``work`` in place at ``path`` (no-op when they are one).

    The old folder is removed only after the new one is complete; paths inside the
    run's JSON files (and in ``summary``, returned) are made to point at ``path``.
    """
    path, work = Path(path).resolve(), Path(work).resolve()
    if work == path:
        return summary
    if mpi.is_root():
        for f in work.rglob("*.json"):
            text = f.read_text()
            if str(work) in text:
                f.write_text(text.replace(str(work), str(path)))
        old = sibling(path, ".old")
        _remove_ours(old)
        path.rename(old)
        work.rename(path)
        shutil.rmtree(old)
    mpi.barrier()
    return _retarget(summary, str(work), str(path))


def abandon_run(path: Path, work: Path, error: BaseException) -> Path:
    """Record a failed run: ``failure.json`` in its folder; the attempt of a replacement
    moves to ``<path>.failed`` (replacing an older one) and ``path`` stays as it was.
    Returns the folder that holds the failure record."""
    path, work = Path(path).resolve(), Path(work).resolve()
    where = work
    if mpi.is_root() and work.exists():
        if work != path:
            where = sibling(path, FAILED)
            _remove_ours(where)
            work.rename(where)
        record = {"error": str(error), "kind": type(error).__name__,
                  "exit_code": getattr(error, "exit_code", 1),
                  "kept": str(path) if where != path else None}
        write_json(where / "failure.json", record)
    mpi.barrier()
    return sibling(path, FAILED) if work != path else path
