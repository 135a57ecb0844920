"""JSON-able descriptions of scene objects (written into ``scene.json`` and ``BeadModel.info``)."""

from __future__ import annotations

import dataclasses
import enum
import math
from pathlib import Path

import numpy as np


def scene_dict(obj) -> dict:
    """A resolved, JSON-able description of a scene object (dataclasses, enums, paths)."""
    def convert(value):
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            out = {"type": type(value).__name__}
            out.update({f.name: convert(getattr(value, f.name))
                        for f in dataclasses.fields(value)})
            return out
        if isinstance(value, enum.Enum):
            return value.value
        if isinstance(value, dict):
            return {str(k): convert(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [convert(v) for v in value]
        if isinstance(value, Path):
            return str(value)
        if isinstance(value, np.generic):
            return value.item()
        if isinstance(value, float) and not math.isfinite(value):
            return str(value)
        return value
    return convert(obj)
