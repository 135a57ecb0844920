"""Yarn centrelines of one unit cell of a :class:`~fabmd.geometry.fabric.Fabric` (SI):
the 2D weave's crossings and the 3D architecture's layers and gaps.

The fabric's own methods (``Fabric.levels``, ``Fabric.unit_cell_paths``) call these; they
read the fabric's yarn table and spacings and return plain paths and numbers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .paths import YarnPath

if TYPE_CHECKING:  # the fabric calls this module
    from .fabric import Fabric


def layered_levels(fabric: Fabric, c: float) -> dict[str, list[float]]:
    """3D: z of every weft layer and gap [m] and each gap's height [m]; neighbours are
    (their heights)/2 + ``c`` apart (clearance plus lift [m]), centred on z = 0."""
    a = fabric.architecture
    binder_gaps = a.binder_gaps()
    table = fabric.yarn_spec_table()
    binder_h = max(s.occupied_height_m for s in fabric._family_specs("binder"))
    heights = []
    for g in range(a.n_gaps):
        h = 0.0
        if g in a.warp_gaps:  # the tallest stuffer of the gap, over the dents
            h = max(h, max(table[fabric._spec_key("warp", d, g)].occupied_height_m
                           for d in range(1, a.dents + 1)))
        if g in binder_gaps:
            h = max(h, binder_h)
        heights.append(h)
    # each weft layer as high as its tallest weft
    hfs = [max(table[fabric._spec_key("weft", col, k)].occupied_height_m
               for col in range(1, a.columns + 1)) for k in range(1, a.weft_layers + 1)]
    gap_z = [0.0]
    weft_z = []
    for k in range(a.weft_layers):
        weft_z.append(gap_z[k] - 0.5 * (heights[k] + hfs[k]) - c)
        gap_z.append(weft_z[k] - 0.5 * (heights[k + 1] + hfs[k]) - c)
    mid = 0.5 * (gap_z[0] + gap_z[-1])
    return {"weft": [z - mid for z in weft_z], "gap": [z - mid for z in gap_z],
            "gap_height": heights}


def woven_cell(fabric: Fabric) -> tuple[list[YarnPath], list[str]]:
    """2D weave: warp then weft centrelines of the unit cell and their yarn spec keys."""
    lx, ly = fabric.unit_cell_m
    f = fabric.plateau
    table = fabric.yarn_spec_table()
    out: list[YarnPath] = []
    keys: list[str] = []
    m = fabric.architecture.array
    c = fabric.clearance_m + fabric.lift_m
    warp_keys = [fabric._spec_key("warp", i + 1, None) for i in range(m.shape[0])]
    weft_keys = [fabric._spec_key("weft", j + 1, None) for j in range(m.shape[1])]
    hw = np.array([table[k].occupied_height_m for k in warp_keys])
    hf = np.array([table[k].occupied_height_m for k in weft_keys])
    # each crossing as far apart as its two yarns' fibres need
    half = 0.25 * (hw[:, None] + hf[None, :]) + 0.5 * c
    ww = np.array([table[k].occupied_width_m for k in warp_keys])
    wf = np.array([table[k].occupied_width_m for k in weft_keys])
    sx, sy = fabric.weft.spacing_m, fabric.warp.spacing_m
    weft_u = (np.arange(m.shape[1]) + 0.5) * sx
    warp_u = (np.arange(m.shape[0]) + 0.5) * sy
    for i in range(m.shape[0]):
        out.append(YarnPath(f"warp-{i + 1}", "warp", 0, warp_u[i], lx, lx,
                            tuple(weft_u), tuple(np.where(m[i] == 1, half[i], -half[i])),
                            tuple(f * 0.5 * wf)))
        keys.append(warp_keys[i])
    for j in range(m.shape[1]):
        out.append(YarnPath(f"weft-{j + 1}", "weft", 1, weft_u[j], ly, ly,
                            tuple(warp_u),
                            tuple(np.where(m[:, j] == 1, -half[:, j], half[:, j])),
                            tuple(f * 0.5 * ww)))
        keys.append(weft_keys[j])
    return out, keys


def layered_cell(fabric: Fabric) -> tuple[list[YarnPath], list[str]]:
    """3D: stuffer warps, weft layers and binders of the unit cell and their spec keys."""
    lx, ly = fabric.unit_cell_m
    f = fabric.plateau
    out: list[YarnPath] = []
    keys: list[str] = []
    a = fabric.architecture
    lev = fabric.levels()
    sx, p = fabric.weft.spacing_m, fabric.warp.spacing_m
    cols = (np.arange(a.columns) + 0.5) * sx
    for d in range(a.dents):
        for g in a.warp_gaps:
            out.append(YarnPath(f"warp-d{d + 1}-g{g}", "warp", 0, (d + 0.25) * p,
                                lx, lx, z_m=lev["gap"][g], level=g))
            keys.append(fabric._spec_key("warp", d + 1, g))
    for c in range(a.columns):
        for k in range(a.weft_layers):
            out.append(YarnPath(f"weft-c{c + 1}-l{k + 1}", "weft", 1, cols[c], ly, ly,
                                z_m=lev["weft"][k], level=k))
            keys.append(fabric._spec_key("weft", c + 1, k + 1))
    for d, dent in enumerate(a.binder_paths):
        for b, path in enumerate(dent):
            y = (d + 0.75) * p if not a.separate_binders else \
                (d + 0.25 + (b + 1) * fabric.binder_pitch_m() / p) * p
            out.append(YarnPath(f"binder-d{d + 1}-{b + 1}", "binder", 0,
                                y, lx, lx, tuple(cols),
                                tuple(lev["gap"][g] for g in path),
                                (f * 0.5 * fabric.weft.occupied_width_m,), level=min(path)))
            keys.append(fabric._spec_key("binder", d + 1, None))
    return out, keys
