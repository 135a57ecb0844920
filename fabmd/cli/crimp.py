"""``fabmd crimp SCENE.toml --out DIR``: the as-woven state of a fabric."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_preset_options, add_run_options, emit, engine_from, scene_from


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", type=Path, help="scene file (TOML) with [fabric], [yarns.*], "
                                           "and optionally [crimp]")
    p.add_argument("--form", choices=["fabric", "cell"], default="fabric",
                   help="crimp the fabric as described (default) or its periodic unit cell")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_preset_options(p)
    add_run_options(p, out_required=True)


def run(args) -> int:
    from ..pipeline import run_crimp
    from ..results.yarn_tension import tension_line
    scene = scene_from(args)
    result = run_crimp(scene, args.out, engine=engine_from(args), overwrite=args.overwrite,
                       form=args.form)
    s = result.summary
    lo, cr = s["loose"], s["crimped"]
    crimps = ", ".join(f"{f} {lo['crimp_pct'][f]:.2f} -> {cr['crimp_pct'][f]:.2f} %"
                       for f in cr["crimp_pct"])
    text = (f"crimped {scene.source}: {cr['n_beads']} beads, {s['steps']} steps, "
            f"{s['wall_s']:.1f} s; quasi-static: {s['quasi_static']}\n"
            f"  thickness {1e3 * lo['thickness_m']:.3f} -> {1e3 * cr['thickness_m']:.3f} mm\n"
            f"  crimp {crimps}\n"
            f"  fibre volume fraction {cr['fibre_volume_fraction']}\n"
            f"  {tension_line(s.get('yarn_tension') or {})}\n"
            f"  results in {result.run_dir}")
    emit(s, args.json, text)
    return 0
