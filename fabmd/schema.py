"""One schema for every table of a scene file and for ``fabmd validate --set``.

A table (``[fabric]``, ``[yarns.warp]``, ``[materials.X]``, ``[contact]``,
``[discretisation]``, ``[crimp]``, each test and its sub-tables ``coupon``,
``time_step``, ``trajectory``, ``contact``, ``tool``, ``relax``, ...) is the
dataclass it builds. Its fields are declared once, there:

* the **type** comes from the field's annotation (``typing.get_type_hints``): a
  dataclass is a sub-table, ``tuple[...]`` takes a TOML list, ``bool`` and ``str``
  refuse other values;
* the **unit** comes from the field's metadata (``field(metadata=unit("length"))``)
  or, for the classes of the model and the protocols, from :data:`UNITS` below (by
  class, base classes included: a field declared on ``DrivenTest`` serves every
  driven test). A field of no declared unit takes plain numbers only — a unit is
  never guessed from a name suffix (``stiffness_n_per_m = "5 mm"`` was once read as
  a length). ``tests/test_schema.py`` checks that every field whose name carries a
  unit is declared.

:func:`build` is the one builder: ``fabmd.scenefile`` (owned tables),
``fabmd.settings`` (stage tables) and ``fabmd.verification`` (``--set``) all call it.
It refuses unknown keys naming the key and the allowed ones, converts text with
units (``"120 mm"``, ``"10 GPa"``, ``"5 N/m"``) to SI, and prefixes the classes' own
one-line messages (field, value, allowed range) with the file and the table.

Why no library: pydantic (v2) and attrs/cattrs were weighed. The table classes are
plain frozen dataclasses that validate themselves in ``__post_init__`` (the same
one-line messages for scripts and scene files) and are refactored in parallel by
other work; pydantic would either replace them or validate a second copy of each,
its errors are multi-line lists that would have to be rewritten into the house
one-line form, and it brings a compiled dependency (pydantic-core); cattrs needs attrs
classes. What is needed — annotations, unknown keys, unit text, nesting — is this
module's ~150 lines over ``dataclasses`` and ``typing``.
"""

from __future__ import annotations

import copy
import dataclasses
import types
import typing
from dataclasses import dataclass
from typing import Any

from .errors import InputError
from .units import TEX, quantity


@dataclass(frozen=True)
class Unit:
    """A field's unit: the kind of quantity :func:`fabmd.units.quantity` reads, the SI
    value of the field's own unit (``TEX`` for a field in tex) and words taken as they
    are (``"auto"``)."""

    kind: str
    si_per_unit: float = 1.0
    words: tuple[str, ...] = ()

    def read(self, value: Any, name: str) -> Any:
        """``value`` in the field's unit: text with a unit converted, numbers as given."""
        if isinstance(value, str) and value.strip() in self.words:
            return value
        if not isinstance(value, str):
            return value  # numbers are in the field's unit already; the class checks them
        try:
            si = quantity(value, self.kind, name)
        except InputError as exc:  # name the value as typed, not only its unit
            text = str(exc)
            if text.startswith(f"{name}: "):
                text = f"{name} = {value!r}: {text[len(name) + 2:]}"
            if self.words:
                text += f" (or the word {' / '.join(repr(w) for w in self.words)})"
            raise InputError(text) from None
        return si if self.si_per_unit == 1.0 else si / self.si_per_unit


def unit(kind: str, si_per_unit: float = 1.0, words: tuple[str, ...] = ()) -> dict:
    """Field metadata declaring a unit: ``field(default=0.1e-3, metadata=unit("length"))``."""
    return {"unit": Unit(kind, si_per_unit, words)}


_CONTACT = {"normal_stiffness_pa": "pressure", "within_family_stiffness_pa": "pressure",
            "stiffness_n_per_m": "stiffness"}

#: class name -> field -> kind (or :class:`Unit`) of the fields that carry a unit
UNITS: dict[str, dict[str, str | Unit]] = {
    # tables a scene file owns
    "FibreMaterial": {"modulus_pa": "pressure", "density_kg_m3": "density"},
    "YarnSpec": {"linear_density_tex": Unit("linear_density", TEX), "width_m": "length",
                 "height_m": "length", "spacing_m": "length",
                 "count_per_m": "count_per_length", "filament_diameter_m": "length",
                 "bending_stiffness_nm2": Unit("bending_stiffness", words=("filaments",))},
    "Fabric": {"clearance_m": Unit("length", words=("auto",)),
               "areal_density_kg_m2": "areal_density", "thickness_m": "length",
               "thickness_pressure_pa": "pressure", "lift_m": "length"},
    "ContactModel": _CONTACT,
    "ToolContact": _CONTACT,
    "CompactionLaw": {"modulus_pa": "pressure"},
    "BundleContact": {"area_m2": "area", "diameter_m": "length"},
    # stage tables and their sub-tables
    "TimeStep": {"value_s": "time"},
    "Damping": {"viscous_time_s": "time"},
    "Coupon": {"length_m": "length", "width_m": "length", "edge_zone_m": "length"},
    "DrivenTest": {"damping_time_s": "time", "clamp_length_m": "length",
                   "max_displacement_m": "length"},
    "PictureFrame": {"frame_length_m": "length", "clamp_width_m": "length"},
    "Drape": {"punch_radius_m": "length", "depth_m": "length", "die_clearance_m": "length",
              "holder_force_n": "force", "holder_inner_radius_m": "length",
              "shear_cell_m": "length", "report_depths_m": "length"},
    "Compaction": {"max_pressure_pa": "pressure", "datasheet_pressure_pa": "pressure"},
    "AdaptiveLoading": {"floor_force_n": "force"},
    "Crimp": {"settle_force_n": "force", "loose_height_start_m": "length"},
}
#: fields whose name carries a unit that text cannot give: numbers only (a gain in m/s/N;
#: a dict of widths [m] by family that the build sets, no scene key)
NUMBERS = {"Drape": ("holder_gain_m_s_n",), "Fabric": ("woven_width_m",)}


def unit_of(cls: type, name: str) -> Unit | None:
    """The declared unit of field ``name`` of dataclass ``cls`` (None: a plain value)."""
    for f in dataclasses.fields(cls):
        if f.name == name and "unit" in f.metadata:
            return f.metadata["unit"]
    for base in cls.__mro__:
        kind = UNITS.get(base.__name__, {}).get(name)
        if kind is not None:
            return kind if isinstance(kind, Unit) else Unit(kind)
    return None


def _dataclasses_in(hint) -> tuple[type, ...]:
    """The dataclasses in a type hint (``X``, ``X | None``, ``X | Y``)."""
    if dataclasses.is_dataclass(hint):
        return (hint,)
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        return tuple(a for a in typing.get_args(hint) if dataclasses.is_dataclass(a))
    return ()


def _is_tuple(hint) -> bool:
    args = typing.get_args(hint) if typing.get_origin(hint) in (typing.Union,
                                                                 types.UnionType) else (hint,)
    return any(a is tuple or typing.get_origin(a) is tuple for a in args)


def _default(f: dataclasses.Field):
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return None if f.default is dataclasses.MISSING else f.default


def check_keys(table: dict, allowed, section: str) -> None:
    """Refuse a key not in ``allowed``, naming it and the allowed ones."""
    for key in table:
        if key not in allowed:
            raise InputError(f"[{section}] has no key {key!r} (allowed: {', '.join(allowed)})")


def merged(base: dict, override: dict) -> dict:
    """A new nested table: ``base`` with ``override`` put in, sub-tables merged key by key
    (``{"contact": {"friction": 0.1}}`` changes one key of ``[contact]``); a value that is
    not a table on both sides replaces. Neither input is changed, and the result shares
    no mutable value with them (it is deep-copied)."""
    out = copy.deepcopy(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merged(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _value(cls, f: dataclasses.Field, hint, value, section: str, base):
    """One table value as the field takes it (sub-table built, units read, list -> tuple)."""
    key = f.name
    nested = _dataclasses_in(hint)
    if nested:
        if isinstance(value, dict):
            # keys the sub-table leaves out keep the owner's default (e.g. the trajectory
            # frames a test writes), not the nested class's
            base = base if base is not None else _default(f)
            inherited = {g.name: getattr(base, g.name) for g in dataclasses.fields(base)
                         if g.init} if dataclasses.is_dataclass(base) else {}
            target = type(base) if type(base) in nested else nested[0]
            return build(target, {**inherited, **value}, f"{section}.{key}")
        if value is not None and not isinstance(value, nested):
            raise InputError(f"[{section}] {key} must be a table ([{section}.{key}] or "
                             f"{key} = {{ ... }}), got {value!r}")
        return value
    if hint is bool and not isinstance(value, bool):
        raise InputError(f"[{section}] {key} must be true or false, got {value!r}")
    if hint is str and not isinstance(value, str):
        raise InputError(f"[{section}] {key} must be text, got {value!r}")
    declared = unit_of(cls, key)
    name = f"{section}.{key}"
    if isinstance(value, list) and _is_tuple(hint):
        value = tuple(value)
    if declared is not None:
        if isinstance(value, tuple):
            return tuple(declared.read(v, f"{name}[{i}]") for i, v in enumerate(value))
        return declared.read(value, name)
    return value


def build(cls: type, table: dict | None, section: str, *, where: str | None = None,
          defaults: dict | None = None, keys=None):
    """An instance of dataclass ``cls`` from a scene-file table.

    Args:
        table: the TOML table (None or {} for all defaults).
        section: its name in messages (``"tension"``, ``"yarns.warp"``).
        where: the scene file's name, put in front of every message (None: none).
        defaults: values used where the table gives none (e.g. the scene's contact).
        keys: the keys the table may hold (default: every field of ``cls``).

    Raises:
        InputError: one line naming the file, the table, the key and the value.
    """
    try:
        return _build(cls, table, section, defaults or {}, keys)
    except InputError as exc:
        text = str(exc)
        if where is not None and not text.startswith(f"{where}: "):
            text = f"{where}: {text}"
        raise InputError(text) from None


def _build(cls: type, table, section: str, defaults: dict, keys):
    if table is not None and not isinstance(table, dict):
        raise InputError(f"[{section}] must be a table, got {table!r}")
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    check_keys(table or {}, tuple(keys) if keys is not None else tuple(fields), section)
    hints = typing.get_type_hints(cls)
    kwargs = dict(defaults)
    for key, value in (table or {}).items():
        kwargs[key] = _value(cls, fields[key], hints.get(key), value, section,
                             defaults.get(key))
    try:
        return cls(**kwargs)
    except (InputError, TypeError) as exc:  # TypeError: a value of the wrong shape
        text = str(exc)
        raise InputError(text if text.startswith(f"[{section}") else f"[{section}] {text}") \
            from None
