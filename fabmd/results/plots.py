"""Plots people put in a report: labelled axes with units, PNG at 150 dpi.

``plot_curves``/``plot_field`` write a PNG (rank 0 only); ``curves_figure``/
``field_figure`` return the matplotlib figure, for notebooks.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.fieldplot import LENGTH_UNITS, field_figure  # noqa: F401 - notebooks use them here
from ..analysis.fieldplot import pyplot as _pyplot
from ..engine import mpi
from . import figure


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


def plot_field(path: Path, x_edges, y_edges, values, label: str, **kwargs) -> Path | None:
    """Plot a cell field into ``path`` (rank 0 only); see :func:`field_figure`."""
    if not mpi.is_root():
        return None
    return _save(field_figure(x_edges, y_edges, values, label, **kwargs), path)
