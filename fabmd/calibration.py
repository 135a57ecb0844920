"""Calibrate a scene's crimp to its datasheet (``fabmd calibrate SCENE --out DIR``).

The targets come from the scene: its ``[calibrate]`` table
(:class:`~fabmd.protocols.calibrate.CrimpTargets`) and, where that gives no thickness,
the datasheet's ``[fabric] thickness = "0.5 mm at 4.14 kPa"`` (the thickness under that
pressure). The crimp settings are the scene's ``[crimp]`` (its expansion is the start),
the platens that measure a thickness under pressure the scene's ``[compaction]``. The
search runs the crimp stage repeatedly on the periodic cell
(:func:`fabmd.protocols.calibrate.calibrate`). ``DIR`` then holds:

* ``calibration.json``: the targets and where they came from, every run (strains,
  achieved values, wall time), each knob's samples and verdict, the result;
* ``run-NN/crimp`` (and ``run-NN/compaction``): the trial runs (no figures, no trajectory);
* ``calibrated.toml``: the scene file as given with the found ``[crimp] expansion`` and
  nothing else changed (checked by parsing both) — written when every searched target
  is reached; the input file is never touched;
* ``crimp/``: ``fabmd crimp calibrated.toml --form cell`` run in the same process (figures,
  trajectory), which also shows that the calibrated file reproduces what was found.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from .engine import Engine, mpi
from .errors import CalibrationNotReached, InputError, RunInterrupted
from .loose_height import drawn, loose_heights
from .preflight import check_scene
from .protocols.calibrate import CalibrationResult, calibrate, targets_from_scene
from .protocols.calibrate_knobs import check_targets, default_thickness_families
from .results.folder import abandon_run, begin_run, finish_run, write_json
from .scenefile import Scene, load_scene
from .stages import crimp_stage, periodic_cell, protocol_stage

CALIBRATED = "calibrated.toml"


@dataclass
class Calibration:
    """What ``fabmd calibrate`` found: the search's result, the calibrated scene file
    (None where not written), the final crimp's summary (None where not run)."""

    result: CalibrationResult
    out: Path
    calibrated: Path | None
    final: dict | None
    notes: list[str]


def run_calibration(scene: Scene, out: Path, engine: Engine | None = None,
                    overwrite: bool = False, settings: dict | None = None,
                    preset: str = "default", on_run=None) -> Calibration:
    """Calibrate ``scene``'s crimp expansion to its targets; module docstring.

    Every check runs before LAMMPS starts (scene tables, targets, that the scene file can
    be written back with a new expansion). ``preset``: the one applied to ``scene``, used
    again on ``calibrated.toml`` for the final crimp.

    Raises:
        InputError: bad scene or targets (nothing run, no folder written).
        CalibrationNotReached: a target was missed (``out`` holds ``calibration.json``).
    """
    where = scene.source or "scene"
    check_scene(scene)
    if crimp_stage(scene).pins_crimp:
        raise InputError(f"{where}: [crimp] crimp_by = \"loose_height\" reaches the stated "
                         f"crimp at the weaving tension in the crimp stage itself (fabmd "
                         f"crimp / fabmd test): nothing to calibrate; for other targets "
                         f"take target_crimp_pct and crimp_by out of [crimp]")
    targets, notes = targets_from_scene(scene, settings)
    base = crimp_stage(scene)
    if (base.target_tension is not None and targets.crimp_by == "loose_height"
            and targets.target_tension is None):
        # the crimp's own tension target is the one reached beside the crimp
        targets = dataclasses.replace(targets, target_tension=base.target_tension)
        base = dataclasses.replace(base, target_tension=None)
        notes.append("tension target from [crimp] target_tension")
    if base.target_tension is not None:
        raise InputError(f"{where}: [crimp] target_tension searches the expansion itself: "
                         f"for a calibration give it as [calibrate] target_tension instead")
    if base.target_crimp_pct:
        raise InputError(f"{where}: [crimp] target_crimp_pct derives the expansion itself: "
                         f"for a calibration give the crimp as [calibrate] crimp_pct instead")
    compaction = protocol_stage(scene, "compaction") if targets.at_pressure_pa else None
    text = Path(scene.source).read_text() if scene.source else None
    if text is not None:  # can it be written back? (before anything runs)
        with_expansion(text, {f: 0.0 for f in base.expansion or {"warp": 0}}, where)
    cell = periodic_cell(scene)
    check_targets(cell, targets, base, tuple(targets.thickness_families
                                             or default_thickness_families(cell)), compaction)
    tall, tall_range = _loose_heights(scene, targets, text, where)
    if preset != "default":
        notes.append(f"run with the preset --{preset}: crimp calibrated.toml with it too")
    engine = engine or Engine(progress=False)
    trial_engine = dataclasses.replace(engine, progress=False)
    work = begin_run(out, overwrite=overwrite, prefix="calibration")
    try:
        result = calibrate(cell, targets, base=base, out=work, engine=trial_engine,
                           compaction=compaction, on_run=on_run, notes=notes,
                           cell_for=lambda h: drawn(scene.with_yarn_heights(h)),
                           loose_height_m=tall, loose_height_range=tall_range)
        calibrated = final = None
        if result.controlled_reached and text is not None:
            calibrated = work / CALIBRATED
            new_text = with_expansion(
                with_yarn_heights(text, result.summary.get("loose_height_m") or {}, where),
                result.expansion, where, header=_header(scene, result, preset))
            if mpi.is_root():
                calibrated.write_text(new_text)
            mpi.barrier()
            final = _final_crimp(calibrated, work / "crimp", engine, preset, result)
    except (RunInterrupted, KeyboardInterrupt):
        raise
    except BaseException as exc:
        abandon_run(out, work, exc)
        raise
    finish_run(out, work)
    out = Path(out).resolve()
    found = Calibration(result, out, out / CALIBRATED if calibrated else None, final, notes)
    if not result.reached:
        wrote = (f"; {CALIBRATED} written for the targets the expansions control"
                 if calibrated else "")
        raise CalibrationNotReached(f"calibration of {where} did not reach its targets: "
                                    f"{result.reason} (every run in "
                                    f"{out / 'calibration.json'}{wrote})", run_dir=out)
    return found


def _header(scene: Scene, result: CalibrationResult, preset: str) -> str:
    fams = ", ".join(f"{f} {v:+.5g}" for f, v in sorted(result.expansion.items()))
    run = "" if preset == "default" else f" with --{preset}"
    heights = result.summary.get("loose_height_m") or {}
    tall = "".join(f", [yarns.{f}] height_m {_mm(h)}" for f, h in sorted(heights.items()))
    return (f"# fabmd calibrate{run}: {Path(scene.source).name} with [crimp] expansion "
            f"{fams}{tall} (run {result.best_run} of {len(result.runs)}); nothing else "
            f"changed\n")


def _mm(height_m: float) -> str:
    return f"{1e3 * height_m:.6g} mm"


def _loose_heights(scene: Scene, targets, text: str | None,
                   where: str) -> tuple[dict | None, dict | None]:
    """With ``crimp_by = "loose_height"``: :func:`fabmd.loose_height.loose_heights` of the
    crimp targets' families, after checking (before LAMMPS) that the heights can be
    written back into the file; (None, None) otherwise."""
    if targets.crimp_by != "loose_height":
        return None, None
    h0, ranges = loose_heights(scene, targets.crimp_pct, where)
    if text is not None:
        with_yarn_heights(text, h0, where)
    return h0, ranges


def _final_crimp(calibrated: Path, folder: Path, engine: Engine, preset: str,
                 result: CalibrationResult) -> dict:
    """Crimp the calibrated scene file's cell (figures, trajectory) and add what it gave
    beside what the search found to ``calibration.json``."""
    from .presets import apply_preset

    scene = apply_preset(load_scene(calibrated), preset)
    crimped = crimp_stage(scene).run(periodic_cell(scene), folder, engine=engine)
    s = crimped.summary
    final = {"folder": str(folder), "expansion": s["expansion"],
             "thickness_m": s["crimped"]["thickness_m"],
             "crimp_pct": s["crimped"]["crimp_pct"],
             "yarn_tension_n": {f: v["yarn_n"] for f, v in s["yarn_tension"].items()},
             "quasi_static": s["quasi_static"], "wall_s": s["wall_s"]}
    summary = dict(result.summary, final_crimp=final)
    write_json(result.run_dir / "calibration.json", summary)
    result.summary = summary
    return final


# ---- the scene file with new loose heights and a new [crimp] expansion ------------------
_HEADER = re.compile(r"^\s*\[\s*([A-Za-z0-9_.\s\"']+?)\s*\]\s*(#.*)?$")
_EXPANSION = re.compile(r"^(\s*)expansion\s*=")
_HEIGHT = re.compile(r"^(\s*)(height_m|fibre_volume_fraction)\s*=")


def with_yarn_heights(text: str, heights_m: dict[str, float], where: str = "scene") -> str:
    """``text`` (a scene file) with ``[yarns.<family>] height_m`` set to ``heights_m``
    (a ``fibre_volume_fraction`` there, which would size the height, taken out) and
    nothing else changed: checked by parsing both.

    Raises:
        InputError: a family's yarn table is not a ``[yarns.<family>]`` table of its own.
    """
    if not heights_m:
        return text
    data = tomllib.loads(text)
    lines = text.splitlines(keepends=True)
    wanted = {**data, "yarns": {k: dict(v) for k, v in data.get("yarns", {}).items()}}
    for fam, height in heights_m.items():
        headers = [i for i, line in enumerate(lines) if _HEADER.match(line)
                   and not line.lstrip().startswith("[[")]
        start = next((i for i in headers if _HEADER.match(lines[i]).group(1).replace(
            " ", "") == f"yarns.{fam}"), None)
        if start is None or fam not in wanted["yarns"]:
            raise InputError(f"{where}: cannot write the calibrated loose height of the "
                             f"{fam} yarns: no [yarns.{fam}] table of its own in the file")
        end = next((i for i in headers if i > start), len(lines))
        end = next((i for i in range(start + 1, end) if lines[i].lstrip().startswith("[[")),
                   end)  # an [[yarns.<family>.overrides]] table ends it too
        new_line = f'height_m = "{_mm(height)}"  # fabmd calibrate\n'
        body = lines[start + 1:end]
        at = next((i for i, line in enumerate(body) if _HEIGHT.match(line)
                   and _HEIGHT.match(line).group(2) == "height_m"), None)
        if at is not None:  # in place, with its indentation
            body[at] = _HEIGHT.match(body[at]).group(1) + new_line
        body = [line for i, line in enumerate(body) if i == at or not _HEIGHT.match(line)]
        lines[start + 1:end] = ([] if at is not None else [new_line]) + body
        table = {k: v for k, v in wanted["yarns"][fam].items()
                 if k not in ("height_m", "fibre_volume_fraction")}
        wanted["yarns"][fam] = {**table, "height_m": _mm(height)}
    new = "".join(lines)
    if not _reads_back(new, wanted):
        raise InputError(f"{where}: cannot write the calibrated loose heights into this file "
                         f"without changing something else (a dotted or inline yarn "
                         f"table?); write each [yarns.<family>] as a table of its own")
    return new


def _reads_back(text: str, wanted: dict) -> bool:
    """Whether the edited scene file ``text`` parses to ``wanted`` (nothing else changed)."""
    try:
        return tomllib.loads(text) == wanted
    except tomllib.TOMLDecodeError:
        return False


def _number(value: float) -> str:
    return repr(float(value))


def with_expansion(text: str, expansion: dict[str, float], where: str = "scene",
                   header: str = "") -> str:
    """``text`` (a scene file) with ``[crimp] expansion`` set to ``expansion`` (families
    not named keep theirs) and nothing else changed: the result is parsed and compared
    with the original table by table.

    Raises:
        InputError: the file holds the expansion in a form this cannot edit (say which).
    """
    data = tomllib.loads(text)
    crimp = data.get("crimp", {})
    new_expansion = {**(crimp.get("expansion") or {}), **expansion}
    inline = "{ " + ", ".join(f"{f} = {_number(v)}" for f, v in new_expansion.items()) + " }"
    lines = text.splitlines(keepends=True)
    tables = [(i, _HEADER.match(line).group(1).replace(" ", ""))
              for i, line in enumerate(lines) if _HEADER.match(line)
              and not line.lstrip().startswith("[[")]
    names = [name for _, name in tables]
    comment = "  # fabmd calibrate\n"
    if "crimp.expansion" in names:
        start = next(i for i, name in tables if name == "crimp.expansion")
        end = next((i for i, _ in tables if i > start), len(lines))
        body = [f"{f} = {_number(v)}\n" for f, v in new_expansion.items()]
        lines[start + 1:end] = body + ["\n"]
    elif "crimp" in names:
        start = next(i for i, name in tables if name == "crimp")
        end = next((i for i, _ in tables if i > start), len(lines))
        hits = [i for i in range(start + 1, end) if _EXPANSION.match(lines[i])]
        if hits:
            i = hits[0]
            lines[i] = f"{_EXPANSION.match(lines[i]).group(1)}expansion = {inline}{comment}"
        else:
            lines.insert(start + 1, f"expansion = {inline}{comment}")
    elif "crimp" in data:
        raise InputError(f"{where}: cannot write the calibrated expansion into this file's "
                         f"crimp settings (not a [crimp] table): write them as [crimp]")
    else:
        if lines and not lines[-1].endswith("\n"):
            lines[-1] += "\n"
        lines += ["\n", "[crimp]\n", f"expansion = {inline}{comment}"]
    new = header + "".join(lines)
    wanted = dict(data, crimp=dict(crimp, expansion=new_expansion))
    if not _reads_back(new, wanted):
        raise InputError(f"{where}: cannot write the calibrated [crimp] expansion into this "
                         f"file without changing something else (a dotted or inline form?); "
                         f"write [crimp] expansion = {{ ... }} as one line")
    return new
