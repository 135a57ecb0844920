"""What a scene file runs: loose fabric → crimp → coupon → virtual test.

A results folder of ``fabmd test NAME SCENE.toml --out DIR`` holds one folder
per stage::

    DIR/loose_height/  with ``[crimp] crimp_by = "loose_height"``: the search of the loose
                  sections that reach the stated crimp at the weaving tension
                  (:func:`fabmd.loose_height.pin_crimp`; ``pinned_crimp.json``)
    DIR/crimp/    the as-woven state (crimped.data + crimped.json, sections.png, ...); with
                  ``[crimp] release_tension`` its ``release/`` holds the cell released off
                  the loom (released.data), which the later stages start from
    DIR/release/  only with ``--crimped`` of a folder crimped without the release that the
                  scene asks for: that cell released here
    DIR/coupon/   the coupon cut (or tiled) from it and relaxed free (coupon.data)
    DIR/NAME/     the test: curve.csv, summary.json, curve.png, the LAMMPS run
    DIR/summary.json   the stages' key results

Coupons are tiled from the crimped *periodic unit cell* of the scene's fabric by
default (cheap, no edge zone); ``[NAME.coupon] source = "fabric"`` cuts them from
the crimped fabric as described instead (its edge zone excluded).
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

from .engine import Engine, interrupt, mpi
from .engine.checkpoint import has_checkpoint
from .errors import InputError, NotQuasiStatic, RunInterrupted
from .loose_height import PINNED, pin_crimp, pinned_scene
from .preflight import check_scene, check_test, plan_test
from .protocols.coupon import CouponResult, load_coupon
from .protocols.crimp import CrimpResult, has_release, load_crimped
from .protocols.release import load_released
from .results.folder import (
    MARKER,
    PARTIAL,
    abandon_run,
    begin_run,
    finish_run,
    is_finished,
    prepare_run_folder,
    sibling,
    write_json,
)
from .scenefile import Scene

# the stage builders live in fabmd.stages (below preflight); their names stay importable here
from .stages import (  # noqa: F401
    TESTS,
    TestKind,
    build_protocol,
    coupon_stage,
    crimp_stage,
    periodic_cell,
    protocol_stage,
    section,
)

#: the folder of a test run where the loose heights are searched (crimp_by = "loose_height")
LOOSE_HEIGHT = "loose_height"


def run_crimp(scene: Scene, out: Path | None, engine: Engine | None = None,
              overwrite: bool = False, form: str = "fabric") -> CrimpResult:
    """Crimp the scene's fabric (``form="fabric"``) or its periodic unit cell (``"cell"``)."""
    if form not in ("fabric", "cell"):
        raise InputError(f"crimp form must be 'fabric' or 'cell', got {form!r}")
    check_scene(scene)  # every stage table, before the crimp starts
    loose = scene.model() if form == "fabric" else periodic_cell(scene)
    crimp = crimp_stage(scene)
    crimp.check_model(loose)  # families and target crimps against this fabric: no folder yet
    # an existing crimp is replaced only when the new one succeeded
    work = None if out is None else begin_run(out, overwrite=overwrite, prefix="crimp")
    try:
        found = {}
        if crimp.pins_crimp:  # the loose heights first, beside the crimp's folder
            search = (prepare_run_folder(None, prefix="loose-height") if work is None
                      else sibling(Path(out).resolve(), "." + LOOSE_HEIGHT))
            scene, found = pin_crimp(scene, search, engine)
            loose = scene.model() if form == "fabric" else periodic_cell(scene)
            crimp = crimp_stage(scene)
        if work is None:
            return crimp.run(loose, None, engine=engine, overwrite=overwrite)
        result = crimp.run(loose, work, engine=engine)
        if found:  # the search's runs into the crimp's folder, what it found beside them
            if mpi.is_root():
                shutil.rmtree(work / LOOSE_HEIGHT, ignore_errors=True)
                shutil.move(str(search), str(work / LOOSE_HEIGHT))
            mpi.barrier()
            _record_pin(work, dict(found, calibration=str(work / LOOSE_HEIGHT)), result)
    except (RunInterrupted, KeyboardInterrupt):
        raise
    except BaseException as exc:
        if work is not None:
            abandon_run(out, work, exc)
        raise
    summary = finish_run(out, work, result.summary)
    return dataclasses.replace(result, run_dir=Path(out).resolve(), summary=summary)


def _record_pin(crimp_dir: Path, found: dict, result: CrimpResult | None = None) -> None:
    """Write what the loose-height search found into the crimp folder (``PINNED``, and
    ``pinned_crimp`` in its ``summary.json``): a later stage rebuilds its scene from it."""
    if result is not None:
        result.summary["pinned_crimp"] = found
    if mpi.is_root():
        write_json(Path(crimp_dir) / PINNED, found)
        path = Path(crimp_dir) / "summary.json"
        if path.exists():
            summary = json.loads(path.read_text())
            summary["pinned_crimp"] = found
            write_json(path, summary)
    mpi.barrier()


def scene_of_crimp(scene: Scene, crimp_dir: Path) -> Scene:
    """The scene a finished crimp folder was crimped with: ``scene`` with the loose
    heights and expansion its ``PINNED`` file records (``crimp_by = "loose_height"``),
    else ``scene`` itself.

    Raises:
        InputError: the scene asks for ``crimp_by = "loose_height"`` and the folder was
            crimped without it (its yarns are not the ones the scene states).
    """
    path = Path(crimp_dir) / PINNED
    if path.exists():
        return pinned_scene(scene, json.loads(path.read_text()))
    if crimp_stage(scene).pins_crimp:
        raise InputError(f"{crimp_dir} was crimped without [crimp] crimp_by = "
                         f"\"loose_height\" (no {PINNED}): its loose sections are not the "
                         f"ones that reach the scene's crimp; crimp the scene again")
    return scene


def stage_mode(stage_dir: Path, resume: bool) -> str:
    """What a pipeline stage does with its folder: ``"done"`` (finished, its
    ``summary.json`` written: keep it), ``"resume"`` (``resume`` and a checkpoint there:
    continue from it) or ``"run"`` (run it, replacing a partial folder)."""
    stage_dir = Path(stage_dir)
    if (stage_dir / "summary.json").exists():
        return "done"
    return "resume" if resume and has_checkpoint(stage_dir) else "run"


def _stop_between_stages(out: Path, finished: str) -> None:
    """Honour a stop signal that came after a stage's last chunk (collective)."""
    if interrupt.stop_requested():
        raise RunInterrupted(f"stopped by {interrupt.signal_name()} after the {finished} "
                             f"stage (finished and kept in {out}); run the same command with "
                             f"--resume to continue", run_dir=Path(out))


def run_test(scene: Scene, test: str, out: Path, engine: Engine | None = None,
             overwrite: bool = False, check_rate: bool = False, resume: bool = False,
             crimped: Path | None = None, strict: bool = False, redo: bool = False) -> dict:
    """Run the whole pipeline for one test; returns the combined summary.

    Every check the scene decides runs first (:mod:`fabmd.preflight`): a bad scene
    starts no LAMMPS and writes no folder. A run that replaces an existing ``out``
    (``overwrite``) writes into ``<out>.partial`` and replaces ``out`` only when it
    succeeded; a failed one leaves ``out`` as it was and its attempt, with
    ``failure.json``, in ``<out>.failed`` (see :mod:`fabmd.results.folder`).

    Args:
        crimped: a finished crimp folder to start from (skips the crimp stage).
        resume: continue an interrupted run in ``out``: finished stages are kept, the
            interrupted one continues from its checkpoint (:func:`stage_mode`); a finished
            run is refused unless ``redo``.
        strict: a test whose curve is not quasi-static fails
            (:class:`~fabmd.errors.NotQuasiStatic`, exit status 4).
        redo: with ``resume``, run a finished run's test stage again on its crimp and
            coupon (the old test is replaced only when the new one succeeds).

    Raises:
        RunInterrupted: SIGTERM/SIGINT arrived; the stage running wrote a checkpoint.
    """
    if redo and not resume:
        raise InputError("--redo goes with --resume (run a finished run's test again); "
                         "to start a run over, use --overwrite")
    plan = plan_test(scene, test)
    check_test(scene, test, plan)
    check_scene(scene)
    if crimped is None and not resume:
        _check_crimp_targets(scene, plan.source)
    out = Path(out).resolve()
    partial = sibling(out, PARTIAL)
    if resume and (partial / MARKER).exists():
        work = partial  # an interrupted replacement: continue it, then put it in place
    elif resume and is_finished(out):
        if not redo:
            raise InputError(f"{out} holds a finished run (summary.json); --resume would "
                             f"rerun it: pass --redo to run its test again on its crimp "
                             f"and coupon, or choose another --out")
        work = begin_run(out, overwrite=True, prefix=test)
        if mpi.is_root():
            for stage in ("crimp", "coupon"):
                if (out / stage).is_dir():
                    shutil.copytree(out / stage, work / stage)
        mpi.barrier()
    elif resume:
        work = out
    else:
        work = begin_run(out, overwrite=overwrite, prefix=test)
    try:
        summary = _run_stages(scene, test, work, engine=engine, overwrite=False,
                              check_rate=check_rate, resume=resume,
                              crimped=crimped)
        verdict = summary["test_summary"].get("quasi_static")
        if strict and isinstance(verdict, dict) and not verdict.get("ok", True):
            raise NotQuasiStatic(
                f"{test} is not quasi-static under --strict: "
                f"{'; '.join(verdict.get('problems', []))}")
    except (RunInterrupted, KeyboardInterrupt):
        raise  # the checkpoint stays where it is, for --resume
    except BaseException as exc:
        record = abandon_run(out, work, exc)
        if isinstance(exc, NotQuasiStatic):
            kept = "; the old results are unchanged" if work != out else ""
            raise NotQuasiStatic(f"{exc} (results and failure.json in {record}{kept})") \
                from None
        raise
    return finish_run(out, work, summary)


def _check_crimp_targets(scene: Scene, source: str) -> None:
    """Refuse target crimps this fabric cannot reach before any folder is written (they
    need the loose model, so only a scene that sets ``[crimp] target_crimp_pct`` builds
    it here)."""
    crimp = crimp_stage(scene)
    if crimp.target_crimp_pct:
        crimp.check_model(periodic_cell(scene) if source == "cell" else scene.model())


def _stages(scene: Scene, test: str):
    """The crimp, the test's protocol and its coupon (None: the test takes the cell) of
    ``scene`` (built again once the loose heights changed the virtual fibre)."""
    coupon = coupon_stage(scene, test)[0] if TESTS[test].coupon is not None else None
    return crimp_stage(scene), protocol_stage(scene, test), coupon


def _run_stages(scene: Scene, test: str, out: Path, engine: Engine | None = None,
                overwrite: bool = False, check_rate: bool = False, resume: bool = False,
                crimped: Path | None = None) -> dict:
    """The stages of :func:`run_test` in the folder ``out``."""
    engine = engine or Engine()
    protocol = protocol_stage(scene, test)  # validate everything before LAMMPS starts
    coupon, source = coupon_stage(scene, test) if TESTS[test].coupon is not None else \
        (None, "cell")
    if coupon is None and scene.protocols.get(section(test), {}).get("coupon"):
        raise InputError(f"[{section(test)}] takes the crimped periodic cell itself: "
                         f"remove its coupon table")
    crimp = crimp_stage(scene)
    out = Path(out)
    if resume:
        if not out.is_dir():
            raise InputError(f"nothing to resume: {out} does not exist")
    else:
        out = prepare_run_folder(out, overwrite=overwrite, prefix=test)
    with interrupt.catching():  # SIGTERM/SIGINT: checkpoint, RunInterrupted (exit code 5)
        # 1. crimp
        crimp_dir = Path(crimped) if crimped is not None else out / "crimp"
        mode = "done" if crimped is not None else stage_mode(crimp_dir, resume)
        if mode != "done":
            found = {}
            if crimp.pins_crimp:  # 0. the loose sections that reach the stated crimp
                search = out / LOOSE_HEIGHT
                if resume and (search / PINNED).exists():
                    found = json.loads((search / PINNED).read_text())
                    scene = pinned_scene(scene, found)
                else:
                    scene, found = pin_crimp(scene, search, engine)
                    _stop_between_stages(out, "loose-height")
                crimp, protocol, coupon = _stages(scene, test)
            loose = periodic_cell(scene) if source == "cell" else scene.model()
            crimp_result: CrimpResult | None = crimp.run(
                loose, crimp_dir, engine=engine, overwrite=True, resume=mode == "resume")
            if found:
                _record_pin(crimp_dir, found, crimp_result)
            crimped_model = crimp_result.model
            _stop_between_stages(out, "crimp")
        else:
            crimp_result = None
            if (Path(crimp_dir) / PINNED).exists() or crimp.pins_crimp:
                scene = scene_of_crimp(scene, crimp_dir)
                crimp, protocol, coupon = _stages(scene, test)
            # the scene decides whether the tests start from the released cell
            crimped_model = load_crimped(crimp_dir, released=crimp.release_tension)
            if crimp.release_tension and not has_release(crimp_dir):
                # a crimp folder from before the release (or crimped without it): release
                # its cell here, in this run's own folder
                release_dir = out / "release"
                if stage_mode(release_dir, resume) == "done":
                    crimped_model = load_released(release_dir)
                else:
                    crimped_model = crimp.release_stage().run(
                        crimped_model, release_dir, engine=engine, overwrite=True).model
                    _stop_between_stages(out, "release")
        # 2. coupon
        coupon_dir = out / "coupon"
        if coupon is None:
            specimen = crimped_model
            coupon_result: CouponResult | None = None
        elif (mode := stage_mode(coupon_dir, resume)) == "done":
            specimen, coupon_result = load_coupon(coupon_dir), None
        else:
            coupon_result = coupon.run(crimped_model, coupon_dir, engine=engine,
                                       overwrite=True, resume=mode == "resume")
            specimen = coupon_result.model
            _stop_between_stages(out, "coupon")
        # 3. test
        test_dir = out / section(test)
        result = protocol.run(specimen, test_dir, engine=engine, check_rate=check_rate,
                              overwrite=True, resume=resume and has_checkpoint(test_dir))
    summary = {"test": test, "scene": scene.source, "results": str(out / section(test)),
               "crimp": str(crimp_dir), "coupon_beads": specimen.n_beads,
               "test_summary": result.summary}
    if (Path(crimp_dir) / PINNED).exists():  # the loose heights the crimp was reached with
        summary["pinned_crimp"] = json.loads((Path(crimp_dir) / PINNED).read_text())
    if crimp_result is not None:
        summary["crimped"] = crimp_result.summary.get("crimped")
        summary["crimp_stop"] = crimp_result.summary.get("stop")
        summary["within_family_law"] = crimp_result.summary.get("within_family_law")
    elif (crimp_summary := Path(crimp_dir) / "summary.json").exists():
        # a crimp run earlier (--crimped, or a resumed run): its law, as that run wrote it
        law = json.loads(crimp_summary.read_text()).get("within_family_law")
        if law is not None:
            summary["within_family_law"] = law
    if coupon_result is not None:
        summary["coupon"] = coupon_result.summary.get("relaxed_state")
        summary["coupon_stop"] = coupon_result.summary.get("stop")
    if mpi.is_root():
        write_json(out / "summary.json", summary)
    return summary
