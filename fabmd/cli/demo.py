"""``fabmd demo``: the main job, a small default scene end to end."""

from __future__ import annotations

import argparse

from .common import add_run_options, engine_from


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_run_options(p)


def run(args) -> int:
    from ..engine import mpi
    from ..verification import fibre_tension

    result = fibre_tension.check(out=args.out, engine=engine_from(args),
                                 overwrite=args.overwrite)
    if mpi.is_root():
        print("fabmd demo: single virtual fibre in tension (E-glass, 0.1 mm, 10 mm)")
        print(f"  force at 1 % strain: {result['measured_force_n']:.5g} N "
              f"(E·A·ε = {result['expected_force_n']:.5g} N, "
              f"rel. error {result['rel_error']:.1e})")
        print(f"  {result['n_beads']} beads, {result['steps']} steps, "
              f"{result['wall_s']:.1f} s; results in {result['run_dir']}")
    return 0 if result["passed"] else 1
