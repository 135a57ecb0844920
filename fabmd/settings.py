"""Build protocol objects from scene-file tables (``[crimp]``, ``[tension]``, ...).

:func:`build` maps a table onto a dataclass: unknown keys are refused naming the
key and the allowed ones; values of fields whose names carry an SI unit suffix
may be given as text with units ("120 mm", "2 mm/min"); sub-tables build nested
settings (``[crimp.quasi_static]``, ``[tension.contact]``, ``[tension.trajectory]``),
starting from the field's default (or the default passed in) for the keys they omit.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any

from .errors import InputError
from .units import quantity

#: field-name suffix -> quantity kind (longest suffix first)
SUFFIX_KINDS = (
    ("_m_s", "speed"), ("_kg_m3", "density"), ("_m2", "area"), ("_pa", "pressure"),
    ("_deg", None), ("_pct", None), ("_m", "length"), ("_s", "time"), ("_n", "force"),
)


def _kind(name: str) -> str | None:
    for suffix, kind in SUFFIX_KINDS:
        if name.endswith(suffix):
            return kind
    return None


def _dataclass_of(hint) -> type | None:
    """The dataclass in a type hint (``X`` or ``X | None``), if any."""
    if dataclasses.is_dataclass(hint):
        return hint
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        for arg in typing.get_args(hint):
            if dataclasses.is_dataclass(arg):
                return arg
    return None


def _field_default(f: dataclasses.Field):
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None if f.default is dataclasses.MISSING else f.default


def build(cls: type, table: dict | None, section: str, **defaults: Any):
    """An instance of dataclass ``cls`` from a scene-file table.

    Args:
        table: the TOML table (None or {} for all defaults).
        section: its name, used in error messages (``"tension"``).
        defaults: values used where the table gives none (e.g. the scene's contact).
    """
    table = dict(table or {})
    if not isinstance(table, dict):
        raise InputError(f"[{section}] must be a table, got {table!r}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    hints = typing.get_type_hints(cls)
    kwargs = dict(defaults)
    for key, value in table.items():
        if key not in fields:
            raise InputError(f"[{section}] has no key {key!r} (allowed: {', '.join(fields)})")
        nested = _dataclass_of(hints.get(key))
        if nested is not None and not isinstance(value, dict | nested | None):
            raise InputError(f"[{section}] {key} must be a table ([{section}.{key}] or "
                             f"{key} = {{ ... }}), got {value!r}")
        if nested is not None and isinstance(value, dict):
            # keys the sub-table leaves out keep the protocol's own default (e.g. the
            # trajectory frames a test writes), not the nested class's
            base = defaults.get(key, _field_default(fields[key]))
            inherited = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)} \
                if dataclasses.is_dataclass(base) else {}
            merged = {**inherited, **value}
            value = build(nested, merged, f"{section}.{key}")
        elif isinstance(value, str) and _kind(key):
            value = quantity(value, _kind(key), f"{section}.{key}")
        elif isinstance(value, list):
            value = tuple(value)
        kwargs[key] = value
    try:
        return cls(**kwargs)
    except InputError as exc:
        raise InputError(f"[{section}] {exc}") from None
    except TypeError as exc:
        raise InputError(f"[{section}] {exc}") from None
