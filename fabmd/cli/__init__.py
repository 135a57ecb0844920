"""The ``fabmd`` command.

Subcommands live in small modules of this package and are imported only when
chosen, so ``fabmd --help`` starts fast. Errors print as one line
(``fabmd: error: ...``); ``--traceback`` shows the whole traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

#: subcommand -> (module in fabmd.cli, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("demo", "run the main job: a small default scene end to end"),
    "validate": ("validate", "physics checks against closed form (fibre-tension, ...)"),
    "info": ("info", "LAMMPS version, packages and what fabmd needs of them"),
    "crimp": ("crimp", "the as-woven state of a fabric: crimp its loose form (scene file)"),
    "calibrate": ("calibrate", "the crimp expansion that gives the datasheet's thickness, "
                               "crimp, tension (scene file -> calibrated scene file)"),
    "test": ("test_cmd", "a virtual test end to end: crimp, coupon, test (scene file)"),
    "measure": ("measure", "thickness, crimp, volume fraction of the state in a run folder"),
    "build": ("build", "render a fabric scene (TOML) into beads: data file, VTU, preview"),
    "export": ("export", "voxel mesh (VTU, Abaqus .inp) and yarn surfaces of a fabric state"),
}


def _chosen(argv: list[str]) -> str | None:
    for word in argv:
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(argv: list[str]) -> argparse.ArgumentParser:
    from ..errors import EXIT_CODES

    parser = argparse.ArgumentParser(
        prog="fabmd",
        description="fabmd — virtual testing lab for dry textile reinforcements "
                    "(virtual fibres in LAMMPS). SI units unless stated.",
        epilog="exit status: " + "; ".join(f"{k} {v}" for k, v in EXIT_CODES.items()))
    parser.add_argument("--traceback", action="store_true",
                        help="show the full traceback on errors")
    parser.add_argument("--version", action="version", version=f"fabmd {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    chosen = _chosen(argv)
    for name, (module, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        if name == chosen:
            importlib.import_module(f"fabmd.cli.{module}").add_arguments(p)
    return parser


def version() -> str:
    """The installed package's version (its metadata)."""
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as metadata_version

    try:
        return metadata_version("fabmd")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "unknown (not installed)"


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``fabmd`` command; returns the exit status."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    module = importlib.import_module(f"fabmd.cli.{COMMANDS[args.command][0]}")
    from ..errors import FabmdError
    from .terminal import install_warning_format

    install_warning_format()  # warnings as one "fabmd: warning: ..." line each

    try:
        from .ranks import relaunch_if_worth_it

        relaunched = relaunch_if_worth_it(args, argv)  # on every core: under mpirun
        if relaunched is not None:
            return relaunched
        return int(module.run(args) or 0)
    except FabmdError as exc:
        if args.traceback:
            raise
        if _is_root():  # under mpirun every rank raises it: say it once
            print(f"fabmd: error: {exc}", file=sys.stderr)
        return getattr(exc, "exit_code", 2)  # RunInterrupted: 5
    except KeyboardInterrupt:
        print("fabmd: interrupted", file=sys.stderr)
        return 130


def _is_root() -> bool:
    """Rank 0 (or no MPI); True where MPI itself is what failed."""
    from ..engine import mpi

    try:
        return mpi.is_root()
    except Exception:  # noqa: BLE001 - the error to print may be MPI's own
        return True


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
