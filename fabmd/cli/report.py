"""Numbers for the terminal: 3–4 significant digits with the unit the key names, and the
per-stage verdicts (where a stage stopped, quasi-static or not, energy balance)."""

from __future__ import annotations

import math

#: key suffix -> (factor, unit) for display, longest suffix first
SUFFIX_UNITS = (
    ("stiffness_n", 1.0, "N per unit strain"),
    ("_n_m_per_rad", 1.0, "N/m per rad"), ("_n_m_per_width", 1.0, "N/m per unit strain"),
    ("_n_per_m", 1.0, "N/m"), ("_n_m", 1.0, "N/m"), ("_m_s", 1.0, "m/s"),
    ("_m2", 1e6, "mm²"), ("_pct", 1.0, "%"), ("_deg", 1.0, "°"), ("_rad", 1.0, "rad"),
    ("_pa", 1.0, "Pa"), ("_kg", 1.0, "kg"), ("_j", 1.0, "J"), ("_n", 1.0, "N"),
    ("_m", 1e3, "mm"), ("_s", 1.0, "s"),
)


def number(value: float, digits: int = 4) -> str:
    """``value`` to ``digits`` significant digits (thousands separated when whole)."""
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, int):
        return f"{value:,}"
    if not math.isfinite(value):
        return str(value)
    return f"{value:.{digits}g}"


def value_text(key: str, value) -> str:
    """``value`` of summary ``key`` with its unit, e.g. ``("gauge_length_m", 0.016)`` ->
    ``16 mm``."""
    if isinstance(value, str) or isinstance(value, bool) or value is None:
        return str(value)
    for suffix, factor, unit in SUFFIX_UNITS:
        if key.endswith(suffix):
            return f"{number(value * factor if factor != 1.0 else value)} {unit}"
    return number(value)


def quasi_static_line(verdict) -> str | None:
    """``quasi-static: yes`` or ``quasi-static: NO (...)`` of a driven test's verdict."""
    if isinstance(verdict, bool):
        return f"quasi-static: {'yes' if verdict else 'NO'}"
    if not isinstance(verdict, dict):
        return None
    if verdict.get("ok"):
        return "quasi-static: yes"
    return "quasi-static: NO (" + "; ".join(verdict.get("problems", [])) + ")"


def energy_line(balance) -> str | None:
    """``energy balance: external work 1.234e-3 J, closing error 0.31 %``."""
    if not isinstance(balance, dict):
        return None
    work = balance.get("external_work_j")
    err = balance.get("relative_error")
    parts = []
    if work is not None:
        parts.append(f"external work {number(work)} J")
    for key, name in (("strain_energy_change_j", "strain energy"),
                      ("damping_dissipation_j", "damping"), ("contact_work_j", "contact")):
        if balance.get(key) is not None:
            parts.append(f"{name} {number(balance[key])} J")
    parts.append("closing error " + (f"{100 * err:.3g} %" if err is not None else
                                     "not measured"))
    return "energy balance: " + ", ".join(parts)
