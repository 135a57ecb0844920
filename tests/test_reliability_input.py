"""Every input checked first, nothing lost, exit codes by kind (issue 18, part A).

Pure-Python tests first (no LAMMPS: the checks must refuse before it starts); the
LAMMPS ones share one tiny finished pipeline run (about 10 s).
"""

import hashlib
import json
import subprocess
import tomllib
from importlib.metadata import version
from pathlib import Path

import pytest

from fabmd import errors
from fabmd.cli import main
from fabmd.engine import Engine
from fabmd.errors import EXIT_CODES, InputError, NotQuasiStatic, OutputExists, UnstableRun
from fabmd.pipeline import run_test
from fabmd.results import folder
from fabmd.scenefile import load_scene, parse_scene

from .test_pipeline import TINY

# ---- helpers ---------------------------------------------------------------------------


def scene_file(tmp_path: Path, text: str = TINY, name: str = "scene.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def with_table(table: str, body: str, text: str = TINY) -> str:
    """TINY with ``[table]`` replaced by ``body`` (a whole table, header included)."""
    out, skip = [], False
    for line in text.splitlines():
        if line.startswith("["):
            skip = line.strip() == f"[{table}]"
        if not skip:
            out.append(line)
    return "\n".join(out) + "\n" + body + "\n"


def digest(path: Path) -> dict[str, str]:
    """Every file under ``path`` -> its SHA-256 (byte-for-byte comparison)."""
    return {str(p.relative_to(path)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(path.rglob("*")) if p.is_file()}


@pytest.fixture
def no_lammps(monkeypatch):
    """Any attempt to start LAMMPS fails the test."""
    def refuse(*args, **kwargs):
        raise AssertionError("LAMMPS was started")
    monkeypatch.setattr(Engine, "run", refuse)
    monkeypatch.setattr("fabmd.engine.library.load_lammps", refuse, raising=False)


def cli(capsys, *args) -> tuple[int, str]:
    code = main(list(args))
    return code, capsys.readouterr().err


# ---- 1. tracebacks -> one-line errors naming the scene file ------------------------------
@pytest.mark.parametrize("coupon,words", [
    ('coupon = "big"', "coupon must be a table"),
    ("coupon = [3, 3]", "coupon must be a table"),
    ('coupon = { cells = ["a", 2] }', "cells must be two whole numbers"),
    ("coupon = { cells = [3, 2], lenght_m = 0.01 }", "has no key 'lenght_m'"),
])
def test_malformed_coupon_tables_are_one_line_errors(tmp_path, capsys, no_lammps, coupon,
                                                     words):
    path = scene_file(tmp_path, TINY.replace("coupon = { cells = [3, 2] }", coupon))
    out = tmp_path / "run"
    code, err = cli(capsys, "test", "tension", str(path), "--out", str(out), "--quiet")
    assert code == 2, err
    line = err.strip()
    assert "\n" not in line and "Traceback" not in line
    assert str(path) in line and "[tension" in line and words in line
    assert not out.exists()


@pytest.mark.parametrize("change,words", [
    (("max_elongation_pct", "max_elongaton_pct"), "has no key 'max_elongaton_pct'"),
    (("[tension]", "[tenson]"), "[tenson] is not a table fabmd reads"),
    (("expansion = {", "expanson = {"), "[crimp] has no key 'expanson'"),
    (('coupon = { cells = [3, 2] }', 'coupon = "big"'), "coupon must be a table"),
    (("speed_fraction = 2e-4", "speed_fraction = 2e-4\nrelax = 5"), "relax must be a table"),
])
def test_build_refuses_misspelt_test_tables(tmp_path, capsys, change, words):
    path = scene_file(tmp_path, TINY.replace(*change))
    out = tmp_path / "b"
    code, err = cli(capsys, "build", str(path), "--out", str(out))
    assert code == 2 and words in err and str(path) in err, err
    assert not out.exists()


def test_a_material_table_no_yarn_uses_is_an_error():
    # [materials.glas] misspelt: the yarns' "glass" would silently be the built-in glass
    scene = tomllib.loads(TINY.replace('material = "soft"', 'material = "glass"')
                          .replace("[materials.soft]", "[materials.glas]"))
    with pytest.raises(InputError, match=r"\[materials.glas\] is not used by any yarn"):
        parse_scene(scene, source="s.toml")


# ---- 2. every size check before LAMMPS: no LAMMPS started, no folder written -------------
PICTURE_FRAME = """[picture_frame]
max_shear_angle_deg = 30
coupon = { length_m = "15 mm", width_m = "10 mm" }"""
DRAPE = """[drape]
punch_radius_m = "20 mm"
depth_m = "15 mm"
coupon = { length_m = "30 mm", width_m = "30 mm" }"""


@pytest.mark.parametrize("test,text,words", [
    # the tiny fabric is one 5 x 5 mm cell: a 15 x 10 mm coupon cut from it cannot fit
    ("tension", TINY.replace("coupon = { cells = [3, 2] }",
                             'coupon = { source = "fabric", length_m = "15 mm", '
                             'width_m = "10 mm" }'),
     "set [fabric] tiling = [3, 2]"),
    ("picture-frame", with_table("picture_frame", PICTURE_FRAME),
     "needs a square coupon"),
    ("picture-frame", with_table("picture_frame", "[picture_frame]\nclamp_yarns = 2\n"
                                 "coupon = { cells = [2, 2] }"),
     "clamp_yarns = 2 holds 4 of the 4 warp yarns"),
    ("drape", with_table("drape", DRAPE), "needs a blank at least"),
    ("drape", with_table("drape", DRAPE.replace('"30 mm"', '"60 mm"')
                         + '\ndie_clearance_m = "0.01 mm"'), "raise die_clearance_m"),
    ("tension", TINY.replace("coupon = { cells = [3, 2] }",
                             'coupon = { length_m = "500 mm", width_m = "1 mm" }'),
     "500:1"),
    ("tension", TINY.replace("coupon = { cells = [3, 2] }",
                             'coupon = { length_m = "20 mm", width_m = "2 mm" }'),
     "fewer than 2 yarn spacings"),
    ("tension", TINY.replace("speed_fraction = 2e-4",
                             'speed_fraction = 2e-4\nclamp_length_m = "7 mm"'),
     "clamp_length_m = 7 mm leaves no gauge length"),
])
def test_size_checks_refuse_before_any_stage(tmp_path, capsys, no_lammps, test, text, words):
    path = scene_file(tmp_path, text)
    out = tmp_path / "run"
    code, err = cli(capsys, "test", test, str(path), "--out", str(out), "--quiet")
    assert code == 2, err
    assert words in err and str(path) in err and "\n" not in err.strip(), err
    assert "Coupon(" not in err  # the fix in scene-file terms, not Python
    assert not out.exists() and not folder.sibling(out, folder.PARTIAL).exists()


def test_the_fabric_size_check_agrees_with_the_cut(tmp_path):
    """What preflight refuses, the cut refuses too; what it accepts, the cut accepts
    (loose fabric, no LAMMPS)."""
    from fabmd.pipeline import coupon_stage
    from fabmd.preflight import check_test, plan_test

    base = TINY.replace("[fabric]\narchitecture = \"plain\"",
                        "[fabric]\narchitecture = \"plain\"\ntiling = [3, 2]")
    for length, fits in (("14 mm", True), ("16 mm", False)):
        scene = parse_scene(tomllib.loads(base.replace(
            "coupon = { cells = [3, 2] }",
            f'coupon = {{ source = "fabric", length_m = "{length}", width_m = "8 mm" }}')),
            source="s.toml")
        coupon, _ = coupon_stage(scene, "tension")
        fabric = scene.model()
        try:
            coupon.geometry(fabric)
            cut_ok = True
        except InputError:
            cut_ok = False
        try:
            check_test(scene, "tension", plan_test(scene, "tension"))
            pre_ok = True
        except InputError:
            pre_ok = False
        assert pre_ok == fits and cut_ok == fits, (length, pre_ok, cut_ok)


# ---- 3. nothing lost ------------------------------------------------------------------
def make_result(path: Path, text: str) -> Path:
    work = folder.begin_run(path)
    (work / "curve.csv").write_text(text)
    (work / "summary.json").write_text(json.dumps({"results": str(work / "t")}))
    return folder.finish_run(path, work) or work


def test_a_replacement_is_swapped_in_only_when_it_succeeds(tmp_path):
    old = tmp_path / "r"
    make_result(old, "old\n")
    before = digest(old)
    with pytest.raises(OutputExists, match="--overwrite"):
        folder.begin_run(old)
    work = folder.begin_run(old, overwrite=True)
    assert work == folder.sibling(old, folder.PARTIAL) and digest(old) == before
    (work / "curve.csv").write_text("half\n")
    record = folder.abandon_run(old, work, UnstableRun("blew up", cause="nan", step=40))
    assert digest(old) == before  # byte for byte
    failure = json.loads((record / "failure.json").read_text())
    assert record == folder.sibling(old, folder.FAILED)
    assert failure["kind"] == "UnstableRun" and failure["exit_code"] == 3
    assert not work.exists()
    # a successful replacement: new content in place, its paths point at the final folder
    work = folder.begin_run(old, overwrite=True)
    (work / "curve.csv").write_text("new\n")
    (work / "summary.json").write_text(json.dumps({"results": str(work / "t")}))
    summary = folder.finish_run(old, work, {"results": str(work / "t")})
    assert (old / "curve.csv").read_text() == "new\n" and not work.exists()
    assert summary["results"] == str(old.resolve() / "t")
    assert json.loads((old / "summary.json").read_text())["results"] == str(old.resolve() / "t")


def test_nothing_that_is_not_a_fabmd_folder_is_replaced(tmp_path):
    mine = tmp_path / "thesis"
    mine.mkdir()
    (mine / "chapter1.tex").write_text("precious")
    with pytest.raises(OutputExists, match="not a fabmd results folder"):
        folder.begin_run(mine, overwrite=True)
    assert (mine / "chapter1.tex").read_text() == "precious"


# ---- 4. exit codes, --version, --help -----------------------------------------------
def test_exit_codes_are_by_kind(tmp_path, capsys, monkeypatch):
    assert {c.exit_code for c in (errors.InputError, errors.OutputExists)} == {2}
    assert errors.SimulationFailed.exit_code == errors.UnstableRun.exit_code == 3
    assert errors.NotQuasiStatic.exit_code == 4 and errors.RunInterrupted.exit_code == 5
    assert set(EXIT_CODES) == {0, 1, 2, 3, 4, 5}
    path = scene_file(tmp_path)
    for exc, code in ((UnstableRun("x", cause="nan", step=3), 3), (NotQuasiStatic("x"), 4),
                      (errors.RunInterrupted("x"), 5), (InputError("x"), 2)):
        def fail(*args, exc=exc, **kwargs):
            raise exc
        monkeypatch.setattr("fabmd.pipeline.run_test", fail)
        got, err = cli(capsys, "test", "tension", str(path), "--out", str(tmp_path / "o"))
        assert got == code and err.startswith("fabmd: error:"), (exc, got, err)


def test_version_and_help_epilog(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"fabmd {version('fabmd')}"
    with pytest.raises(SystemExit):
        main(["--help"])
    text = " ".join(capsys.readouterr().out.split())
    for code, meaning in EXIT_CODES.items():
        assert f"{code} {' '.join(meaning.split())}" in text


# ---- 5. remedies name the measure that failed and point the right way ------------------
def test_remedies_name_the_failed_measure():
    from fabmd.protocols.driven import quasi_static_verdict

    calm = {"max_kinetic_to_strain_energy": 0.02,
            "energy_balance": {"external_work_j": 1.0, "damping_dissipation_j": 0.1,
                               "relative_error": 0.01}}
    assert quasi_static_verdict(calm)["remedies"] == []
    cases = {
        "start_settled": ({**calm, "start_settled": False}, "relax.max_steps"),
        "damping_share": ({**calm, "energy_balance": {**calm["energy_balance"],
                                                      "damping_dissipation_j": 0.9}},
                          "raise damping_time_s"),
        "energy_balance_error": ({**calm, "energy_balance": {**calm["energy_balance"],
                                                             "relative_error": 0.3}},
                                 "time_step.factor"),
        "max_kinetic_to_strain_energy": ({**calm, "max_kinetic_to_strain_energy": 3.0},
                                         "lower speed_fraction"),
    }
    for measure, (summary, fix) in cases.items():
        remedies = quasi_static_verdict(summary)["remedies"]
        assert len(remedies) == 1 and remedies[0].startswith(measure + ":"), remedies
        assert fix in remedies[0]
        if measure in ("start_settled", "energy_balance_error"):  # slower does not cure it
            assert "does not cure it" in remedies[0]


def test_a_start_up_spike_is_caught_with_its_own_remedy():
    import numpy as np

    from fabmd.protocols.driven import quasi_static_verdict, start_spike_ratio

    ramp = np.linspace(0.0, 2.0, 201)  # a settled start: force grows with the elongation
    assert start_spike_ratio(ramp) == pytest.approx(ramp[10] / ramp[-1])  # 1st 5 % of 200
    assert start_spike_ratio(ramp ** 3) < 0.01 and start_spike_ratio(ramp[:3]) is None
    # the shape measured on a tension with a 1000x stiffer warp: 3.77 N at the first
    # sample, then about 3 mN for the rest of the test
    spike = np.full(201, 3e-3)
    spike[0], spike[1] = 0.0, 3.77
    ratio = start_spike_ratio(spike)
    assert ratio == pytest.approx(3.77 / 3e-3)
    verdict = quasi_static_verdict({"start_settled": True, "start_spike_ratio": ratio})
    assert not verdict["ok"] and verdict["remedies"][0].startswith("start_spike_ratio:")
    assert "relax.force_ratio" in verdict["remedies"][0]
    assert "speed_fraction does not cure it" in verdict["remedies"][0]


def test_lammps_errors_that_name_a_step_keep_it():
    from fabmd.engine.diagnosis import to_exception

    exc = to_exception("ERROR: Bond atoms 9 10 missing on proc 0 at step 2 (ntopo_bond_all.cpp)",
                       None)
    assert isinstance(exc, UnstableRun) and exc.cause == "lost_atoms" and exc.step == 2
    assert "at step 2" in str(exc)


@pytest.mark.lammps
@pytest.mark.parametrize("factor", [1.5, 3.0])
def test_a_time_step_blow_up_is_caught_by_fabmd_with_its_step(tmp_path, factor):
    """Time steps 6 and 12 x fabmd's default (above the stable one; only benchmarks may
    ask for them): fabmd's bond guard (every 2 steps) stops the run, before LAMMPS loses
    bond atoms (it did at step 5 with the guard every 20 steps)."""
    from fabmd.model.beads import TimeStep
    from fabmd.protocols.crimp import Crimp

    from .fabrics import plain_weave_cell

    crimp = Crimp(expansion={"warp": -0.1, "weft": -0.1},
                  time_step=TimeStep(factor=factor, check=False))
    with pytest.raises(UnstableRun) as err:
        crimp.run(plain_weave_cell(), tmp_path / "c", engine=Engine(progress=False))
    record = json.loads((tmp_path / "c" / "failure.json").read_text())
    assert err.value.cause == record["cause"] == "bond_stretch", record
    assert record["step"] == err.value.step and 0 < record["step"] < 20
    assert "time_step.factor" in str(err.value)


@pytest.mark.lammps
def test_the_crimp_verdict_is_its_stop_condition(tmp_path):
    """quasi-static is whether the settle condition fired, not the last history line."""
    from fabmd.protocols.crimp import Crimp
    from fabmd.scene.quasi_static import QuasiStatic, relaxation_settled

    from .fabrics import plain_weave_cell

    unreachable = QuasiStatic(kinetic_ratio=1e-15, force_ratio=1e-15, max_steps=2000)
    for name, criterion, fired in (("default", QuasiStatic(), True),
                                   ("unreachable", unreachable, False)):
        crimp = Crimp(expansion={"warp": -0.1, "weft": -0.1}, quasi_static=criterion)
        result = crimp.run(plain_weave_cell(), tmp_path / name, engine=Engine(progress=False))
        assert relaxation_settled(result.run_dir / "log.lammps") is fired
        assert result.summary["quasi_static"] is fired


# ---- 6. slurm.sh ------------------------------------------------------------------------
def test_every_run_folder_has_a_slurm_script(tmp_path):
    from fabmd.protocols.common import slurm_ranks, write_run_folder

    from .fabrics import plain_weave_cell

    model = plain_weave_cell()
    run_dir = write_run_folder(tmp_path / "r", "tension", model, "run 0\n", {})
    script = (run_dir / "slurm.sh").read_text()
    assert (run_dir / "run.sh").exists()
    assert f"#SBATCH --ntasks={slurm_ranks(model.n_beads)}" in script
    assert "#SBATCH --time=" in script and "-in in.tension -log log.lammps" in script
    assert subprocess.run(["bash", "-n", str(run_dir / "slurm.sh")]).returncode == 0
    assert slurm_ranks(10) == 1 and slurm_ranks(50_000) == 8 and slurm_ranks(10**9) == 1024
    assert slurm_ranks(235_000) == 32  # not 47: a prime count cuts a sheet into strips


# ---- LAMMPS: a finished tiny run, replaced, resumed, strict ----------------------------
@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished tiny tension pipeline run (about 10 s)."""
    root = tmp_path_factory.mktemp("finished")
    path = scene_file(root)
    scene = load_scene(path)
    out = root / "run"
    run_test(scene, "tension", out, engine=Engine(progress=False))
    return scene, out


@pytest.mark.lammps
def test_a_failed_overwrite_keeps_the_old_result(finished, monkeypatch):
    scene, out = finished
    before = digest(out)
    ran = []

    def unstable(self, *args, **kwargs):
        ran.append(True)
        raise UnstableRun("kinetic energy ran away", cause="kinetic_energy", step=123)
    monkeypatch.setattr("fabmd.protocols.tension.Tension.run", unstable)
    with pytest.raises(UnstableRun):
        run_test(scene, "tension", out, engine=Engine(progress=False), overwrite=True)
    assert ran and digest(out) == before  # byte for byte
    failed = folder.sibling(out, folder.FAILED)
    record = json.loads((failed / "failure.json").read_text())
    assert record["kind"] == "UnstableRun" and record["kept"] == str(out.resolve())
    assert (failed / "crimp" / "crimped.data").exists()  # the stages it ran, for a look


@pytest.mark.lammps
def test_resume_of_a_finished_run_refuses_unless_redo(finished):
    scene, out = finished
    before = digest(out)
    with pytest.raises(InputError, match="--redo"):
        run_test(scene, "tension", out, engine=Engine(progress=False), resume=True)
    assert digest(out) == before


@pytest.mark.lammps
def test_redo_runs_the_test_again_on_the_same_crimp_and_coupon(finished, tmp_path):
    import shutil

    scene, out = finished
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    stages = {k: v for k, v in digest(copy).items() if k.startswith(("crimp/", "coupon/"))}
    old_curve = (copy / "tension" / "curve.csv").read_bytes()
    (copy / "tension" / "curve.csv").write_text("stale\n")  # the redo must replace this
    summary = run_test(scene, "tension", copy, engine=Engine(progress=False), resume=True,
                       redo=True)
    assert (copy / "tension" / "curve.csv").read_bytes() == old_curve  # same state, same run
    assert {k: v for k, v in digest(copy).items() if k in stages} == stages
    assert summary["results"] == str(copy.resolve() / "tension")
    assert not folder.sibling(copy, folder.PARTIAL).exists()


@pytest.mark.lammps
@pytest.mark.slow
def test_strict_fails_a_tension_pulled_far_too_fast(finished, tmp_path, capsys):
    scene, out = finished
    # 500 x the default speed_fraction of a tension (1e-4)
    fast = scene_file(tmp_path, TINY.replace("speed_fraction = 2e-4", "speed_fraction = 0.05"))
    target = tmp_path / "fast"
    code, err = cli(capsys, "test", "tension", str(fast), "--out", str(target),
                    "--crimped", str(out / "crimp"), "--strict", "--quiet")
    assert code == 4, err
    assert "not quasi-static" in err and "failure.json" in err
    assert "max_kinetic_to_strain_energy" in err  # names the measure that failed
    summary = json.loads((target / "summary.json").read_text())
    assert summary["test_summary"]["quasi_static"]["ok"] is False
    assert (target / "failure.json").exists()
