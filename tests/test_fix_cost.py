"""The cheap forms of the drag and the power sums (issue 20) compute what the per-bead
formulas computed: the damping and clamp powers from LAMMPS's own sums equal the old
per-bead sums in the same run, and the split drag (fix viscous + addforce) moves the
beads as the old three-formula addforce did; interval means sampled every 10 steps stay
within 1 % of the peak of the every-step means, and the energy balance still closes."""

import re

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.engine.standalone import run_standalone
from fabmd.protocols.common import write_run_folder
from fabmd.protocols.driven import MEAN_SAMPLE_EVERY, mean_sample_every
from fabmd.protocols.picture_frame import PictureFrame
from fabmd.protocols.tension import Tension
from fabmd.scene.drag import AffineField, damping_power, drag_commands

from .fabrics import SOFT_GLASS, parallel_fibres, plain_weave_cell

STEPS = 600


def _fixed(text: str, steps: int = STEPS) -> str:
    """The loading run cut to ``steps``, a relaxation before it to ``run 0``."""
    plain = re.compile(r"^run\s+\d+\s*$", re.M)
    n = len(plain.findall(text))
    seen = iter(range(n))
    return plain.sub(lambda _m: f"run {steps if next(seen) == n - 1 else 0}", text)


def _old_sums(text: str, field: AffineField, gamma: float, ext_ref: str) -> str:
    """``text`` with the old per-bead sums written beside the new ones every 50 steps."""
    vx, vy, g = field.vx, field.vy, f"{gamma:.10g}"
    old = (f'variable        old_pa_damp atom "{g}*((vx-({vx}))*vx+(vy-({vy}))*vy+vz*vz)"\n'
           "compute         old_p_damp free reduce sum v_old_pa_damp\n"
           'variable        old_pa_clamp atom "-(fx*vx+fy*vy+fz*vz)"\n'
           "compute         old_p_ext clamps reduce sum v_old_pa_clamp\n"
           "fix             check all ave/time 50 1 50 v_p_damp c_old_p_damp "
           f"{ext_ref} c_old_p_ext format \" %.15g\" file check.dat\n")
    i = list(re.finditer(r"^run\s+\d+\s*$", text, re.M))[-1].start()
    return text[:i] + old + text[i:]


def _columns(path):
    return np.loadtxt(path, comments="#", ndmin=2)


def _gamma(text: str) -> float:
    return float(re.search(r"fix\s+damping free viscous (\S+)", text).group(1))


@pytest.fixture(scope="module")
def coupon():
    return plain_weave_cell(spacing_m=1e-3, cells=(3, 2), periodic=False)


def test_power_text_needs_no_formula_per_bead_beyond_the_gradient():
    field = AffineField(origin_m=(1e-3, 0.0), xx="2*v_v/(0.01+2*v_u)", tools="clamps")
    text, power = drag_commands("affine", "free", 2e-4, field)
    atom_vars = re.findall(r"variable\s+(\S+) atom \"([^\"]*)\"", text + power)
    # one product x*vx for the sum and one multiply-add for the force
    assert atom_vars == [("drag_fx", "v_drag_kxx*(x-(0.001))"), ("damp_xx", "x*vx")]
    assert "fix             damping free viscous 0.0002" in text
    assert "reduce sumsq vx vy vz" in power
    absolute = damping_power("free", 2e-4)
    assert " atom " not in absolute and "v_p_damp" not in absolute.split("equal")[0]
    assert 'variable        p_damp equal "0.0002*(c_damp_vv[1]+c_damp_vv[2]+c_damp_vv[3])"' \
        in absolute


@pytest.mark.lammps
@pytest.mark.parametrize("test", ["tension", "picture-frame"])
def test_sums_equal_the_per_bead_formulas(tmp_path, coupon, test):
    if test == "tension":
        proto = Tension(max_elongation_pct=2.0)
        model = coupon
        left, right, _ = proto.clamps(model)
        field = AffineField(origin_m=(0.5 * (left + right), 0.0),
                            xx=f"2*v_v/({right - left:.10g}+2*v_u)", tools="clamps")
        name, ext_ref = "in.tension", "v_p_ext"
    else:
        proto = PictureFrame(max_shear_angle_deg=20)
        model = proto.prepare(plain_weave_cell(spacing_m=1e-3, cells=(3, 3), periodic=False))
        g = proto.frame(model)
        field = AffineField(origin_m=(float(g.pin_a[0]), float(g.pin_a[1])), xx="v_frame_lxx",
                            xy="v_frame_lxy", yx="v_frame_lxy", yy="v_frame_lxx", tools="frame")
        name, ext_ref = "in.picture_frame", "c_p_ext"
    text = _fixed(proto.input_text(model))
    text = _old_sums(text, field, _gamma(text), ext_ref)
    folder = write_run_folder(tmp_path / "run", name.removeprefix("in."), model, text, {})
    run_standalone(folder, name)
    c = _columns(folder / "check.dat")
    assert len(c) == STEPS // 50 + 1
    # damping power: the same sum, γ(Σ|v|² − Σ v_aff·v) against Σ γ(v − v_aff)·v
    scale = np.max(np.abs(c[:, 2]))
    assert scale > 0
    assert np.max(np.abs(c[:, 1] - c[:, 2])) < 1e-9 * scale
    # clamp power: from the clamp forces and velocities (tension) or the same formula
    scale = np.max(np.abs(c[:, 4]))
    assert scale > 0
    assert np.max(np.abs(c[:, 3] - c[:, 4])) < 1e-9 * scale


OLD_DRAG = """variable        drag_fx atom "-{g}*(vx-({vx}))"
variable        drag_fy atom "-{g}*(vy-({vy}))"
variable        drag_fz atom "-{g}*vz"
fix             damping free addforce v_drag_fx v_drag_fy v_drag_fz
"""


@pytest.mark.lammps
def test_split_drag_moves_the_beads_as_the_old_formula(tmp_path):
    """The picture frame (a gradient in x and y) with the old drag and the new: the
    interval means of the frame power and the damping power agree to 1e-6 of their peak
    over the run (the same force, summed in another order)."""
    proto = PictureFrame(max_shear_angle_deg=20, damping_time_s=None)
    model = proto.prepare(plain_weave_cell(spacing_m=1e-3, cells=(3, 3), periodic=False))
    new = _fixed(proto.input_text(model))
    g = proto.frame(model)
    field = AffineField(origin_m=(float(g.pin_a[0]), float(g.pin_a[1])), xx="v_frame_lxx",
                        xy="v_frame_lxy", yx="v_frame_lxy", yy="v_frame_lxx", tools="frame")
    gamma = _gamma(new)
    drag, _ = drag_commands("affine", "free", gamma, field)
    assert drag in new
    old = new.replace(drag, OLD_DRAG.format(g=f"{gamma:.10g}", vx=field.vx, vy=field.vy))
    means = {}
    for key, text in (("new", new), ("old", old)):
        folder = write_run_folder(tmp_path / key, "picture_frame", model, text, {})
        run_standalone(folder, "in.picture_frame")
        means[key] = _columns(folder / "means.dat")
    assert means["new"].shape == means["old"].shape
    for col in (1, 2):  # external power, damping power
        a, b = means["new"][:, col], means["old"][:, col]
        assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(b))


# -- interval means sampled every 10 steps ---------------------------------------------------
def test_long_intervals_sample_the_means_every_ten_steps():
    assert mean_sample_every(430) == MEAN_SAMPLE_EVERY == 10
    assert mean_sample_every(199) == mean_sample_every(431) == 1
    test = Tension(max_elongation_pct=1.2, samples=20)
    model = parallel_fibres(n=4)
    assert test.every(model) % MEAN_SAMPLE_EVERY == 0  # the plan rounds it
    text = test.input_text(model)
    every = test.every(model)
    assert f"fix             means all ave/time 10 {every // 10} {every} " in text
    short = Tension(max_elongation_pct=1.2)  # 200 samples: short intervals, every step
    assert f"ave/time 1 {short.every(model)} {short.every(model)} " in short.input_text(model)


@pytest.mark.lammps
def test_sampled_means_match_every_step_and_the_balance_closes(tmp_path):
    """Straight fibres pulled with 20 output intervals (430 steps each, sampled every 10):
    the sampled interval means against an every-step copy on the same run, and the
    energy balance and N·EA·ε of the whole test."""
    n = 4
    model = parallel_fibres(n=n)
    test = Tension(max_elongation_pct=1.2, samples=20)
    text = test.input_text(model)
    m = re.search(r"^fix\s+means all ave/time 10 (\d+) (\d+) (.*?)&\n\s+format", text, re.M)
    every, values = m.group(2), m.group(3).strip()
    i = text.index("\n", m.end()) + 1
    text = (text[:i] + f"fix             exact all ave/time 1 {every} {every} {values} "
            "format \" %.12g\" file exact.dat\n" + text[i:])
    folder = write_run_folder(tmp_path / "exact", "tension", model, text, {})
    run_standalone(folder, "in.tension")
    s, e = _columns(folder / "means.dat"), _columns(folder / "exact.dat")
    assert s.shape == e.shape and len(s) == 21
    for col in (1, 2, 3, 4):  # forces left, right, external and damping power
        peak = np.max(np.abs(e[:, col]))
        assert np.max(np.abs(s[:, col] - e[:, col])) < 0.01 * peak, col
    # the works (sums over the intervals) closer still
    for col in (3, 4):
        assert abs(np.sum(s[:, col] - e[:, col])) < 2e-3 * np.max(np.abs(np.cumsum(e[:, col])))
    result = test.run(model, tmp_path / "run", engine=Engine(progress=False))
    ea = SOFT_GLASS.modulus_pa * 3.14159265 * 0.5e-3**2 / 4
    # (an interval mean lags its end by half an interval: 3 % at 1 % with 20 intervals)
    assert result.summary["force_at_elongation_n"]["1"] == pytest.approx(n * ea / 100, rel=0.05)
    assert result.summary["energy_balance"]["relative_error"] < 0.05


# -- benchmarks/fix_cost.py: its input surgery and its table (no LAMMPS) -------------------
def test_fix_cost_script_removes_fixes_and_reports(tmp_path):
    from .test_benchmarks import load_benchmark

    fc = load_benchmark("fix_cost")
    text = Tension(samples=20).input_text(parallel_fibres(n=2))
    bare = fc.without(text, [i for ids in fc.GROUPS.values() for i in ids])
    for fix in ("damping", "damping_affine", "means", "guard_speed", "pull_left"):
        assert f"fix             {fix} " in text and f"fix             {fix} " not in bare
    assert "fix             curve " in bare  # only the named fixes go
    exact = fc.with_exact_means(text)
    assert "fix             exact_means all ave/time 1 " in exact
    assert fc.fixed_steps(text, 50).count("\nrun 50\n") == 1
    rec = {"cpu_s": 2.0, "wall_s": 4.0, "load": 3.0, "loop_s": 3.5, "modify_pct": 60.0,
           "atoms": 1000, "steps": 100}
    runs = {"after": [rec, rec], "before": [dict(rec, cpu_s=3.0)] * 2,
            **{f"-{g}": [dict(rec, cpu_s=1.5)] * 2 for g in fc.GROUPS},
            "bare": [dict(rec, cpu_s=1.0)] * 2}
    data = {"steps": 100, "repeat": 2, "runs": {"x": runs}, "sampling_steps": 600,
            "sampling": {"x": {"force_left_n": {"interval": 1e-3, "sum": 1e-4,
                                                "intervals": 3}}}}
    body = fc.report(data)
    assert "x 1.50×" in body and "| x | 3.00 | 2.00 | 1.50x | 0.50 | 0.50 |" in body
    assert "| x | force_left_n | 3 | 1.0e-03 | 1.0e-04 |" in body
