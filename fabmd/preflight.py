"""Checks a scene must pass before any stage starts (no LAMMPS started, no folder written).

:func:`check_scene` validates every stage table of a scene file (``[crimp]`` and the
test tables, their ``coupon`` sub-tables) and refuses a table fabmd does not read.
:func:`check_test` runs, for one test, every size check that can be decided from the
scene alone — coupon against the fabric, picture-frame squareness, punch against the
blank, clamps against the coupon, coupon aspect — with messages that name the scene file,
the table and the field, and give the fix in scene-file terms. The protocols keep their
own checks on the relaxed coupon (the crimp may change a size slightly); these catch what
is wrong in the description before hours are spent on the stages before it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import InputError

#: longest side / shortest side a coupon may have
MAX_ASPECT = 20.0
#: yarn spacings a coupon side must hold at least
MIN_SPACINGS = 2.0


def where(scene) -> str:
    """The scene's name in messages: its file, or ``scene`` when built in Python."""
    return scene.source or "scene"


def _in_scene(scene, message: str) -> InputError:
    text = str(message)
    prefix = f"{where(scene)}: "
    return InputError(text if text.startswith(prefix) else prefix + text)


def known_tables() -> tuple[str, ...]:
    """Stage tables a scene file may hold: ``crimp``, ``calibrate`` and one per test."""
    from .stages import TESTS, section

    return ("crimp", "calibrate", *(section(t) for t in TESTS))


@dataclass(frozen=True)
class TestPlan:
    """A test's validated settings: its protocol, its coupon (None: the periodic cell
    itself) and the coupon's source (``cell`` or ``fabric``)."""

    protocol: object
    coupon: object | None
    source: str


def plan_test(scene, test: str) -> TestPlan:
    """Validate one test's tables (protocol and coupon); errors name the scene file."""
    from .stages import TESTS, coupon_stage, protocol_stage, section

    try:
        if test not in TESTS:
            raise InputError(f"test must be one of {', '.join(sorted(TESTS))}, got {test!r}")
        table = scene.protocols.get(section(test), {})
        protocol = protocol_stage(scene, test)
        if TESTS[test].coupon is None:
            if table.get("coupon") is not None:
                raise InputError(f"[{section(test)}] takes the crimped periodic cell itself: "
                                 f"remove its coupon table")
            return TestPlan(protocol, None, "cell")
        coupon, source = coupon_stage(scene, test)
        return TestPlan(protocol, coupon, source)
    except InputError as exc:
        raise _in_scene(scene, exc) from None


def check_scene(scene) -> None:
    """Every stage table of the scene is one fabmd reads and is well formed.

    Raises:
        InputError: naming the scene file, the table and the key or value.
    """
    from .stages import TESTS, crimp_stage, section

    known = known_tables()
    for name in scene.protocols:
        if name not in known:
            raise _in_scene(scene, f"[{name}] is not a table fabmd reads (stage tables: "
                                   f"{', '.join('[' + k + ']' for k in known)}); check its "
                                   f"spelling")
    try:
        crimp_stage(scene)
    except InputError as exc:
        raise _in_scene(scene, exc) from None
    from .loose_height import check_start

    check_start(scene)  # where a loose-height search starts: a height it may draw
    if "calibrate" in scene.protocols:  # fabmd calibrate's targets
        from .protocols.calibrate import targets_from_scene

        targets_from_scene(scene)
    for test in TESTS:
        if section(test) in scene.protocols:
            check_test(scene, test, plan_test(scene, test))


def _mm(value_m: float) -> str:
    return f"{1e3 * value_m:.4g} mm"


def check_test(scene, test: str, plan: TestPlan) -> None:
    """Every size check of ``test`` that the scene decides, before any stage runs.

    Raises:
        InputError: what does not fit and which scene-file field to change.
    """
    from .stages import section

    sec = section(test)
    coupon = plan.coupon
    if coupon is None:
        return
    fabric = scene.fabric
    length, width = coupon.length_m, coupon.width_m
    a = math.radians(coupon.angle_deg)
    span_x = abs(length * math.cos(a)) + abs(width * math.sin(a))
    span_y = abs(length * math.sin(a)) + abs(width * math.cos(a))
    size = f"{_mm(length)} x {_mm(width)}"
    fail = lambda text: _in_scene(scene, text)  # noqa: E731
    # a sliver holds no woven structure: the test would run for long and mean nothing
    aspect = max(length, width) / min(length, width)
    if aspect > MAX_ASPECT:
        raise fail(f"[{sec}.coupon] {size} is {aspect:.0f}:1, longer than {MAX_ASPECT:g}:1; "
                   f"set length_m and width_m (or cells) closer to each other")
    spacing = max(fabric.spacing("warp"), fabric.spacing("weft"))
    if min(length, width) < MIN_SPACINGS * spacing * (1 - 1e-9):
        raise fail(f"[{sec}.coupon] {size} holds fewer than {MIN_SPACINGS:g} yarn spacings "
                   f"({_mm(spacing)} each) across its "
                   f"{'width' if width <= length else 'length'}; set "
                   f"{'width_m' if width <= length else 'length_m'} >= "
                   f"{_mm(MIN_SPACINGS * spacing)}")
    if plan.source == "fabric" and not fabric.periodic:
        have = fabric.size_m
        need = (span_x + 2 * coupon.edge_zone_m, span_y + 2 * coupon.edge_zone_m)
        if need[0] > have[0] * (1 + 1e-9) or need[1] > have[1] * (1 + 1e-9):
            cell = fabric.unit_cell_m
            tiles = [max(t, math.ceil(n / c))
                     for t, n, c in zip(fabric.tiling, need, cell, strict=True)]
            raise fail(f"[{sec}.coupon] {size} at {coupon.angle_deg:g} deg with edge_zone_m "
                       f"{_mm(coupon.edge_zone_m)} needs {_mm(need[0])} x {_mm(need[1])} of "
                       f"fabric, but [fabric] tiling = {list(fabric.tiling)} gives "
                       f"{_mm(have[0])} x {_mm(have[1])}; set [fabric] tiling = {tiles}, cut "
                       f"a smaller coupon, or set source = \"cell\"")
    check = _CHECKS.get(test)
    if check is not None:
        check(plan.protocol, coupon, sec, fail, fabric)


def _tension(protocol, coupon, sec, fail, fabric) -> None:
    length = coupon.length_m
    clamp = protocol.clamp_length_m if protocol.clamp_length_m is not None else 0.1 * length
    if 2 * clamp >= 0.8 * length:
        raise fail(f"[{sec}] clamp_length_m = {_mm(clamp)} leaves no gauge length on the "
                   f"{_mm(length)} coupon; set clamp_length_m <= {_mm(0.4 * length)} or a "
                   f"longer [{sec}.coupon] length_m")


def _bias_extension(protocol, coupon, sec, fail, fabric) -> None:
    length, width = coupon.length_m, coupon.width_m
    clamp = protocol.clamp_length_m if protocol.clamp_length_m is not None else 0.1 * length
    _tension(protocol, coupon, sec, fail, fabric)
    free = length - 2 * clamp
    if free < 2 * width * (1 - 1e-9):
        raise fail(f"[{sec}] needs a free length between the clamps of at least twice the "
                   f"width: [{sec}.coupon] length_m = {_mm(length)} less two clamps of "
                   f"{_mm(clamp)} leaves {_mm(free)} for a width of {_mm(width)}; set "
                   f"length_m >= {_mm(2 * width + 2 * clamp)} or a smaller width_m")


def _picture_frame(protocol, coupon, sec, fail, fabric) -> None:
    length, width = coupon.length_m, coupon.width_m
    if abs(length - width) > 0.1 * max(length, width):
        raise fail(f"[{sec}] needs a square coupon, got [{sec}.coupon] {_mm(length)} x "
                   f"{_mm(width)}; set length_m = width_m (with cells = [nx, ny]: nx x "
                   f"{_mm(fabric.unit_cell_m[0])} = ny x {_mm(fabric.unit_cell_m[1])})")
    side = 0.5 * (length + width)
    clamp = protocol.clamp_width_m
    if clamp is not None and clamp >= 0.35 * side:
        raise fail(f"[{sec}] clamp_width_m = {_mm(clamp)} leaves too little free fabric on a "
                   f"{_mm(side)} coupon; set clamp_width_m <= {_mm(0.35 * side)}")
    held = protocol.clamp_yarns
    for fam in ("warp", "weft") if held is not None else ():
        yarns = int(round(side / fabric.spacing(fam)))  # whole-yarn clamps leave 2 free
        if yarns < 2 * int(held) + 2:
            raise fail(f"[{sec}] clamp_yarns = {int(held)} holds {2 * int(held)} of the "
                       f"{yarns} {fam} yarns of a {_mm(side)} coupon and leaves fewer than 2 "
                       f"free; set clamp_yarns <= {max(yarns // 2 - 1, 0)} or a larger coupon")


def _drape(protocol, coupon, sec, fail, fabric) -> None:
    # the blank must reach past the holder's opening by a yarn spacing (Drape.blank)
    side = min(coupon.length_m, coupon.width_m)
    spacing = max(fabric.spacing("warp"), fabric.spacing("weft"))
    holder = protocol.holder_radius_m
    need = 2 * (holder + spacing)
    if side < need * (1 - 1e-9):
        raise fail(f"[{sec}] the blank holder's opening (radius {_mm(holder)}: "
                   f"holder_inner_radius_m, or punch_radius_m {_mm(protocol.punch_radius_m)} "
                   f"+ die_clearance_m {_mm(protocol.die_clearance_m)}) needs a blank at least "
                   f"{_mm(need)} wide; set [{sec}.coupon] length_m and width_m >= {_mm(need)} or a "
                   f"smaller punch_radius_m")
    _drape_clearance(protocol, sec, fail, fabric)


def _drape_clearance(protocol, sec, fail, fabric) -> None:
    # the fabric must pass between the punch and the die edge at full depth (Drape.blank);
    # the gap shrinks as the fabric thickens, so judging with a thickness no fabric is
    # thinner than (one yarn's height) refuses only what the later check refuses too
    thin = min(spec.height_m for spec in fabric.specs().values())
    r, depth = protocol.punch_radius_m, protocol.depth_m
    gap = math.hypot(protocol.die_radius_m, thin + r - depth) - r
    if gap < thin:
        raise fail(f"[{sec}] at depth_m = {_mm(depth)} the punch passes {_mm(gap)} from the "
                   f"die edge, less than one yarn's height ({_mm(thin)}): raise "
                   f"die_clearance_m (now {_mm(protocol.die_clearance_m)}) or lower depth_m")


_CHECKS = {"tension": _tension, "bias-extension": _bias_extension,
           "picture-frame": _picture_frame, "drape": _drape}
