"""``fabmd test NAME SCENE.toml --out DIR``: a virtual test of a fabric, end to end."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_stage_options, emit, stage_inputs


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
    add_stage_options(p)


def run(args) -> int:
    import dataclasses

    from ..pipeline import run_test
    scene, engine = stage_inputs(args)
    engine = dataclasses.replace(engine, checkpoint_every=args.checkpoint_every)
    summary = run_test(scene, args.name, args.out, engine=engine, overwrite=args.overwrite,
                       check_rate=args.check_rate, resume=args.resume, crimped=args.crimped,
                       strict=args.strict, redo=args.redo)
    emit(summary, args.json, summary_text(args.name, scene.source, summary))
    return 0


def summary_text(name: str, source: str, summary: dict) -> str:
    """The terminal summary of a pipeline run: bead count of the model that ran, per-stage
    verdicts (crimp stop, quasi-static, energy balance), then every scalar with its unit."""
    from .build import law_line
    from .report import energy_line, quasi_static_line, value_text

    s = summary["test_summary"]
    beads = s.get("n_beads", summary["coupon_beads"])
    whole = "" if beads == summary["coupon_beads"] else \
        f" (specimen {summary['coupon_beads']:,} beads; the model runs part of it)"
    lines = [f"{name} of {source}: {beads:,} beads{whole}"]
    for stage in ("crimp", "coupon"):
        if summary.get(f"{stage}_stop"):
            lines.append(f"  {stage}: {summary[f'{stage}_stop']}")
    if law := law_line(summary).strip("\n"):  # the law of the fabric that was crimped
        lines.append(law)
    stage = [text for text in (quasi_static_line(s.get("quasi_static")),
                               energy_line(s.get("energy_balance"))) if text]
    lines += [f"  {name}: {text}" for text in stage]
    for key in sorted(s):
        value = s[key]
        if isinstance(value, int | float | str) and not key.endswith("_note"):
            lines.append(f"  {key:40s} {value_text(key, value)}")
    lines.append(f"  results in {summary['results']}")
    return "\n".join(lines)
