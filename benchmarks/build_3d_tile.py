"""Benchmark: build a 6 x 6 unit-cell tile of the 3D angle-interlock example.

19 virtual fibres per yarn (override with --fibres), non-periodic unless
--periodic. Prints the bead count, the time to render (geometry, beads, overlap
check) and to write the data file, and the peak memory (tracemalloc peak of
Python allocations and the process's maximum resident set size). Target: < 60 s.

    python benchmarks/build_3d_tile.py [--tiles 6] [--fibres 19] [--periodic] [--keep DIR]
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import shutil
import tempfile
import time
import tracemalloc
from pathlib import Path

from fabmd.model.fabric_model import render_fabric
from fabmd.scenefile import load_scene

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "angle_interlock_3d.toml"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tiles", type=int, default=6)
    p.add_argument("--fibres", type=int, default=19)
    p.add_argument("--periodic", action="store_true")
    p.add_argument("--keep", type=Path, help="write the data file here (default: a temp dir)")
    args = p.parse_args()

    scene = load_scene(EXAMPLE)
    f = scene.fabric
    f = dataclasses.replace(
        f, tiling=(args.tiles, args.tiles), periodic=args.periodic,
        warp=dataclasses.replace(f.warp, n_fibres=args.fibres),
        weft=dataclasses.replace(f.weft, n_fibres=args.fibres),
        binder=dataclasses.replace(f.binder, n_fibres=args.fibres))
    tracemalloc.start()
    t0 = time.perf_counter()
    model = render_fabric(f, scene.discretisation)
    t_render = time.perf_counter() - t0
    folder = args.keep or Path(tempfile.mkdtemp(prefix="fabmd-bench-"))
    t1 = time.perf_counter()
    data, _ = model.save(folder)
    t_write = time.perf_counter() - t1
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    size = data.stat().st_size
    if args.keep is None:
        shutil.rmtree(folder)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB -> MiB (Linux)
    total = t_render + t_write
    print(f"3D angle interlock, {args.tiles} x {args.tiles} unit cells, {args.fibres} fibres "
          f"per yarn{', periodic' if args.periodic else ''}")
    print(f"  beads {model.n_beads:,}  bonds {model.n_bonds:,}  fibres {model.n_fibres:,}  "
          f"yarns {len(model.yarns)}")
    print(f"  render {t_render:.1f} s (overlap check included; smallest gap "
          f"{model.info['clearance_m'] * 1e3:.3g} mm)  write {t_write:.1f} s "
          f"({size / 2**20:.0f} MiB)  total {total:.1f} s  [target < 60 s: "
          f"{'met' if total < 60 else 'MISSED'}]")
    print(f"  peak memory: tracemalloc {peak / 2**20:.0f} MiB, max RSS {rss:.0f} MiB")


if __name__ == "__main__":
    main()
