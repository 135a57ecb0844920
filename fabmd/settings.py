"""Build protocol objects from scene-file tables (``[crimp]``, ``[tension]``, ...).

:func:`build` maps a table onto a dataclass through the one scene schema
(:func:`fabmd.schema.build`): unknown keys are refused naming the key and the allowed
ones; fields with a declared unit may be given as text with units ("120 mm",
"2 mm/min"); sub-tables build nested settings (``[crimp.quasi_static]``,
``[tension.contact]``, ``[tension.trajectory]``), starting from the field's default (or
the default passed in) for the keys they omit.
"""

from __future__ import annotations

from typing import Any

from . import schema


def build(cls: type, table: dict | None, section: str, **defaults: Any):
    """An instance of dataclass ``cls`` from a scene-file table.

    Args:
        table: the TOML table (None or {} for all defaults).
        section: its name, used in error messages (``"tension"``).
        defaults: values used where the table gives none (e.g. the scene's contact).
    """
    return schema.build(cls, table, section, defaults=defaults)
