"""The yarns' sections in crimped periodic cells: how the crimped state depends on the
fibres per yarn.

Reads each crimp folder's ``crimped.data`` / ``crimped.json`` and prints the yarns' mean
width and height — at stations 0.25 mm apart along each yarn, the spread of its virtual
fibres' centres across the yarn in the fabric's plane (width) and through the thickness
(height), plus the bead diameter, unwrapped across the periodic cell — their ratio and the
fabric's span (outermost bead surfaces).

    python benchmarks/crimp_sections.py CRIMP [CRIMP ...]

CRIMP: a ``fabmd crimp`` folder or the ``crimp`` folder of a ``fabmd test`` run.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from fabmd.model.bead_model import BeadModel

STATION_M = 0.25e-3  # distance between stations along a yarn


def sections(model: BeadModel) -> dict:
    """Mean and extreme width and height [m] of the yarns' sections, and the span [m]."""
    x, d = model.positions, model.diameters
    size = model.box_hi - model.box_lo
    widths, heights = [], []
    yarn_ids = model.yarn_ids
    for y in np.unique(yarn_ids):
        on = yarn_ids == y
        along = 0 if model.yarns[y - 1].family == "warp" else 1  # weft and binders: y
        across = 1 - along
        c = x[on, across]
        c = c - size[across] * np.round((c - np.median(c)) / size[across])  # unwrap
        s, z, dd = x[on, along], x[on, 2], d[on]
        for station in np.arange(model.box_lo[along], model.box_hi[along], STATION_M):
            near = np.abs(s - station) < 0.5 * STATION_M
            if near.sum() < 1:
                continue
            widths.append(np.ptp(c[near]) + dd[near].mean())
            heights.append(np.ptp(z[near]) + dd[near].mean())
    w, h = np.array(widths), np.array(heights)
    return {"width_m": float(w.mean()), "min_width_m": float(w.min()),
            "height_m": float(h.mean()), "max_height_m": float(h.max()),
            "span_m": float((x[:, 2] + d / 2).max() - (x[:, 2] - d / 2).min()),
            "fibres_per_yarn": model.n_fibres // len(model.yarns),
            "fibre_diameter_m": float(d.mean())}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("crimps", nargs="+", type=Path)
    args = p.parse_args(argv)
    print("| crimp | fibres per yarn | d [mm] | width [mm] | height [mm] | width / height "
          "| span [mm] |")
    print("|---|---|---|---|---|---|---|")
    for folder in args.crimps:
        s = sections(BeadModel.load(folder / "crimped.data", folder / "crimped.json"))
        print(f"| {folder} | {s['fibres_per_yarn']} | {1e3 * s['fibre_diameter_m']:.3f} | "
              f"{1e3 * s['width_m']:.3f} | {1e3 * s['height_m']:.3f} | "
              f"{s['width_m'] / s['height_m']:.2f} | {1e3 * s['span_m']:.3f} |")


if __name__ == "__main__":
    main()
