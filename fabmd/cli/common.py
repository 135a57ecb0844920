"""Options shared by the subcommands that run LAMMPS."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def add_run_options(p: argparse.ArgumentParser, out_required: bool = False) -> None:
    p.add_argument("--out", type=Path, required=out_required,
                   help="results folder (must not exist unless --overwrite)"
                   + ("" if out_required else "; default: a temporary folder"))
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing fabmd results folder")
    p.add_argument("--backend", choices=["inprocess", "standalone"], default="inprocess",
                   help="run LAMMPS in this process (default) or as 'mpirun lmp -in' "
                        "in the run folder")
    p.add_argument("--np", type=int, default=None, dest="ranks", metavar="N",
                   help="MPI ranks (default: every usable core for a large model, one for "
                        "a small one; env FABMD_NP); --np 1 runs serially")
    p.add_argument("--threads", type=int, default=1, help="OpenMP threads per rank")
    p.add_argument("--quiet", action="store_true", help="no progress line")


def engine_from(args):
    from ..engine import Engine

    return Engine(backend=args.backend, ranks=args.ranks, threads=args.threads,
                  progress=not args.quiet)


def emit(obj: dict, as_json: bool, text: str) -> None:
    """Print ``obj`` as JSON or ``text`` (rank 0 only)."""
    from ..engine import mpi

    if not mpi.is_root():
        return
    if as_json:
        json.dump(obj, sys.stdout, indent=2, default=str)
        sys.stdout.write("\n")
    else:
        print(text)


def add_preset_options(p: argparse.ArgumentParser) -> None:
    """``--fast`` / ``--accurate``: the presets of :mod:`fabmd.presets`."""
    group = p.add_mutually_exclusive_group()
    group.add_argument("--fast", dest="preset", action="store_const", const="fast",
                       help="one virtual fibre per yarn, bead spacing 0.25 d "
                            "(see README: expected error)")
    group.add_argument("--accurate", dest="preset", action="store_const", const="accurate",
                       help="19 virtual fibres per yarn (about 8x the run time)")
    p.set_defaults(preset="default")


def scene_from(args):
    """The scene file of ``args.scene`` with the chosen preset applied."""
    from ..presets import apply_preset
    from ..scenefile import load_scene

    return apply_preset(load_scene(args.scene), args.preset)


def add_stage_options(p: argparse.ArgumentParser) -> None:
    """Options of the commands that run a scene's stages (``crimp``, ``test``): ``--json``,
    the presets and the run options (``--out`` required)."""
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_preset_options(p)
    add_run_options(p, out_required=True)


def stage_inputs(args):
    """The scene (preset applied) and the engine of a stage command."""
    return scene_from(args), engine_from(args)
