"""Plots people put in a report: labelled axes with units, PNG at 150 dpi."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..engine import mpi


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_curves(path: Path, series: list[dict], xlabel: str, ylabel: str, title: str = "",
                notes: str = "") -> Path | None:
    """Plot one or more curves into ``path`` (rank 0 only).

    Each series is a dict with ``x``, ``y`` and optional ``label``, ``style``.
    """
    if not mpi.is_root():
        return None
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
    for s in series:
        ax.plot(np.asarray(s["x"]), np.asarray(s["y"]), s.get("style", "-"),
                label=s.get("label"), lw=s.get("lw", 1.6))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, alpha=0.3)
    if any(s.get("label") for s in series):
        ax.legend(frameon=False)
    if notes:
        ax.text(0.02, 0.98, notes, transform=ax.transAxes, va="top", ha="left", fontsize=8,
                family="monospace")
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return Path(path)
