"""The README's Python snippets run (issue 19).

Every ```python block of README.md is extracted and executed. Blocks that start from
objects the README makes elsewhere (a coupon, a crimped cell, a blank) get tiny ones, and
blocks that would run for minutes get smaller loads by named text substitutions; each
substitution must still match the README (a stale one fails the test).
"""

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

from fabmd.engine import Engine  # noqa: E402

from .fabrics import plain_weave_cell  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = re.findall(r"^```python\n(.*?)^```", (ROOT / "README.md").read_text(),
                    re.S | re.M)


def block(marker: str) -> str:
    """The one README block that contains ``marker``."""
    found = [b for b in BLOCKS if marker in b]
    assert len(found) == 1, f"{len(found)} README python blocks contain {marker!r}"
    return found[0]


def run_block(code: str, namespace: dict | None = None,
              substitutions: tuple[tuple[str, str], ...] = ()) -> dict:
    for old, new in substitutions:
        assert old in code, f"README block no longer contains {old!r}"
        code = code.replace(old, new)
    namespace = dict(namespace or {})
    try:
        exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the README's code
    finally:
        plt.close("all")
    return namespace


KNOWN = ("from fabmd.scenefile import load_scene", "FibreTension(", "fabmd.load(\"runs/crimp\")",
         "from ovito", "ContactModel(friction=0.3)", "PictureFrame(", "Drape(",
         'mda.Universe("model.data", "trajectory.h5"', "fabmd.load_scene(")


def test_every_python_block_of_the_readme_is_run_here():
    assert BLOCKS
    for b in BLOCKS:
        assert sum(marker in b for marker in KNOWN) == 1, b[:200]


def test_describing_a_fabric(monkeypatch):
    monkeypatch.chdir(ROOT)  # the block reads examples/plain_weave.toml
    ns = run_block(block(KNOWN[0]))
    assert ns["model"].n_beads > 0


def test_python_quick_start_uses_the_public_api(monkeypatch, tmp_path):
    """The quick start's names are fabmd's; its run and load are stood in for (the
    pipeline and ``fabmd.load`` have their own tests), the arguments are checked."""
    import fabmd

    monkeypatch.chdir(ROOT)  # the block reads examples/plain_weave.toml
    calls = []

    def run_test(scene, test, out, engine=None):
        calls.append((scene, test, out, engine))
        return {"results": str(tmp_path / "t" / "tension")}

    monkeypatch.setattr(fabmd, "run_test", run_test)
    monkeypatch.setattr(fabmd, "load", lambda path: calls.append(path) or "universe")
    ns = run_block(block("fabmd.load_scene("))
    scene, test, out, engine = calls[0]
    assert isinstance(scene, fabmd.Scene) and isinstance(engine, fabmd.Engine)
    assert (test, out) == ("tension", "runs/t")
    assert calls[1] == str(tmp_path / "t" / "tension") and ns["u"] == "universe"
    assert set(fabmd.__all__) >= {"Scene", "load_scene", "run_test", "Engine", "load",
                                  "InputError", "OverlapWarning", "QuasiStaticWarning"}


@pytest.mark.lammps
def test_python_api_fibre_tension(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    ns = run_block(block(KNOWN[1]), substitutions=(("Engine()", "Engine(progress=False)"),))
    s = ns["result"].summary
    assert s["measured_force_n"] == pytest.approx(s["expected_force_n"], rel=0.01)


@pytest.mark.lammps
def test_mdanalysis_snippet_measures_the_crimped_state(monkeypatch, tmp_path):
    import json

    from fabmd.protocols.crimp import Crimp

    monkeypatch.chdir(tmp_path)
    Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(plain_weave_cell(cells=(2, 2)),
                                                      tmp_path / "runs" / "crimp",
                                                      engine=Engine(progress=False))
    ns = run_block(block(KNOWN[2]))
    summary = json.loads((tmp_path / "runs" / "crimp" / "summary.json").read_text())
    measured = ns["analysis"].crimp_by_family(ns["frame"])
    # the snippet's frame is the crimped state (the last frame), not the loose one
    for fam, pct in summary["crimped"]["centreline_crimp_pct"].items():
        assert 100 * measured[fam] == pytest.approx(pct, rel=1e-6)
        assert 100 * measured[fam] != pytest.approx(summary["loose"]["crimp_pct"][fam],
                                                    rel=1e-3)


@pytest.mark.lammps
def test_stock_mdanalysis_snippet_reads_a_run_folder(monkeypatch, tmp_path):
    import numpy as np

    from fabmd.protocols.crimp import Crimp
    from fabmd.results.universe import load

    run = tmp_path / "crimp"
    Crimp(expansion={"warp": -0.05, "weft": -0.05}).run(plain_weave_cell(cells=(1, 1)), run,
                                                        engine=Engine(progress=False))
    monkeypatch.chdir(run)
    u = run_block(block(KNOWN[7]))["u"]
    ours = load(run)
    assert len(u.atoms) == len(ours.atoms) and len(u.trajectory) == len(ours.trajectory)
    u.trajectory[-1]
    ours.trajectory[-1]
    # stock MDAnalysis gives ångströms, fabmd's reader SI metres: the same positions
    assert np.allclose(u.atoms.positions * 1e-10, ours.atoms.positions, rtol=1e-5, atol=1e-12)


def test_ovito_snippet():
    pytest.importorskip("ovito", reason="OVITO is optional (not a fabmd dependency)")
    pytest.skip("needs a crimp run folder with trajectory.bin; OVITO is not installed in CI")


def test_contact_snippet():
    ns = run_block(block(KNOWN[4]))
    assert ns["contact"].friction == 0.3 and ns["tool"].friction == 0.2


@pytest.mark.lammps
@pytest.mark.slow
def test_virtual_tests_snippet(monkeypatch, tmp_path):
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.crimp import Crimp

    from .test_bias_extension import braced_bias_net

    engine = Engine(progress=False)
    crimped = Crimp(expansion={"warp": -0.02, "weft": -0.02}).run(
        plain_weave_cell(spacing_m=1e-3, gap=1.0), tmp_path / "crimp", engine=engine)
    square = Coupon(length_m=6e-3, width_m=6e-3, relax=None).run(
        crimped.model, tmp_path / "coupon", engine=engine).model
    monkeypatch.chdir(tmp_path)
    ns = run_block(block(KNOWN[5]),
                   {"square_coupon": square, "coupon_45deg": braced_bias_net(),
                    "crimped_cell": crimped.model},
                   substitutions=(("max_shear_angle_deg=60", "max_shear_angle_deg=10"),
                                  ("max_shear_angle_deg=40", "max_shear_angle_deg=5"),
                                  ("max_strain_pct=2", "max_strain_pct=0.5"),
                                  ("max_shear_angle_deg=45", "max_shear_angle_deg=5")))
    assert "rate_check" in ns["pf"].summary  # check_rate=True ran the half-speed twin
    assert ns["pt"].summary["initial_stiffness_n_m_per_width"] > 0
    assert ns["be"].summary["max_force_n"] > 0 and ns["ps"].summary["steps"] > 0


@pytest.mark.lammps
@pytest.mark.slow
def test_drape_snippet(monkeypatch, tmp_path):
    from fabmd.model.transform import cut, tile
    from fabmd.protocols.crimp import Crimp

    crimped = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(
        plain_weave_cell(spacing_ratio=0.9), tmp_path / "crimp", engine=Engine(progress=False))
    blank = cut(tile(crimped.model, 7, 7, periodic=False), 26e-3, 26e-3)
    monkeypatch.chdir(tmp_path)
    ns = run_block(block(KNOWN[6]), {"blank": blank}, substitutions=(
        ("punch_radius_m=0.05, depth_m=0.04, die_clearance_m=0.003, holder_force_n=100",
         "punch_radius_m=5e-3, depth_m=3e-3, die_clearance_m=1.5e-3, holder_force_n=20"),
        ("modulus_scale=0.02", "modulus_scale=1.0"),
        ("speed_fraction=1.32e-3", "speed_fraction=1e-3")))
    s = ns["result"].summary
    assert s["max_punch_force_n"] > 0 and s["max_shear_angle_deg"] > 0
