"""``fabmd measure DIR``: measure the fabric state a run folder holds."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import emit

#: state files, most advanced first
STATES = (("final.data", "model.json"), ("released.data", "released.json"),
          ("crimped.data", "crimped.json"),
          ("coupon.data", "coupon.json"), ("model.data", "model.json"))


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("folder", type=Path, help="a run folder (crimp, coupon, test or build)")
    p.add_argument("--edge-m", type=float, default=0.0,
                   help="measure only beads this far inside the fabric's edges [m]")
    p.add_argument("--overwrite", action="store_true", help="replace measures.json")
    p.add_argument("--json", action="store_true", help="print the measures as JSON")
    p.add_argument("--cut-at", action="append", default=[], metavar="POSITION",
                   help="also write a cut image (cut_<normal>_<mm>mm.png + .csv of its beads) "
                        "at this coordinate of the model, e.g. 5mm (repeatable); the cut holds "
                        "the beads within ±d/2 of the plane")
    p.add_argument("--cut-normal", choices=["x", "y"], default="x",
                   help="normal of the --cut-at planes: x (warp direction; the cut shows the "
                        "weft paths, default) or y")


def run(args) -> int:
    from ..errors import InputError, OutputExists
    from ..model.bead_model import BeadModel
    from ..results.folder import write_json
    from ..results.measure import fabric_measures
    from ..results.preview import preview_png

    folder = args.folder
    for data, meta in STATES:
        if (folder / data).exists() and (folder / meta).exists():
            break
    else:
        raise InputError(f"{folder} holds no fabric state (looked for "
                         f"{', '.join(d for d, _ in STATES)} with their .json)")
    out = folder / "measures.json"
    if out.exists() and not args.overwrite:
        raise OutputExists(f"{out} exists; pass --overwrite to replace it")
    model = BeadModel.load(folder / data, folder / meta)
    cut_files = _check_cuts(model, folder, args)  # bad positions fail before anything is written
    measures = fabric_measures(model, edge_m=args.edge_m)
    measures["state"] = data
    measures["cuts"] = [p.name for p, _ in cut_files]
    write_json(out, measures)
    preview_png(model, folder / "measures.png", title=f"{folder.name}: {data}")
    if cut_files:  # one image per position (+ a grid overview cuts.png of several)
        from ..results.cuts import cut_png, cut_pngs

        if len(cut_files) == 1:
            path, pos = cut_files[0]
            cut_png(model, path, args.cut_normal, pos, title=f"{folder.name}: {data}")
        else:
            cut_pngs(model, folder, [(args.cut_normal, pos) for _, pos in cut_files],
                     title=f"{folder.name}: {data}")
    crimps = crimp_text(measures)
    text = (f"{folder / data}: {model.n_beads} beads\n"
            f"  thickness {1e3 * measures['thickness_m']:.3f} mm ({measures['measured_over']})\n"
            f"  crimp per fibre {crimps}\n"
            f"  fibre volume fraction {measures['fibre_volume_fraction']:.3f}\n"
            f"  written {out} and {folder / 'measures.png'}"
            + "".join(f"\n  cut {p} (+ .csv)" for p, _ in cut_files))
    emit(measures, args.json, text)
    return 0


def _check_cuts(model, folder: Path, args) -> list[tuple[Path, float]]:
    """``(image path, position [m])`` of every ``--cut-at``; raises InputError for a position
    that is not a length or lies outside the fabric."""
    if not args.cut_at:
        return []
    from ..analysis import FabricFrame, fabric_cut
    from ..errors import InputError
    from ..results.cuts import cut_label
    from ..units import quantity

    frame = FabricFrame.from_model(model)
    out = []
    for text in args.cut_at:
        pos = quantity(text, "length", "--cut-at")
        try:
            fabric_cut(frame, args.cut_normal, pos)
        except InputError as exc:
            hint = "" if any(c.isalpha() for c in str(text)) else \
                " (a bare number is in metres: write e.g. 5mm)"
            raise InputError(f"--cut-at {text}: {exc}{hint}") from None
        out.append((folder / f"cut_{cut_label(args.cut_normal, pos)}.png", pos))
    return out


def crimp_text(measures: dict, before: list[str] | None = None) -> str:
    """Per-fibre crimp of each family (``before[i]`` written ahead of family i's value),
    then the yarn-centreline crimp where the measures have it."""
    before = before or [""] * len(measures["crimp_pct"])
    text = ", ".join(f"{f} {b}{c:.2f} %"
                     for b, (f, c) in zip(before, measures["crimp_pct"].items(), strict=True))
    centre = measures.get("centreline_crimp_pct") or {}
    if centre:
        text += " (yarn centreline: " + ", ".join(f"{f} {c:.2f} %"
                                                  for f, c in centre.items()) + ")"
    return text
