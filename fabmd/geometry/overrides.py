"""Per-yarn or per-layer yarn specs within a family.

A :class:`YarnOverride` gives some yarns of a family another
:class:`~fabmd.geometry.fabric.YarnSpec` (heavier tex, other width or height, other
filaments): one heavier warp yarn in a 2D weave, heavier stuffers in the middle
layers of a 3D fabric. Which yarns:

* ``yarns``: positions in the unit cell along the family's spacing, from 1 — in 2D
  warp *i* / weft *j* (the names ``warp-i``, ``weft-j`` of a one-cell tile); in 3D
  the dent of a stuffer or binder, the column of a weft.
* ``layers`` (3D only): for stuffers the warp gap (as in ``warp_gaps``, 0 = above the
  top weft layer), for wefts the weft layer from 1 at the top (``weft-cC-lK``).

Both given: the yarns in those positions *and* layers; one omitted: all of it.
Every copy of the unit cell repeats the override. Later overrides win where two
match. Scene files write them as ``[[yarns.<family>.overrides]]`` tables that hold
``yarns`` and/or ``layers`` plus any ``[yarns.<family>]`` key to change (the rest is
taken from the family's table).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import InputError
from .yarn_spec import YarnSpec

#: families an override may name, and whether it may select by layer
OVERRIDE_LAYERS = {"warp": True, "weft": True, "binder": False}


def _indices(field: str, value, low: int) -> tuple[int, ...]:
    if isinstance(value, int) and not isinstance(value, bool):
        value = [value]
    if not isinstance(value, list | tuple) or not all(
            isinstance(v, int) and not isinstance(v, bool) and v >= low for v in value):
        raise InputError(f"{field} must be a list of integers >= {low}, got {value!r}")
    return tuple(sorted(set(value)))


@dataclass(frozen=True)
class YarnOverride:
    """Another yarn spec for some yarns of a family (see the module docstring).

    Args:
        family: ``"warp"``, ``"weft"`` or ``"binder"``.
        spec: the :class:`~fabmd.geometry.fabric.YarnSpec` of those yarns (its
            spacing, if given, must be the family's).
        yarns: positions in the unit cell, from 1 (empty: every position).
        layers: 3D only — warp gaps (stuffers) or weft layers from 1 (empty: all).
    """

    family: str
    spec: object
    yarns: tuple = ()
    layers: tuple = ()

    def __post_init__(self):
        if self.family not in OVERRIDE_LAYERS:
            raise InputError(f"yarn override family must be one of "
                             f"{', '.join(OVERRIDE_LAYERS)}, got {self.family!r}")
        where = f"yarns.{self.family}.overrides"
        if not isinstance(self.spec, YarnSpec):
            raise InputError(f"{where}: spec must be a YarnSpec, got {self.spec!r}")
        object.__setattr__(self, "yarns", _indices(f"{where}.yarns", self.yarns, 1))
        low = 1 if self.family == "weft" else 0
        object.__setattr__(self, "layers", _indices(f"{where}.layers", self.layers, low))
        if self.layers and not OVERRIDE_LAYERS[self.family]:
            raise InputError(f"{where}: binders are chosen by yarns (their dent), not by "
                             f"layers")
        if not self.yarns and not self.layers:
            raise InputError(f"{where}: give yarns (positions in the unit cell, from 1) "
                             f"and/or layers (3D) that take this spec")

    def matches(self, family: str, position: int, layer: int | None) -> bool:
        """Whether the yarn of ``family`` at unit-cell ``position`` (from 1) and ``layer``
        takes this spec."""
        return (family == self.family and (not self.yarns or position in self.yarns)
                and (not self.layers or layer in self.layers))
