"""``fabmd export DIR``: voxel mesh (VTU, Abaqus .inp) and yarn surfaces of a state."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import emit


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("folder", type=Path, help="a run folder holding a fabric state (crimp, "
                                            "coupon, test or build)")
    size = p.add_mutually_exclusive_group()
    size.add_argument("--voxel", type=int, default=None, metavar="N",
                      help="voxels along the domain's longest edge")
    size.add_argument("--voxel-size", default=None, metavar="SIZE",
                      help="voxel edge, e.g. '50 um' or 5e-5 (default: the smallest fibre "
                           "diameter / 4)")
    p.add_argument("--stations", type=int, default=None,
                   help="stations along each yarn (default: beads of its longest fibre)")
    p.add_argument("--samples", type=int, default=None,
                   help="sub-voxel samples per axis for the fibre volume fraction (default: "
                        "the voxel centre, or 2 where the centres miss the beads' fraction "
                        "by more than 2 %%; 2 costs 9x)")
    p.add_argument("--png", nargs="?", type=Path, const=True, default=None, metavar="PATH",
                   help="also draw the voxels by yarn and the fibre-direction field "
                        "(default OUT/voxels.png)")
    p.add_argument("--out", type=Path, default=None, help="output folder (default DIR/export)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output folder")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def run(args) -> int:
    from ..errors import OutputExists
    from ..export import export_state, load_state
    from ..units import quantity

    size = None if args.voxel_size is None else \
        quantity(args.voxel_size, "length", "--voxel-size")
    out = args.out or args.folder / "export"
    if out.exists() and any(out.iterdir()) and not args.overwrite:
        raise OutputExists(f"{out} exists; pass --overwrite to replace it")
    model, state = load_state(args.folder)
    s = export_state(model, out, voxels=args.voxel, voxel_size_m=size, stations=args.stations,
                     samples=args.samples, keep_mesh=args.png is not None)
    s["state"] = state
    if args.png is not None:
        from ..export.plot import voxel_figure

        png = out / "voxels.png" if args.png is True else args.png
        voxel_figure(s.pop("mesh"), png, title=f"{args.folder.name}: {state}")
        s["picture"] = str(png)
    s.pop("mesh", None)
    vf, d, pen = s["fibre_volume_fraction"], s["direction_error"], s["interpenetration"]
    text = (f"{args.folder / state}: {len(s['yarns'])} yarns -> "
            f"{'x'.join(map(str, s['voxels']))} voxels of "
            f"{1e6 * min(s['voxel_size_m']):.0f}-{1e6 * max(s['voxel_size_m']):.0f} um\n"
            f"  fibre volume fraction: voxels {vf['voxels']:.4f}, beads {vf['beads']:.4f} "
            f"({100 * vf['relative_error']:+.2f} %"
            + (f"; {s['samples_per_axis']}^3 samples per voxel, the centres alone were "
               f"{100 * vf['centre_sampling_error']:+.2f} %"
               if vf.get("centre_sampling_error") is not None else "") + ")\n"
            f"  fibre direction vs bead tangents: mean {d['mean_deg']:.2f} deg, "
            f"95 % {d['p95_deg']:.2f} deg ({100 * d['beads_in_matrix']:.1f} % of beads in "
            f"matrix voxels)\n"
            f"  yarn interpenetration: {100 * pen['fraction_of_yarn_volume']:.2f} % of the "
            f"yarn volume; surfaces watertight: {s['all_surfaces_watertight']}\n"
            f"  written {out}/: voxels.vtu, voxels.inp, voxels_elements.csv, surfaces/, "
            f"export.json" + (f", {s['picture']}" if "picture" in s else ""))
    emit(s, args.json, text)
    return 0
