"""Accuracy presets: the same scene, run faster or more accurately.

A preset changes how the scene is *discretised and loaded*, never what fabric it
describes: virtual fibres per yarn, bead spacing ratio s/d, and the loading
speed of the virtual tests (a factor on every test's ``speed_fraction``). A scene that
states its crimp (``[crimp] crimp_by = "loose_height"``) is crimped to it by every preset
but ``--fast``, whose one-fibre yarns cannot reach it (:attr:`Preset.pin_crimp`).

Measured on the shipped plain weave as it states its crimp (1.5 % at 1 cN/tex;
``benchmarks/presets.py``, ``benchmarks/RESULTS.md`` "Presets against the reference",
2026-12-06), signed errors against a reference of 19 fibres, s/d 0.5, half speed —
tension: force at 4 / 5 / 6 % (3 × 1-cell coupon, past its toe); picture frame
(2 × 2 cells): normalised force at 10 / 20 / 30 / 40°, locking angle:

========  ======  ====  =====  ========  =================  ===========================  =======
preset    fibres  s/d   speed  run time  tension            picture frame                locking
========  ======  ====  =====  ========  =================  ===========================  =======
fast      1       0.25  × 1    0.08×     −99 / −98 / −86 %  +278 / +757 / +593 / +328 %  +0.3°
default   7       0.5   × 1    1×        +13 / +10 / +8 %   −26 / +0.4 / +3.7 / +10 %    −1.8°
accurate  19      0.5   × 1    6.6×      0 / 0 / 0 %        +0.5 / +4.2 / +8.8 / +0.1 %  −1.6°
========  ======  ====  =====  ========  =================  ===========================  =======

The reference is not converged in s/d (RESULTS "Where the plain weave's convergence
stands"), so these are distances to the reference, not to a converged model. Measured
before the crimp stopped only at rest (RESULTS "The crimp stopped before the fabric was at
rest"): each state's weaving tension fell to about a third as its test began; not
re-measured since. The force
in the slack toe of tension depends on the loading speed and is not in these numbers.
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
        direction: -1: the discretisation is applied only where it is cheaper than the
            scene's, +1: only where it is finer, 0: always. Cost per unit of fabric and time
            grows as (fibres per yarn / spacing ratio)² (beads ∝ n^1.5/s, time step ∝
            s/√n), so a scene already coarser than ``--fast`` (the drape example: one
            fibre, s/d 0.9) keeps its own.
        pin_crimp: keep a scene's ``[crimp] crimp_by = "loose_height"`` (the loose
            sections searched for the stated crimp: a crimp run per try). False: crimp the
            drawn sections at the weaving tension instead — one-fibre yarns cannot reach
            the example's 1.5 % (2.6 % at the lowest loose height allowed), so ``--fast``,
            a set-up check, does not search.
    """

    n_fibres: int | None = None
    spacing_ratio: float | None = None
    speed_factor: float = 1.0
    direction: int = 0
    pin_crimp: bool = True


PRESETS: dict[str, Preset] = {
    "default": Preset(),
    "fast": Preset(n_fibres=1, spacing_ratio=0.25, speed_factor=1.0, direction=-1,
                   pin_crimp=False),
    "accurate": Preset(n_fibres=19, spacing_ratio=0.5, speed_factor=1.0, direction=+1),
}

#: tests whose scene tables take a speed_fraction
DRIVEN_TABLES = ("tension", "picture_frame", "bias_extension", "periodic_tension",
                 "periodic_shear", "drape")


def resolution(n_fibres: int, spacing_ratio: float) -> float:
    """Fibres per yarn over spacing ratio: cost per unit of fabric and time ∝ its square."""
    return n_fibres / spacing_ratio


def _moves(scene: Scene, preset: Preset) -> bool:
    """Does the preset move the scene's discretisation the way it is meant to?"""
    n_scene = max(spec.n_fibres for spec in scene.fabric.specs().values())
    s_scene = scene.discretisation.spacing_ratio
    now = resolution(n_scene, s_scene)
    then = resolution(preset.n_fibres or n_scene, preset.spacing_ratio or s_scene)
    return then * preset.direction > now * preset.direction


def speed_fraction(scene: Scene, table: str) -> float | None:
    """The loading speed test ``table`` (``"tension"``, ``"picture_frame"``, ...) runs
    ``scene`` at: its ``speed_fraction`` there, else the test's default (None where this
    install has no such test)."""
    current = scene.protocols.get(table, {}).get("speed_fraction")
    if current is not None:
        return float(current)
    from .pipeline import build_protocol

    try:
        return float(build_protocol(table.replace("_", "-")).speed_fraction)
    except InputError:
        return None


def apply_preset(scene: Scene, name: str) -> Scene:
    """``scene`` as preset ``name`` runs it."""
    if name not in PRESETS:
        raise InputError(f"preset must be one of {', '.join(PRESETS)}, got {name!r}")
    preset = PRESETS[name]
    if preset.direction and not _moves(scene, preset):
        preset = dataclasses.replace(preset, n_fibres=None, spacing_ratio=None)
    # the contact's laws follow the new virtual fibre
    scene = scene.rediscretised(preset.n_fibres, preset.spacing_ratio)
    protocols = {k: dict(v) for k, v in scene.protocols.items()}
    if preset.speed_factor != 1.0:
        for table in DRIVEN_TABLES:
            current = speed_fraction(scene, table)
            if current is None:  # a test this install does not have
                continue
            protocols.setdefault(table, {})["speed_fraction"] = current * preset.speed_factor
    title = f"{scene.title} [{name}]" if name != "default" else scene.title
    scene = dataclasses.replace(scene, protocols=protocols, title=title)
    if not preset.pin_crimp:
        from .loose_height import without_crimp_targets

        scene = without_crimp_targets(scene)
    return scene
