"""The loose section's height as what reaches a crimp (``crimp_by = "loose_height"``).

The crimp the crimp stage leaves at a given weaving tension follows the loose section the
cell is drawn with (benchmarks/RESULTS.md "Crimp pinned by the loose height"): so a
family's crimp can be reached by its loose height h0·(1 + s) (width, tex and count kept;
the cell drawn again and the contact's law derived again for the new virtual fibre) while
the expansion reaches the tension. ``fabmd calibrate`` does it for a ``[calibrate]``
table (:mod:`fabmd.calibration`); :func:`pin_crimp` does it for the crimp stage of a scene
that states ``[crimp] target_crimp_pct`` and ``target_tension`` with ``crimp_by =
"loose_height"``, so that every discretisation (``--fast``, default, ``--accurate``)
crimps to the fabric's stated crimp and tension, not to the crimp its own virtual fibres
happen to leave (RESULTS "Presets against the reference").
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path
from types import SimpleNamespace

from .engine import Engine, mpi
from .errors import CalibrationNotReached, InputError
from .protocols.calibrate import CrimpTargets, calibrate
from .protocols.calibrate_knobs import (
    LOOSE_HEIGHT_RANGE,
    check_targets,
    default_thickness_families,
    height_start,
)
from .results.folder import write_json
from .scenefile import Scene
from .stages import crimp_stage, periodic_cell, protocol_stage


def loose_heights(scene: Scene, families, where: str) -> tuple[dict, dict]:
    """The scene's loose section height per family of ``families`` [m] and the range of
    relative changes (within :data:`~fabmd.protocols.calibrate_knobs.LOOSE_HEIGHT_RANGE`,
    on a 0.05 grid) at which the section can be drawn; checked before LAMMPS.

    Raises:
        InputError: a family with overrides, or one whose section cannot be drawn lower
            and higher than it is.
    """
    specs = scene.fabric.specs()
    h0 = {fam: float(specs[fam].height_m) for fam in families if fam in specs}
    scene.with_yarn_heights(h0)  # overrides are refused here
    ranges = {}
    for fam, h in h0.items():
        lo, hi = LOOSE_HEIGHT_RANGE
        steps = [round(lo + 0.05 * k, 2) for k in range(int(round((hi - lo) / 0.05)) + 1)]
        can = [s for s in steps if drawable(scene, {fam: h * (1 + s)})]
        if not can or can[0] > 0 or can[-1] < 0:
            raise InputError(f"{where}: the {fam} yarns' loose section cannot be drawn "
                             f"much lower or higher than {1e3 * h:.6g} mm (tried {lo:+.2f} "
                             f"… {hi:+.2f} of it), so the loose height cannot reach a crimp")
        ranges[fam] = (can[0], can[-1])
    return h0, ranges


def drawn(scene: Scene):
    """The loose periodic cell of ``scene``, its crimp's contact and its compaction (for
    the contact of the platens' run): what one loose-height trial needs."""
    return (periodic_cell(scene), crimp_stage(scene).contact,
            protocol_stage(scene, "compaction"))


def drawable(scene: Scene, heights_m: dict[str, float]) -> bool:
    """Whether the fabric can be drawn with these loose heights (the section holds the
    filaments below the packing limit, a racetrack is no taller than wide...)."""
    try:
        scene.with_yarn_heights(heights_m)
    except InputError:
        return False
    return True


#: the crimp stage's file naming the loose heights and expansion its crimp was reached with
PINNED = "pinned_crimp.json"
_PIN_KEYS = ("target_crimp_pct", "crimp_by", "crimp_tolerance_pct", "loose_height_start_m")


def pin_crimp(scene: Scene, out: Path, engine: Engine | None = None,
              say=None) -> tuple[Scene, dict]:
    """The scene whose crimp stage reaches ``[crimp] target_crimp_pct`` and
    ``target_tension`` together (``crimp_by = "loose_height"``), and what was found.

    The loose section's height of each family is searched for its crimp while each run's
    crimp searches the expansion for the tension (:func:`fabmd.protocols.calibrate
    .calibrate`, as ``fabmd calibrate`` with ``crimp_by = "loose_height"``; trial runs and
    ``calibration.json`` in ``out``). The scene returned has those heights (its contact
    derived again for the new virtual fibre) and ``[crimp]`` with the expansion found as
    its start and the target tension, without the crimp targets: crimp it, and run every
    later stage with it. ``PINNED`` in ``out`` records the result
    (:func:`pinned_scene` rebuilds the scene from it). A scene without ``crimp_by =
    "loose_height"`` comes back unchanged, with {}. ``say``: called with one line per
    run (default: to stderr on rank 0 where ``engine.progress``).

    Raises:
        CalibrationNotReached: a crimp or the tension was not reached within the
            tolerances (``out`` holds ``calibration.json``: every run, the closest).
    """
    crimp = crimp_stage(scene)
    if not crimp.pins_crimp:
        return scene, {}
    where = scene.source or "scene"
    plain = without_crimp_targets(scene)
    tall, tall_range = loose_heights(plain, crimp.target_crimp_pct, where)
    targets = CrimpTargets(crimp_pct=dict(crimp.target_crimp_pct), crimp_by="loose_height",
                           crimp_tolerance_pct=crimp.crimp_tolerance_pct,
                           target_tension=crimp.target_tension, datasheet=False,
                           tied_heights=alike_families(scene, crimp.target_crimp_pct,
                                                       crimp.target_tension),
                           loose_height_start=start_strains(plain, crimp, tall, tall_range,
                                                            where))
    base = crimp_stage(plain)
    base = dataclasses.replace(base, target_tension=None)
    cell = periodic_cell(plain)
    check_targets(cell, targets, base, default_thickness_families(cell), None)
    engine = engine or Engine()
    if say is None and engine.progress and mpi.is_root():  # beside the progress lines
        def say(line: str) -> None:
            print(line, file=sys.stderr, flush=True)
    if say is not None:
        state = (" once released off the loom, woven" if crimp.release_tension else "")
        start = crimp.start_heights_m()
        start = f" from {_heights_text(start)}" if start else ""
        say(f"loose height: searching the loose sections of {', '.join(targets.crimp_pct)}"
            f"{start} for crimp {_targets_text(crimp.target_crimp_pct)}{state} at the "
            f"weaving tension (a crimp run each, at most {targets.max_runs})")
    result = calibrate(cell, targets, base=base, out=out,
                       engine=dataclasses.replace(engine, progress=False), overwrite=True,
                       on_run=None if say is None else lambda r: say(_run_line(r)),
                       notes=[f"[crimp] crimp_by = \"loose_height\" of {where}"],
                       cell_for=lambda h: drawn(plain.with_yarn_heights(h)),
                       loose_height_m=tall, loose_height_range=tall_range)
    if not result.reached:
        raise CalibrationNotReached(
            f"{where}: [crimp] crimp_by = \"loose_height\" did not reach the crimp and the "
            f"weaving tension together: {result.reason} (every run in "
            f"{Path(out) / 'calibration.json'})", run_dir=Path(out))
    found = {"loose_height_m": result.summary.get("loose_height_m") or {},
             "expansion": dict(result.expansion),
             "target_crimp_pct": dict(crimp.target_crimp_pct),
             "achieved": result.achieved, "runs": len(result.runs),
             "calibration": str(Path(out).resolve())}
    if mpi.is_root():
        write_json(Path(out) / PINNED, found)
    return pinned_scene(scene, found), found


def start_strains(scene: Scene, crimp, tall: dict, ranges: dict | None, where: str) -> dict:
    """``[crimp] loose_height_start_m`` as the relative change of each family's loose
    height h = h0·(1 + s) (``tall``: h0 per family), checked before LAMMPS: within
    ``ranges``, the range the section can be drawn at (:func:`loose_heights`; None:
    :data:`LOOSE_HEIGHT_RANGE`), the cell drawable there.

    Raises:
        InputError: a start outside that range, or one the cell cannot be drawn at.
    """
    start_m = crimp.start_heights_m()
    strains = {}
    for fam, h in start_m.items():
        if fam not in tall:  # a family the fabric does not have: refused with the targets
            continue
        h0 = tall[fam]
        s = h / h0 - 1
        lo, hi = LOOSE_HEIGHT_RANGE if ranges is None else ranges[fam]
        if not lo - 1e-9 <= s <= hi + 1e-9:
            raise InputError(f"{where}: crimp.loose_height_start_m.{fam} = {1e3 * h:.6g} mm "
                             f"is outside the heights the search may draw the {fam} yarns "
                             f"at, {1e3 * h0 * (1 + lo):.6g} … {1e3 * h0 * (1 + hi):.6g} mm "
                             f"(the yarns' height_m {1e3 * h0:.6g} mm × {1 + lo:g} … "
                             f"{1 + hi:g})")
        strains[fam] = s
    if strains and not drawable(scene, {f: tall[f] * (1 + s) for f, s in strains.items()}):
        raise InputError(f"{where}: the cell cannot be drawn with crimp.loose_height_start_m "
                         f"({_heights_text(start_m)})")
    return strains


def check_start(scene: Scene) -> None:
    """``[crimp] loose_height_start_m`` of ``scene`` checked against the fabric before any
    folder is made (:func:`fabmd.preflight.check_scene`): a height the search may draw,
    one height for families drawn alike (nothing where the scene gives no start).

    Raises:
        InputError: as :func:`start_strains`, or a tied group given two heights.
    """
    crimp = crimp_stage(scene)
    if not crimp.pins_crimp or not crimp.start_heights_m():
        return
    where = scene.source or "scene"
    plain = without_crimp_targets(scene)
    specs = plain.fabric.specs()
    tall = {fam: float(specs[fam].height_m) for fam in crimp.start_heights_m() if fam in specs}
    # the range only (the grid of drawable heights is the search's, 40 drawings)
    targets = SimpleNamespace(loose_height_start=start_strains(plain, crimp, tall, None,
                                                               where))
    for group in alike_families(scene, crimp.target_crimp_pct, crimp.target_tension):
        height_start(targets, group)


def _heights_text(heights_m: dict) -> str:
    return ", ".join(f"{fam} {1e3 * h:.6g} mm" for fam, h in heights_m.items())


def alike_families(scene: Scene, crimp_pct: dict, tension) -> tuple[tuple[str, ...], ...]:
    """Groups of the families drawn alike (every yarn input the same but the name) with one
    crimp and one tension target: each group's loose height moves as one, so that a
    balanced weave stays balanced (two free heights part: the example's 7-fibre cell ended
    at 0.56 and 0.51 mm for 1.53 / 1.46 %, measured); a family unlike the others (a 3D
    fabric's binders) keeps its own. () where no two are alike."""
    specs = scene.fabric.specs()
    tensions = tension if isinstance(tension, dict) else {f: tension for f in crimp_pct}

    def drawing(fam: str):
        return (dataclasses.replace(specs[fam], name=None), float(crimp_pct[fam]),
                str(tensions.get(fam)))

    groups: list[list[str]] = []
    for fam in (f for f in crimp_pct if f in specs):
        group = next((g for g in groups if drawing(g[0]) == drawing(fam)), None)
        if group is None:
            groups.append([fam])
        else:
            group.append(fam)
    return tuple(tuple(g) for g in groups if len(g) > 1)


def _targets_text(crimp_pct: dict) -> str:
    return " / ".join(f"{fam} {value:g} %" for fam, value in crimp_pct.items())


def _run_line(record: dict) -> str:
    """One search run in a line: heights, crimp and tension reached, wall time."""
    heights = " / ".join(f"{1e3 * h:.3f}" for h in (record.get("loose_height_m") or {}).values())
    got = ", ".join(f"{key.replace(':', ' ')} {value:.3f} {'%' if key.startswith('crimp') else 'N'}"
                    for key, value in (record.get("achieved") or {}).items())
    return (f"  loose height run {record.get('run')}: heights {heights} mm: {got} "
            f"({record.get('wall_s', 0):.0f} s)")


def pinned_scene(scene: Scene, found: dict) -> Scene:
    """``scene`` with the loose heights and expansion :func:`pin_crimp` found (``found``,
    or the ``PINNED`` file of a crimp folder read back), its crimp targets taken out."""
    plain = without_crimp_targets(scene)
    pinned = plain.with_yarn_heights(found["loose_height_m"])
    crimp = {**pinned.protocols["crimp"], "expansion": dict(found["expansion"])}
    return dataclasses.replace(pinned, protocols={**pinned.protocols, "crimp": crimp})


def without_crimp_targets(scene: Scene) -> Scene:
    """``scene`` whose crimp stage keeps its expansion and target tension but no crimp
    targets (the drawn loose section as it is)."""
    table = {k: v for k, v in (scene.protocols.get("crimp") or {}).items()
             if k not in _PIN_KEYS}
    return dataclasses.replace(scene, protocols={**scene.protocols, "crimp": table})
