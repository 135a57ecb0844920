"""Export benchmark: convergence of the voxel mesh with voxel size.

For each fabric state (a run folder: a crimp run's ``crimped.data``, or a build's
``model.data``; by default the crimped periodic cell of ``examples/plain_weave.toml``,
crimped here first) the yarns are reconstructed once, then voxelised at voxel edges of
d/k for each k of ``--per-diameter`` (d = the smallest fibre diameter; k = 4 is the
default of ``fabmd export``). Prints, per row: voxels, voxel edge, the cell's fibre volume
fraction from the voxels and from the beads and their relative error, the angle between
voxel fibre directions and bead tangents (mean, 95th percentile), the share of beads
whose voxel is matrix, the yarn interpenetration (share of the yarn volume) and the
voxelising time (measured in this process).

    python benchmarks/export.py [--state LABEL=DIR[@k,k,...] ...] [--per-diameter 2 3 4 6 8]
                                [--samples 1] [--write] [--section Export]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from _results import table, update_section  # noqa: E402

from fabmd.export import (  # noqa: E402
    bead_fibre_volume_fraction,
    direction_errors,
    interpenetration_report,
    load_state,
    reconstruct_yarns,
    voxel_grid,
    voxelise,
)

SCENE = Path(__file__).resolve().parents[1] / "examples" / "plain_weave.toml"


def crimped_example(root: Path) -> Path:
    """Crimp the example's periodic cell (as ``fabmd crimp ... --form cell``)."""
    from fabmd.engine import Engine
    from fabmd.pipeline import run_crimp
    from fabmd.scenefile import load_scene

    run_crimp(load_scene(SCENE), root / "crimp", engine=Engine(progress=False), form="cell")
    return root / "crimp"


def rows_for(label: str, folder: Path, per_diameter: list[float], samples: int) -> list[list]:
    model, state = load_state(folder)
    t0 = time.perf_counter()
    yarns = reconstruct_yarns(model)
    reconstruct_s = time.perf_counter() - t0
    d = float(model.diameters.min())
    rows = []
    for k in per_diameter:
        grid = voxel_grid(model, voxel_size_m=d / k)
        t0 = time.perf_counter()
        mesh = voxelise(yarns, grid, samples=samples)
        wall = time.perf_counter() - t0
        vf, beads = mesh.cell_fibre_volume_fraction(), bead_fibre_volume_fraction(model, grid)
        err = direction_errors(model, mesh)
        pen = interpenetration_report(mesh, yarns)
        rows.append([f"{label} ({state}, {model.n_beads} beads, {len(yarns)} yarns)",
                     f"d/{k:g}", "x".join(map(str, grid.counts)),
                     f"{1e6 * grid.size_m.max():.0f}", f"{vf:.4f}", f"{beads:.4f}",
                     f"{100 * (vf / beads - 1):+.2f} %", f"{err['mean_deg']:.2f}",
                     f"{err['p95_deg']:.2f}", f"{100 * err['beads_in_matrix']:.2f} %",
                     f"{100 * pen['fraction_of_yarn_volume']:.2f} %",
                     f"{wall:.1f} (+{reconstruct_s:.1f})"])
        print(" | ".join(str(v) for v in rows[-1]), flush=True)
    return rows


HEADER = ["state", "voxel edge", "voxels", "edge [µm]", "Vf voxels", "Vf beads",
          "Vf error", "direction error mean [°]", "95 % [°]", "beads in matrix",
          "interpenetration", "voxelise (+ reconstruct) [s]"]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--state", action="append", default=[], metavar="LABEL=DIR",
                   help="a run folder holding a state (default: crimp the example cell); "
                        "@k,k,... sets its own voxel edges d/k")
    p.add_argument("--per-diameter", type=float, nargs="+", default=[2, 3, 4, 6, 8])
    p.add_argument("--samples", type=int, default=1, help="sub-voxel samples per axis")
    p.add_argument("--write", action="store_true", help="write the RESULTS.md section")
    p.add_argument("--section", default="Export")
    p.add_argument("--note", default="", help="a sentence put above the table")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        states = [s.split("=", 1) for s in args.state] or \
            [("plain-weave cell, crimped", str(crimped_example(Path(tmp))))]
        rows = []
        for label, folder in states:
            folder, _, ks = folder.partition("@")
            sizes = [float(k) for k in ks.split(",")] if ks else args.per_diameter
            rows += rows_for(label, Path(folder), sizes, args.samples)
    body = ((args.note + "\n\n") if args.note else "") + (
        f"Voxel edge d/k with d the smallest fibre (bead) diameter; `fabmd export` uses "
        f"d/4. Sub-voxel samples per axis: {args.samples}. Vf beads = filament volume "
        f"Σ A·(bond length) over the voxel domain. Direction error: angle between the "
        f"voxel's fibre direction and the bead's fibre tangent over the beads in a voxel "
        f"of their own yarn.\n\n" + table(HEADER, rows))
    print(body)
    if args.write:
        cmd = "python benchmarks/export.py --write" + "".join(
            f" --state '{s}'" for s in args.state)
        update_section(args.section, body, cmd)
    return 0


if __name__ == "__main__":
    sys.exit(main())
