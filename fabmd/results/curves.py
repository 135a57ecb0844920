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


def tangent_intersection(x, y, initial: tuple[float, float] = (0.05, 0.35),
                         final: float = 0.15, min_ratio: float = 3.0,
                         min_points: int = 3) -> dict:
    """Where the tangent of a curve's low initial part meets that of its steep final part.

    The standard reading of a shear-locking angle: a straight line is fitted to the
    points whose x lies in the ``initial`` fractions of the x range (default 5–35 %,
    past the start-up), another to the last ``final`` fraction of it; the locking
    point is their intersection.

    Returns:
        ``x``, ``y`` of the intersection, ``initial_slope``, ``final_slope``,
        ``initial_range`` and ``final_range`` (the x ranges fitted), and ``found``:
        True when the final slope is at least ``min_ratio`` times the initial one
        (and positive) and the intersection lies inside the x range; ``x``/``y``
        are None when the lines do not meet.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    order = np.argsort(x)
    x, y = x[order], y[order]
    lo, hi = float(x.min()), float(x.max())
    span = hi - lo
    a = lo + initial[0] * span, lo + initial[1] * span
    b = hi - final * span, hi
    first = (x >= a[0]) & (x <= a[1])
    last = (x >= b[0]) & (x <= b[1])
    out = {"x": None, "y": None, "initial_slope": None, "final_slope": None,
           "initial_range": [a[0], a[1]], "final_range": [b[0], b[1]], "found": False}
    if first.sum() < min_points or last.sum() < min_points:
        return out
    p1 = np.polyfit(x[first], y[first], 1)
    p2 = np.polyfit(x[last], y[last], 1)
    out["initial_slope"], out["final_slope"] = float(p1[0]), float(p2[0])
    if p2[0] - p1[0] <= 0:
        return out
    xb = float((p1[1] - p2[1]) / (p2[0] - p1[0]))
    out["x"], out["y"] = xb, float(np.polyval(p1, xb))
    steep = p2[0] > 0 and p2[0] >= min_ratio * max(p1[0], 0.0)
    out["found"] = bool(steep and lo <= xb <= hi)
    return out


#: the stated method of :func:`locking_angle` (README "Virtual tests")
LOCKING_METHOD = ("initial branch: straight line fitted over {initial[0]:g}-{initial[1]:g} deg; "
                  "departure: the first angle past it from which F_norm stays at least "
                  "{factor:g} x that line for {window:g} deg; locking angle: where the "
                  "tangent fitted over those {window:g} deg meets the initial line")


def locking_angle(angle_deg, force, initial_deg: tuple[float, float] = (10.0, 20.0),
                  factor: float = 2.0, window_deg: float = 5.0, min_ratio: float = 3.0,
                  min_points: int = 3) -> dict:
    """Shear-locking angle by a stated method that does not depend on where the test stops.

    1. The initial branch: a straight line F_lin fitted to the points with angle in
       ``initial_deg`` (a fixed range past the start-up: default 10–20°; at 5° the
       fabric is still being brought up to the frame's speed and F may read low or high).
    2. The departure γ_d: the first angle past that range from which the force stays at
       or above ``factor`` × F_lin (and above F_lin + 3 × the fit's scatter) for
       ``window_deg`` degrees.
    3. The locking angle: where the straight line fitted over [γ_d, γ_d + ``window_deg``]
       meets F_lin.

    Only the curve up to γ_d + ``window_deg`` is read, so a test stopped anywhere past that
    gives the same angle. ``found`` is False when the curve does not reach the initial
    range, when no departure is confirmed before it ends (``reason`` says which), or
    when the final slope is not ``min_ratio`` × the initial one.

    Returns:
        ``x``, ``y`` (the locking point), ``departure_x``, ``initial_slope``,
        ``final_slope`` (force per degree), ``initial_range``, ``final_range``,
        ``found``, ``reason`` and ``method`` (the text of the method with its numbers).
    """
    x, y = np.asarray(angle_deg, float), np.asarray(force, float)
    order = np.argsort(x)
    x, y = x[order], y[order]
    out = {"x": None, "y": None, "departure_x": None, "initial_slope": None,
           "final_slope": None, "initial_range": [float(initial_deg[0]), float(initial_deg[1])],
           "final_range": None, "found": False, "reason": "",
           "method": LOCKING_METHOD.format(initial=initial_deg, factor=factor,
                                           window=window_deg)}
    first = (x >= initial_deg[0]) & (x <= initial_deg[1])
    if first.sum() < min_points or x.max() < initial_deg[1]:
        out["reason"] = (f"the curve does not cover the initial range {initial_deg[0]:g}-"
                         f"{initial_deg[1]:g} deg")
        return out
    p1 = np.polyfit(x[first], y[first], 1)
    out["initial_slope"] = float(p1[0])
    scatter = float(np.std(y[first] - np.polyval(p1, x[first])))
    line = np.polyval(p1, x)
    above = (y >= factor * line) & (y >= line + 3 * scatter) & (x > initial_deg[1])
    departure = None
    for k in np.flatnonzero(above):
        end = x[k] + window_deg
        if end > x[-1]:
            break  # the test stopped before a departure could be confirmed
        span = (x >= x[k]) & (x <= end)
        if above[span].all():
            departure = k
            break
    if departure is None:
        out["reason"] = (f"no departure by {factor:g} x the initial line held for "
                         f"{window_deg:g} deg before the curve ends at {x[-1]:.1f} deg")
        return out
    a, b = float(x[departure]), float(x[departure] + window_deg)
    span = (x >= a) & (x <= b)
    if span.sum() < min_points:
        out["reason"] = f"fewer than {min_points} points in {a:.1f}-{b:.1f} deg"
        return out
    p2 = np.polyfit(x[span], y[span], 1)
    out.update(departure_x=a, final_range=[a, b], final_slope=float(p2[0]))
    if p2[0] - p1[0] <= 0:
        out["reason"] = "the final tangent is not steeper than the initial line"
        return out
    xb = float((p1[1] - p2[1]) / (p2[0] - p1[0]))
    out["x"], out["y"] = xb, float(np.polyval(p1, xb))
    steep = p2[0] > 0 and p2[0] >= min_ratio * max(p1[0], 0.0)
    out["found"] = bool(steep and initial_deg[0] <= xb <= b)
    if not out["found"]:
        out["reason"] = (f"final slope {p2[0]:.3g} < {min_ratio:g} x initial {p1[0]:.3g}"
                         if not steep else f"the tangents meet at {xb:.1f} deg, outside "
                         f"{initial_deg[0]:g}-{b:.1f}")
    return out
