"""What the fabmd command prints: one line per warning (issue 19)."""

import types
import warnings

from fabmd import cli
from fabmd.errors import OverlapWarning


def test_a_warning_is_one_fabmd_line(monkeypatch, capsys):
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)  # restored after

    def run(args):
        warnings.warn("largest overlap 0.12 d\n  is above the limit", OverlapWarning,
                      stacklevel=2)
        return 0

    probe = types.ModuleType("fabmd.cli.probe")
    probe.add_arguments = lambda p: None
    probe.run = run
    monkeypatch.setitem(__import__("sys").modules, "fabmd.cli.probe", probe)
    monkeypatch.setitem(cli.COMMANDS, "probe", ("probe", "test probe"))
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert cli.main(["probe"]) == 0
    err = capsys.readouterr().err
    assert err == "fabmd: warning: largest overlap 0.12 d is above the limit\n"


def test_numbers_carry_3_to_4_digits_and_the_key_s_unit():
    from fabmd.cli.report import energy_line, quasi_static_line, value_text

    assert value_text("fibre_volume_fraction", 0.14804596345200766) == "0.148"
    assert value_text("gauge_length_m", 0.016) == "16 mm"
    assert value_text("max_force_n", 12.3456789) == "12.35 N"
    assert value_text("clamp_speed_m_s", 1e-4) == "0.0001 m/s"
    assert value_text("steps", 11500) == "11,500"
    assert quasi_static_line({"ok": False, "problems": ["a > b"]}) == "quasi-static: NO (a > b)"
    line = energy_line({"external_work_j": 2.0, "strain_energy_change_j": 1.5,
                        "damping_dissipation_j": 0.49, "contact_work_j": 0.0,
                        "relative_error": 0.005})
    assert line.startswith("energy balance: external work 2 J") and "0.5 %" in line


def test_stage_header_counts_beads_and_steps(tmp_path):
    from fabmd.engine.estimate import SECONDS_PER_BEAD_STEP, stage_header

    from .fabrics import plain_weave_cell

    model = plain_weave_cell()
    model.save(tmp_path, stem="model")
    (tmp_path / "in.x").write_text("read_data model.data\nrun 1000\nrun 500 # relax\n")
    text = stage_header(tmp_path, "in.x", "crimp", ranks=2)
    assert text.startswith(f"crimp: {model.n_beads:,} beads, up to 1,500 steps")
    seconds = SECONDS_PER_BEAD_STEP * model.n_beads * 1500 / 2
    assert f"{seconds:.2g} s on 2 ranks" in text
    assert "sooner" not in text
    # a run that ends at its target (a halt the input goes on after) says it may be shorter;
    # a guard's hard stop does not count
    (tmp_path / "in.y").write_text("read_data model.data\n"
                                   "fix g all halt 10 v_nan > 0.5 error hard\nrun 1000\n")
    assert "sooner" not in stage_header(tmp_path, "in.y", "x")
    (tmp_path / "in.z").write_text("read_data model.data\nfix r all halt 10 v_p >= 2e5 "
                                   "error continue message yes\nrun 1000\n")
    assert stage_header(tmp_path, "in.z", "compaction").endswith(
        "(a run stops at its target: usually sooner)")
    # a plan's own estimate (the compaction's: its runs are bounds at the step limit)
    (tmp_path / "plan.json").write_text('{"extra": {"estimated_steps": 400}}')
    text = stage_header(tmp_path, "in.z", "compaction")
    seconds = SECONDS_PER_BEAD_STEP * model.n_beads * 400
    assert text.endswith(f"usually sooner); estimated 400 steps, about {seconds:.2g} s")
    (tmp_path / "plan.json").write_text('{"extra": {"estimated_steps": 4000}}')
    assert "estimated" not in stage_header(tmp_path, "in.z", "compaction")  # not below


def test_test_command_summary_states_stages_and_the_beads_that_ran():
    from fabmd.cli.test_cmd import summary_text

    summary = {"coupon_beads": 37500, "results": "runs/drape/drape",
               "crimp_stop": "stopped at step 3,500: quasi-static (criterion met)",
               "test_summary": {"n_beads": 9374, "max_punch_force_n": 33.2468123,
                                "quasi_static": {"ok": True, "problems": []},
                                "energy_balance": {"external_work_j": 1.5,
                                                   "relative_error": 0.0014}}}
    text = summary_text("drape", "examples/drape.toml", summary)
    lines = text.splitlines()
    assert lines[0].startswith("drape of examples/drape.toml: 9,374 beads (specimen 37,500")
    assert "  crimp: stopped at step 3,500: quasi-static (criterion met)" in lines
    assert "  drape: quasi-static: yes" in lines
    assert any(line.startswith("  drape: energy balance:") and "0.14 %" in line
               for line in lines)
    assert any(line.split() == ["max_punch_force_n", "33.25", "N"] for line in lines)
