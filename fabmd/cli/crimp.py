"""``fabmd crimp SCENE.toml --out DIR``: the as-woven state of a fabric."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import add_stage_options, emit, stage_inputs


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", type=Path, help="scene file (TOML) with [fabric], [yarns.*], "
                                           "and optionally [crimp]")
    p.add_argument("--form", choices=["fabric", "cell"], default="fabric",
                   help="crimp the fabric as described (default) or its periodic unit cell")
    add_stage_options(p)


def run(args) -> int:
    from ..pipeline import run_crimp
    from ..results.yarn_tension import tension_line
    scene, engine = stage_inputs(args)
    result = run_crimp(scene, args.out, engine=engine, overwrite=args.overwrite, form=args.form)
    s = result.summary
    lo, cr = s["loose"], s["crimped"]
    from .measure import crimp_text

    crimps = crimp_text(cr, [f"{lo['crimp_pct'][f]:.2f} -> " for f in cr["crimp_pct"]])
    text = (f"crimped {scene.source}: {cr['n_beads']:,} beads, {s['wall_s']:.3g} s wall\n"
            f"  {s.get('stop', s['steps'])}\n"
            f"  thickness {1e3 * lo['thickness_m']:.3f} -> {1e3 * cr['thickness_m']:.3f} mm\n"
            f"  crimp per fibre {crimps}\n"
            f"{_targets_text(s)}"
            f"  fibre volume fraction {cr['fibre_volume_fraction']:.3f}\n"
            f"  {_datasheet_line(s)}\n"
            f"  {tension_line(s.get('yarn_tension') or {})}\n"
            f"{_released_text(s)}"
            f"  results in {result.run_dir}")
    emit(s, args.json, text)
    return 0


def _released_text(s: dict) -> str:
    """What the release of the weaving tension did (``[crimp] release_tension``): '' without."""
    r = s.get("released")
    if not r:
        return ""
    woven, rel = s["woven"], s["crimped"]
    tension = ", ".join(f"{f} {v['yarn_n']:.3g} N" for f, v in
                        (r.get("yarn_tension_released") or {}).items())
    return (f"  released (the measures above; [crimp] release_tension): cell "
            f"{r['strain_pct'][0]:+.2f} / {r['strain_pct'][1]:+.2f} % (x / y), thickness "
            f"{1e3 * woven['thickness_m']:.3f} -> {1e3 * rel['thickness_m']:.3f} mm, crimp "
            + ", ".join(f"{f} {woven['crimp_pct'][f]:.2f} -> {rel['crimp_pct'][f]:.2f} %"
                        for f in rel["crimp_pct"])
            + f"; yarn tension left {tension}; {r['stop']}\n")


def _datasheet_line(s: dict) -> str:
    """Areal density (against the datasheet), yarn packing and the pass-through check."""
    ds = s.get("datasheet") or {}
    text = f"areal density {1e3 * s['areal_density_kg_m2']:.4g} g/m²"
    if ds.get("areal_density_kg_m2"):
        text += (f" (datasheet {1e3 * ds['areal_density_kg_m2']:.4g} g/m², "
                 f"{100 * (s['areal_density_kg_m2'] / ds['areal_density_kg_m2'] - 1):+.1f} %)")
    sections = s["crimped"].get("yarn_sections", {})
    text += "; yarn Vf " + ", ".join(
        f"{f} {v['fibre_volume_fraction']:.2f}" for f, v in sections.items()
        if v.get("fibre_volume_fraction") is not None)
    text += f"; yarns passed through: {s['pass_through']['flipped_pairs']} flipped pairs"
    return text


def _targets_text(s: dict) -> str:
    """One line per family whose expansion came from ``[crimp] target_crimp_pct`` (''),
    or whose loose height was searched for it (``crimp_by = "loose_height"``)."""
    pin = s.get("pinned_crimp")
    if pin:
        return "".join(
            f"  {f}: loose section {1e3 * h:.4g} mm high for the target crimp "
            f"{pin['target_crimp_pct'][f]:.2f} % at the weaving tension "
            f"({pin['runs']} crimp run{'' if pin['runs'] == 1 else 's'}: loose_height/)\n"
            for f, h in pin["loose_height_m"].items())
    return "".join(
        f"  {f}: expansion {t['expansion']:+.4f} from its loose rest crimp "
        f"{t['loose_rest_crimp_pct']:.2f} % to the target {t['target_crimp_pct']:.2f} %"
        f"{' (auto)' if t['auto'] else ''}\n"
        for f, t in (s.get("crimp_targets") or {}).items())
