"""Standalone back end: ``mpirun -np N lmp -in in.<protocol>`` in the run folder.

This is exactly what a user runs on a cluster after copying the folder; fabmd
writes ``run.sh`` with the command beside the input.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from .diagnosis import to_exception
from .library import engine_environment, lmp_executable, mpirun_executable


def command_line(input_name: str, ranks: int = 1, threads: int = 1,
                 lmp: str | Path | None = None, mpirun: str | Path | None = None) -> list[str]:
    """The command that runs ``input_name`` in its folder."""
    cmd = [str(mpirun or mpirun_executable()), "-np", str(ranks)] if ranks > 1 else []
    cmd += [str(lmp or lmp_executable()), "-in", input_name, "-log", "log.lammps", "-nocite"]
    if threads > 1:
        cmd += ["-sf", "omp", "-pk", "omp", str(threads)]
    return cmd


def run_standalone(run_dir: Path, input_name: str, *, ranks: int = 1, threads: int = 1) -> None:
    """Run the input with the ``lmp`` executable of this install.

    Screen output goes to ``run_dir/screen.log``.

    Raises:
        SimulationFailed / UnstableRun: ``lmp`` exited with an error.
    """
    run_dir = Path(run_dir)
    env = engine_environment()
    env["OMP_NUM_THREADS"] = str(threads)
    screen = run_dir / "screen.log"
    with open(screen, "w") as out:
        proc = subprocess.run(command_line(input_name, ranks, threads), cwd=run_dir, env=env,
                              stdout=out, stderr=subprocess.STDOUT, check=False)
    text = screen.read_text(errors="replace")
    if proc.returncode != 0 or "ERROR" in text:
        raise to_exception(text, run_dir)
