"""Running the cases of a closed-form check (capstan, sliding) and judging the worst."""

from __future__ import annotations

from pathlib import Path

from ..engine import Engine, mpi
from ..results.folder import prepare_run_folder


def run_cases(prefix: str, named: list[tuple[str, object]], case_keys: tuple[str, ...],
              head: dict, tolerance: float, out: Path | None = None,
              engine: Engine | None = None, overwrite: bool = False) -> dict:
    """Run each ``(name, test)`` of ``named`` into ``<out>/<name>`` and judge them.

    Returns ``head`` followed by the tolerance, the largest relative error (each case's
    summary ``rel_error``), ``passed``, the summed wall time, the run folder and the
    cases (the summary keys ``case_keys`` of each); every rank gets rank 0's.
    """
    engine = engine or Engine()
    root = prepare_run_folder(out, overwrite=overwrite, prefix=prefix)
    cases, wall = [], 0.0
    for name, test in named:
        s = test.run(out=root / name, engine=engine).summary
        wall += s.get("wall_s", 0.0)
        cases.append({key: s[key] for key in case_keys})
    worst = max(c["rel_error"] for c in cases)
    return mpi.bcast_json({**head, "tolerance": tolerance, "max_rel_error": worst,
                           "passed": worst <= tolerance, "wall_s": wall, "run_dir": str(root),
                           "cases": cases})
