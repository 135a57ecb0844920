"""The one figure style of fabmd's report plots: curve, marks, side panel, title.

Every curve figure (:func:`fabmd.results.plots.curves_figure`) is laid out here the
same way, so that nothing written on it covers data:

* the title is the figure's title, wrapped to the figure width (never clipped);
* the legend and the notes sit in a panel right of the axes (constrained layout
  makes room for them), never on the curve;
* the quantities a summary reports are *marks* on the curve, named in the legend:
  ``{"kind": "vline", "x": 1.8, "label": "transition 1.81 %"}`` (a vertical line),
  ``{"kind": "point", "x": [...], "y": [...], "label": "report points"}``,
  ``{"kind": "line", "x": [x0, x1], "y": [y0, y1], "label": "initial tangent"}``;
* every axis label carries its unit in brackets (:func:`check_units`).

:func:`layout_problems` lists the texts that overlap an axes' data region or stick
out of the figure (the tests use it on every figure family).
"""

from __future__ import annotations

import re
import textwrap

import numpy as np

#: figure size [in] and resolution of curve figures
FIGSIZE_IN = (8.0, 4.4)
DPI = 150
#: colours of marks (after the curves' own colour cycle)
MARK_COLOURS = ("0.25", "tab:purple", "tab:brown", "tab:olive", "tab:cyan")
MARK_KINDS = ("vline", "point", "line")
_UNIT = re.compile(r"\[[^\]]+\]\s*$")


def wrap_title(title: str, width_in: float, fontsize: float = 11.0) -> str:
    """``title`` wrapped to lines that fit ``width_in`` inches at ``fontsize`` points."""
    chars = max(20, int(width_in * 72 / (0.55 * fontsize)))
    return "\n".join(textwrap.fill(part, chars) for part in title.split("\n"))


def add_marks(ax, marks: list[dict] | None) -> None:
    """Draw the summary's quantities on ``ax`` (see the module docstring); each is named
    in the legend by its ``label``."""
    for k, mark in enumerate(marks or []):
        kind = mark.get("kind", "point")
        if kind not in MARK_KINDS:
            raise ValueError(f"mark kind must be one of {MARK_KINDS}, got {kind!r}")
        colour = mark.get("colour", MARK_COLOURS[k % len(MARK_COLOURS)])
        label = mark.get("label")
        if kind == "vline":
            if mark.get("x") is None or not np.isfinite(mark["x"]):
                continue
            ax.axvline(float(mark["x"]), ls=mark.get("style", "--"), lw=1.0, color=colour,
                       label=label)
        elif kind == "line":
            ax.plot(np.asarray(mark["x"], float), np.asarray(mark["y"], float),
                    mark.get("style", ":"), lw=1.3, color=colour, label=label)
        else:
            x = np.atleast_1d(np.asarray(mark["x"], float))
            y = np.atleast_1d(np.asarray(mark["y"], float))
            keep = np.isfinite(x) & np.isfinite(y)
            if keep.any():
                ax.plot(x[keep], y[keep], mark.get("style", "o"), ms=6, mfc="none", mew=1.4,
                        color=colour, label=label)


def report_marks(values: dict, label: str = "report points") -> list[dict]:
    """A ``point`` mark of a summary's ``{x (as text): y or None}`` table."""
    points = [(float(x), float(y)) for x, y in values.items() if y is not None]
    if not points:
        return []
    return [{"kind": "point", "x": [p[0] for p in points], "y": [p[1] for p in points],
             "label": label}]


def side_panel(ax, notes: str = "", legend: bool = True) -> None:
    """Legend (top) and notes (bottom) in a panel right of ``ax``, outside its data."""
    if legend and any(h.get_label() and not h.get_label().startswith("_")
                      for h in [*ax.get_lines(), *ax.collections, *ax.patches]):
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
                  frameon=False, fontsize=8)
    if notes:
        ax.text(1.02, 0.0, notes.strip("\n"), transform=ax.transAxes, va="bottom",
                ha="left", fontsize=8, family="monospace", linespacing=1.3)


def finish(fig, ax, title: str = "", notes: str = "", marks: list[dict] | None = None) -> None:
    """Marks, side panel, wrapped title, grid: the common dressing of a curve figure."""
    add_marks(ax, marks)
    ax.grid(True, alpha=0.3)
    side_panel(ax, notes)
    if title:
        fig.suptitle(wrap_title(title, fig.get_figwidth()), fontsize=11)


def check_units(*labels: str) -> None:
    """Raise ValueError for an axis label without a ``[unit]`` at its end."""
    for label in labels:
        if not _UNIT.search(label or ""):
            raise ValueError(f"axis label {label!r} needs a unit in brackets, e.g. 'x [mm]'")


def _texts(fig):
    yield from (t for t in fig.texts if t.get_text())
    for ax in fig.axes:
        for t in (ax.title, ax._left_title, ax._right_title, *ax.texts):
            if t.get_text() and t.get_visible():
                yield t
        if ax.get_legend() is not None:
            yield ax.get_legend()
    yield from fig.legends


def layout_problems(fig) -> list[str]:
    """Texts (titles, notes, legends) that overlap the data region of an axes or stick out
    of the figure; empty when the layout is clean. Draws the figure."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    page = fig.bbox
    regions = [ax.get_window_extent(renderer) for ax in fig.axes
               if ax.get_visible() and ax.axison and (ax.lines or ax.collections
                                                      or ax.images or ax.patches)]
    problems = []
    seen = []
    for t in _texts(fig):
        box = t.get_window_extent(renderer)
        name = t.get_text() if hasattr(t, "get_text") else "legend"
        name = " ".join(str(name).split())[:40]
        if any(box.overlaps(r) for r in regions):
            problems.append(f"{name!r} overlaps the data region")
        if box.x0 < page.x0 - 1 or box.x1 > page.x1 + 1 or box.y0 < page.y0 - 1 \
                or box.y1 > page.y1 + 1:
            problems.append(f"{name!r} is cut off by the figure edge")
        problems += [f"{name!r} overlaps {other!r}" for other, b in seen if box.overlaps(b)]
        seen.append((name, box))
    return problems


def label_problems(fig) -> list[str]:
    """Axes with data whose x or y label is missing or has no ``[unit]``."""
    problems = []
    for ax in fig.axes:
        if not (ax.get_visible() and ax.axison) or not (ax.lines or ax.collections
                                                        or ax.images):
            continue
        if hasattr(ax, "_colorbar"):  # a colour bar: its one label is checked below
            label = ax.get_ylabel() or ax.get_xlabel()
            if not _UNIT.search(label or ""):
                problems.append(f"colour bar label {label!r} has no unit")
            continue
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if not _UNIT.search(label or ""):
                problems.append(f"axis label {label!r} has no unit")
    return problems
