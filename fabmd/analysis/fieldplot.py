"""Figures of cell fields (shear angle, bond force ... on a regular grid) with units on
the axes; :mod:`fabmd.results.plots` writes them to PNG files."""

from __future__ import annotations

import os

import numpy as np


def pyplot():
    """matplotlib.pyplot, drawing to files (Agg) unless a notebook set its inline backend."""
    import matplotlib

    # files are drawn without a display; a notebook keeps its inline backend
    if "inline" not in os.environ.get("MPLBACKEND", ""):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: length unit of plotted coordinates: name and factor from metres
LENGTH_UNITS = {"m": 1.0, "mm": 1e3, "µm": 1e6}


def field_figure(x_edges, y_edges, values, label: str, *, xlabel: str = "x",
                 ylabel: str = "y", length_unit: str = "mm", x_unit: str | None = None,
                 y_unit: str | None = None, title: str = "", cmap: str = "coolwarm",
                 symmetric: bool = False, aspect: str = "auto"):
    """A matplotlib figure of a cell field ``values[j, i]`` on a regular grid.

    Edges are SI (metres for coordinates) and shown in ``length_unit``; give
    ``x_unit``/``y_unit`` (already scaled axes, e.g. time in µs) to label other
    quantities. ``label`` names the colour bar with its unit, e.g.
    ``"shear angle γ [°]"``. ``symmetric`` centres the colour scale on 0.
    """
    plt = pyplot()
    if length_unit not in LENGTH_UNITS:
        raise ValueError(f"length_unit must be one of {list(LENGTH_UNITS)}, got {length_unit!r}")
    scale = LENGTH_UNITS[length_unit]
    xs = 1.0 if x_unit else scale
    ys = 1.0 if y_unit else scale
    values = np.asarray(values, float)
    fig, ax = plt.subplots(figsize=(6.4, 4.8), layout="constrained")
    limits = {}
    finite = values[np.isfinite(values)]
    if symmetric and finite.size:
        bound = float(np.abs(finite).max()) or 1.0
        limits = {"vmin": -bound, "vmax": bound}
    mesh = ax.pcolormesh(np.asarray(x_edges) * xs, np.asarray(y_edges) * ys,
                         np.ma.masked_invalid(values), cmap=cmap, shading="flat", **limits)
    fig.colorbar(mesh, ax=ax, label=label)
    ax.set_xlabel(f"{xlabel} [{x_unit or length_unit}]")
    ax.set_ylabel(f"{ylabel} [{y_unit or length_unit}]")
    ax.set_aspect(aspect)
    if title:
        ax.set_title(title)
    return fig
