"""Accuracy presets: the same scene, run faster or more accurately.

A preset changes how the scene is *discretised and loaded*, never what fabric it
describes: virtual fibres per yarn, bead spacing ratio s/d, and the loading
speed of the virtual tests (a factor on every test's ``speed_fraction``). The
choices sit on the run-time/error Pareto front measured by
``benchmarks/accuracy.py`` (see ``benchmarks/RESULTS.md``, "Run time against
error"); the README states the expected error of each.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from .errors import InputError
from .scenefile import Scene


@dataclass(frozen=True)
class Preset:
    """How a preset changes a scene.

    Args:
        n_fibres: virtual fibres per yarn (None: as the scene says).
        spacing_ratio: bead spacing over diameter (None: as the scene says).
        speed_factor: factor on every test's ``speed_fraction``.
    """

    n_fibres: int | None = None
    spacing_ratio: float | None = None
    speed_factor: float = 1.0


PRESETS: dict[str, Preset] = {
    "default": Preset(),
    "fast": Preset(n_fibres=1, spacing_ratio=0.5, speed_factor=2.0),
    "accurate": Preset(n_fibres=19, spacing_ratio=0.5, speed_factor=0.5),
}

#: tests whose scene tables take a speed_fraction
DRIVEN_TABLES = ("tension", "picture_frame", "bias_extension", "periodic_tension",
                 "periodic_shear", "drape")
#: the default speed_fraction of each driven test, when the scene gives none
DEFAULT_SPEEDS = {"tension": 1e-4}


def apply_preset(scene: Scene, name: str) -> Scene:
    """``scene`` as preset ``name`` runs it."""
    if name not in PRESETS:
        raise InputError(f"preset must be one of {', '.join(PRESETS)}, got {name!r}")
    preset = PRESETS[name]
    fabric = scene.fabric
    if preset.n_fibres is not None:
        # YarnSpec keeps both its count and the spacing derived from it; pass one
        specs = {fam: dataclasses.replace(spec, n_fibres=preset.n_fibres,
                                          spacing_m=None if spec.count_per_m else spec.spacing_m)
                 for fam, spec in fabric.specs().items()}
        fabric = dataclasses.replace(fabric, **specs)
    disc = scene.discretisation
    if preset.spacing_ratio is not None:
        disc = dataclasses.replace(disc, spacing_ratio=preset.spacing_ratio)
    protocols = {k: dict(v) for k, v in scene.protocols.items()}
    if preset.speed_factor != 1.0:
        from .pipeline import build_protocol

        for table in DRIVEN_TABLES:
            test = table.replace("_", "-")
            current = protocols.get(table, {}).get("speed_fraction")
            if current is None:
                try:
                    current = build_protocol(test).speed_fraction
                except InputError:  # a test this install does not have
                    continue
            protocols.setdefault(table, {})["speed_fraction"] = current * preset.speed_factor
    return dataclasses.replace(scene, fabric=fabric, discretisation=disc, protocols=protocols,
                               title=f"{scene.title} [{name}]" if name != "default"
                               else scene.title)
