"""``fabmd info``: what LAMMPS this install loads and whether it has what fabmd needs."""

from __future__ import annotations

import argparse


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print as JSON")


def run(args) -> int:
    import fabmd

    from ..engine import library
    from .common import emit

    lmp = library.new_instance()
    try:
        missing = library.missing_capabilities(lmp)
        info = {"fabmd": fabmd.__version__, "lammps_version": lmp.version(),
                "lammps_packages": lmp.installed_packages, "missing": missing,
                "mpi_library": str(library.mpi_library_path()),
                "lmp": str(library.lmp_executable())}
    finally:
        lmp.close()
    text = (f"fabmd {info['fabmd']}, LAMMPS {info['lammps_version']}\n"
            f"lmp: {info['lmp']}\nMPI library: {info['mpi_library']}\n"
            f"missing: {', '.join(missing) if missing else 'nothing'}")
    emit(info, args.json, text)
    return 1 if missing else 0
