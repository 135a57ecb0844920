"""Small validators used when fabmd objects are built.

Each raises :class:`fabmd.errors.InputError` with the field name, the value and
what is allowed, e.g. ``"yarn.spacing_m must be > 0, got -0.002"``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from .errors import InputError


def _number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(f"{name} must be finite, got {value}")
    return value


def positive(name: str, value: Any) -> float:
    """Return ``value`` as float if it is a finite number > 0."""
    value = _number(name, value)
    if value <= 0:
        raise InputError(f"{name} must be > 0, got {value:g}")
    return value


def non_negative(name: str, value: Any) -> float:
    """Return ``value`` as float if it is a finite number >= 0."""
    value = _number(name, value)
    if value < 0:
        raise InputError(f"{name} must be >= 0, got {value:g}")
    return value


def in_range(name: str, value: Any, low: float, high: float, *,
             low_open: bool = False, high_open: bool = False) -> float:
    """Return ``value`` if it lies in the interval from ``low`` to ``high``."""
    value = _number(name, value)
    too_low = value <= low if low_open else value < low
    too_high = value >= high if high_open else value > high
    if too_low or too_high:
        lb = "(" if low_open else "["
        hb = ")" if high_open else "]"
        raise InputError(f"{name} must be in {lb}{low:g}, {high:g}{hb}, got {value:g}")
    return value


def finite(name: str, value: Any) -> float:
    """Return ``value`` as float if it is a finite number."""
    return _number(name, value)


def positive_int(name: str, value: Any, minimum: int = 1) -> int:
    """Return ``value`` if it is an integer >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, int):
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        else:
            raise InputError(f"{name} must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise InputError(f"{name} must be an integer >= {minimum}, got {value}")
    return int(value)


def boolean(name: str, value: Any) -> bool:
    """``value`` if it is true or false, else InputError naming ``name``."""
    if not isinstance(value, bool):
        raise InputError(f"{name} must be true or false, got {value!r}")
    return value


def one_of(name: str, value: Any, allowed: Iterable[Any]) -> Any:
    """Return ``value`` if it is one of ``allowed``."""
    allowed = list(allowed)
    if value not in allowed:
        choices = ", ".join(repr(a) for a in allowed)
        raise InputError(f"{name} must be one of {choices}, got {value!r}")
    return value


def locking_method(prefix: str, initial_deg, factor: Any, top_deg: float) -> None:
    """The locking-angle method's settings of a shear test (``prefix``: its table):
    ``locking_initial_deg`` (lo, hi) within [0, ``top_deg``], lo < hi, and a
    ``locking_factor`` in (1, 100]."""
    lo, hi = initial_deg
    in_range(f"{prefix}.locking_initial_deg[0]", lo, 0, top_deg)
    in_range(f"{prefix}.locking_initial_deg[1]", hi, lo, top_deg, low_open=True)
    in_range(f"{prefix}.locking_factor", factor, 1, 100, low_open=True)
