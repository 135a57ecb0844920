"""Reductions of test curves: stiffness before and after a transition, values at points."""

from __future__ import annotations

import numpy as np


def bilinear_fit(x: np.ndarray, y: np.ndarray, min_points: int = 4) -> dict:
    """Fit two straight lines meeting at a break point (least squares over break points).

    Returns the initial slope, the final slope, and the break point (x, y). With
    fewer than ``2 * min_points`` points, one line is fitted and the break is None.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    n = len(x)
    if n < 2 * min_points:
        k = float(np.polyfit(x, y, 1)[0]) if n >= 2 else float("nan")
        return {"initial_slope": k, "final_slope": k, "break_x": None, "break_y": None}
    best = None
    for b in range(min_points, n - min_points + 1):
        p1 = np.polyfit(x[:b], y[:b], 1)
        p2 = np.polyfit(x[b - 1:], y[b - 1:], 1)
        sse = (np.sum((np.polyval(p1, x[:b]) - y[:b]) ** 2)
               + np.sum((np.polyval(p2, x[b - 1:]) - y[b - 1:]) ** 2))
        if best is None or sse < best[0]:
            best = (sse, p1, p2)
    _, p1, p2 = best
    if abs(p1[0] - p2[0]) > 1e-300:
        xb = (p2[1] - p1[1]) / (p1[0] - p2[0])
    else:
        xb = float("nan")
    return {"initial_slope": float(p1[0]), "final_slope": float(p2[0]),
            "break_x": float(xb), "break_y": float(np.polyval(p1, xb))}


def values_at(x: np.ndarray, y: np.ndarray, points) -> dict[float, float | None]:
    """y interpolated at each point inside the range of x (None outside)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    order = np.argsort(x)
    out = {}
    for p in points:
        out[p] = float(np.interp(p, x[order], y[order])) if x.min() <= p <= x.max() else None
    return out


def curve_difference(x1, y1, x2, y2, lower_fraction: float = 0.2) -> float:
    """Largest |y2 − y1| over the common x range (above ``lower_fraction`` of it),
    relative to the largest |y1| there."""
    x1, y1, x2, y2 = (np.asarray(a, float) for a in (x1, y1, x2, y2))
    hi = min(x1.max(), x2.max())
    lo = max(x1.min(), x2.min())
    xs = np.linspace(lo + lower_fraction * (hi - lo), hi, 50)
    a = np.interp(xs, np.sort(x1), y1[np.argsort(x1)])
    b = np.interp(xs, np.sort(x2), y2[np.argsort(x2)])
    scale = np.abs(a).max()
    return float(np.abs(b - a).max() / scale) if scale > 0 else float("nan")
