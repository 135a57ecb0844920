"""Plots people put in a report: labelled axes with units, PNG at 150 dpi.

``plot_curves``/``plot_field`` write a PNG (rank 0 only); ``curves_figure``/
``field_figure`` return the matplotlib figure, for notebooks.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..engine import mpi
from . import figure


def _pyplot():
    import matplotlib

    # files are drawn without a display; a notebook keeps its inline backend
    if "inline" not in os.environ.get("MPLBACKEND", ""):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def curves_figure(series: list[dict], xlabel: str, ylabel: str, title: str = "",
                  notes: str = "", marks: list[dict] | None = None,
                  spans: list | None = None):
    """A matplotlib figure of one or more curves (for notebooks; see :func:`plot_curves`).

    Each series is a dict with ``x``, ``y`` and optional ``label``, ``style``, ``lw``.
    Axis labels carry units, e.g. ``"strain [%]"``. Title, legend, notes and ``marks``
    (the summary's quantities on the curve) are laid out by :mod:`fabmd.results.figure`:
    nothing covers the data. ``spans``: [from, to] ranges of x shaded as not quasi-static
    (the part of the curve not to trust).
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=figure.FIGSIZE_IN, layout="constrained")
    for k, (a, b) in enumerate(spans or []):
        ax.axvspan(a, b, color="tab:red", alpha=0.15, lw=0,
                   label="not quasi-static" if k == 0 else None)
    for s in series:
        ax.plot(np.asarray(s["x"]), np.asarray(s["y"]), s.get("style", "-"),
                label=s.get("label"), lw=s.get("lw", 1.6))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    figure.finish(fig, ax, title, notes, marks)
    return fig


def plot_curves(path: Path, series: list[dict], xlabel: str, ylabel: str, title: str = "",
                notes: str = "", marks: list[dict] | None = None,
                spans: list | None = None) -> Path | None:
    """Plot one or more curves into ``path`` (rank 0 only).

    Each series is a dict with ``x``, ``y`` and optional ``label``, ``style``; ``marks``
    see :mod:`fabmd.results.figure`; ``spans`` as for :func:`curves_figure`.
    """
    if not mpi.is_root():
        return None
    fig = curves_figure(series, xlabel, ylabel, title, notes, marks, spans)
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    plt = _pyplot()
    fig.savefig(path, dpi=figure.DPI)
    plt.close(fig)
    return Path(path)


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
    plt = _pyplot()
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


def plot_field(path: Path, x_edges, y_edges, values, label: str, **kwargs) -> Path | None:
    """Plot a cell field into ``path`` (rank 0 only); see :func:`field_figure`."""
    if not mpi.is_root():
        return None
    return _save(field_figure(x_edges, y_edges, values, label, **kwargs), path)
