"""SI at every interface, textile units at the door.

Users may type ``"68 tex"``, ``"0.3 mm"`` or ``"70 GPa"`` where a scene asks for
a quantity; :func:`quantity` turns such text into an SI float once, where the
value enters fabmd. A bare number is taken as SI already.

The one conversion table, by kind of quantity:

==================  =====================================================
kind                units accepted (SI unit first)
==================  =====================================================
length              m, cm, mm, um (µm)
area                m2, mm2, um2
linear_density      kg/m, g/m, tex (g/km), dtex, ktex, den (g/9 km)
modulus / pressure  Pa, kPa, MPa, GPa
density             kg/m3, g/cm3
force               N, mN, kN
stiffness           N/m, mN/m, kN/m (a spring: force per metre of deflection)
time                s, ms, us, min
speed               m/s, mm/s, mm/min, m/min
angle               rad, deg
count_per_length    1/m, 1/cm, 1/mm (also "/cm", "ends/cm", "picks/cm")
areal_density       kg/m2, g/m2
bending_stiffness   N·m2 (also N.m2, N*m2), N·mm2, cN·cm2 (E·I of a yarn)
==================  =====================================================
"""

from __future__ import annotations

import math
import re
from typing import Any

from .errors import InputError

TEX = 1e-6  # kg/m per tex (1 g/km)

_UNITS: dict[str, dict[str, float]] = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6},
    "area": {"m2": 1.0, "m^2": 1.0, "mm2": 1e-6, "mm^2": 1e-6, "um2": 1e-12, "um^2": 1e-12},
    "linear_density": {"kg/m": 1.0, "g/m": 1e-3, "tex": TEX, "dtex": 0.1 * TEX,
                       "ktex": 1e3 * TEX, "den": TEX / 9.0},
    "pressure": {"pa": 1.0, "kpa": 1e3, "mpa": 1e6, "gpa": 1e9},
    "density": {"kg/m3": 1.0, "kg/m^3": 1.0, "g/cm3": 1e3, "g/cm^3": 1e3},
    "force": {"n": 1.0, "mn": 1e-3, "kn": 1e3},
    "stiffness": {"n/m": 1.0, "mn/m": 1e-3, "kn/m": 1e3},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "min": 60.0},
    "speed": {"m/s": 1.0, "mm/s": 1e-3, "mm/min": 1e-3 / 60.0, "m/min": 1.0 / 60.0},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "count_per_length": {"1/m": 1.0, "1/cm": 1e2, "1/mm": 1e3, "/m": 1.0, "/cm": 1e2,
                         "/mm": 1e3, "ends/cm": 1e2, "picks/cm": 1e2, "percm": 1e2},
    "areal_density": {"kg/m2": 1.0, "g/m2": 1e-3, "gsm": 1e-3},
    "bending_stiffness": {f"{force}{dot}{length}{square}": si
                          for force, length, si in (("N", "m", 1.0), ("N", "mm", 1e-6),
                                                    ("cN", "cm", 1e-6))
                          for dot in ("·", ".", "*") for square in ("2", "²", "^2")},
}
# case-insensitive kinds (SI prefixes of Pa and N never clash there)
_CASE_FREE = {"pressure", "force", "stiffness"}
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def kinds() -> list[str]:
    """The kinds of quantity :func:`quantity` understands."""
    return sorted(_UNITS)


def quantity(value: Any, kind: str, name: str = "value") -> float:
    """Return ``value`` in SI units.

    Args:
        value: a number (already SI) or a string ``"<number> <unit>"``.
        kind: one of :func:`kinds`, e.g. ``"length"``.
        name: field name used in the error message.

    Raises:
        InputError: unknown unit or unparsable text.
    """
    if kind not in _UNITS:
        raise ValueError(f"unknown quantity kind {kind!r}")
    if isinstance(value, bool):
        raise InputError(f"{name} must be a number or a '<number> <unit>' string, got {value!r}")
    if isinstance(value, int | float):
        return float(value)
    if not isinstance(value, str):
        raise InputError(f"{name} must be a number or a '<number> <unit>' string, got {value!r}")
    match = _NUMBER.match(value)
    if not match:
        raise InputError(f"{name}: cannot read a quantity from {value!r}")
    number, unit = float(match.group(1)), match.group(2).replace(" ", "")
    table = _UNITS[kind]
    key = unit.lower() if kind in _CASE_FREE else unit
    if key == "":
        return number
    if key not in table:
        allowed = ", ".join(table)
        raise InputError(f"{name}: unknown {kind.replace('_', ' ')} unit {unit!r} "
                         f"(allowed: {allowed})")
    return number * table[key]


def tex_to_kg_per_m(tex: float) -> float:
    """Linear density in tex (g/km) to kg/m."""
    return tex * TEX
