"""``fabmd test NAME SCENE.toml --out DIR``: a virtual test of a fabric, end to end."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_preset_options, add_run_options, emit, engine_from, scene_from


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..pipeline import TESTS

    p.add_argument("name", choices=sorted(TESTS), help="which test")
    p.add_argument("scene", type=Path, help="scene file (TOML)")
    p.add_argument("--crimped", type=Path, default=None,
                   help="start from this finished crimp folder (skips the crimp stage)")
    p.add_argument("--check-rate", action="store_true",
                   help="rerun the test at half speed and report the change of the curve")
    p.add_argument("--checkpoint-every", type=int, default=0, metavar="STEPS",
                   help="write a checkpoint every STEPS steps (in-process back end)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run in --out from its last checkpoint")
    p.add_argument("--redo", action="store_true",
                   help="with --resume on a finished run: run its test again on its crimp "
                        "and coupon (the old test is replaced only if the new one succeeds)")
    p.add_argument("--strict", action="store_true",
                   help="a curve that is not quasi-static is a failure (exit status 4)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_preset_options(p)
    add_run_options(p, out_required=True)


def run(args) -> int:
    import dataclasses

    from ..pipeline import run_test
    scene = scene_from(args)
    engine = dataclasses.replace(engine_from(args), checkpoint_every=args.checkpoint_every)
    summary = run_test(scene, args.name, args.out, engine=engine, overwrite=args.overwrite,
                       check_rate=args.check_rate, resume=args.resume, crimped=args.crimped,
                       strict=args.strict, redo=args.redo)
    s = summary["test_summary"]
    lines = [f"{args.name} of {scene.source}: {summary['coupon_beads']} beads"]
    for key in sorted(s):
        value = s[key]
        if isinstance(value, int | float | str) and not key.endswith("_note"):
            lines.append(f"  {key:40s} {value}")
    lines.append(f"  results in {summary['results']}")
    emit(summary, args.json, "\n".join(lines))
    return 0
