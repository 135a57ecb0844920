"""The validation benchmark reads its measured data and marks what lies outside it."""

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def load():
    spec = importlib.util.spec_from_file_location("validation_bench",
                                                  ROOT / "benchmarks" / "validation.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["validation_bench"] = module
    spec.loader.exec_module(module)
    return module


def test_measured_ranges_are_ordered_and_cover_the_report_angles():
    bench = load()
    ref = bench.measured()
    assert sorted(ref) == list(bench.ANGLES)
    for a, r in ref.items():
        assert r["min_n_mm"] <= r["median_n_mm"] <= r["max_n_mm"], a
    # the force rises with the angle in every laboratory's median
    medians = [ref[a]["median_n_mm"] for a in bench.ANGLES]
    assert medians == sorted(medians)


def test_section_marks_values_outside_the_laboratories_range():
    bench = load()
    ref = bench.measured()
    inside = {str(a): ref[a]["median_n_mm"] for a in bench.ANGLES}
    outside = {str(a): 10 * ref[a]["max_n_mm"] for a in bench.ANGLES}

    def rec(forces):
        return {"picture_frame": {"f_norm_n_mm": forces, "locking_angle_deg": 40.0,
                                  "flagged_deg": [[0.0, 5.0]], "n_beads": 10, "wall_s": 1.0}}

    text = bench.section({"in": rec(inside), "out": rec(outside)})
    ratios = [line for line in text.splitlines() if line.startswith("| in |")
              or line.startswith("| out |")][-2:]
    assert "outside" not in ratios[0] and ratios[0].count("| 1 ") == 4
    assert ratios[1].count("(outside)") == 4
    assert "0–5°" in text


def test_twill_measurements_cover_the_report_angles_and_rise():
    bench = load()
    ref = bench.measured(fabric="twill")
    assert set(bench.ANGLES) <= set(ref)
    for a, r in ref.items():
        assert r["min_n_mm"] <= r["median_n_mm"] <= r["max_n_mm"], a
    medians = [ref[a]["median_n_mm"] for a in sorted(ref)]
    assert medians == sorted(medians)
    # Fig. 29's spread (N/mm) is over twice the plain weave's at 30 and 40 deg, where the
    # paper calls it "much greater"; at 10 and 20 deg it is not larger
    plain = bench.measured()

    def spread(r, a):
        return r[a]["max_n_mm"] - r[a]["min_n_mm"]
    for a in (30, 40):
        assert spread(ref, a) > 2 * spread(plain, a), a
    for a in (10, 20):
        assert spread(ref, a) <= spread(plain, a), a


def test_each_fabric_is_compared_with_its_own_measurements():
    bench = load()
    twill = bench.measured(fabric="twill")
    forces = {str(a): twill[a]["median_n_mm"] for a in bench.ANGLES}
    rec = {"picture_frame": {"f_norm_n_mm": forces, "locking_angle_deg": None,
                             "flagged_deg": [], "n_beads": 10, "wall_s": 1.0},
           "fabric": "twill"}
    text = bench.section({"tw": rec})
    plain_part, twill_part = text.split("### Twintex balanced 2/2 twill")
    assert "| tw |" not in plain_part
    ratio = [line for line in twill_part.splitlines() if line.startswith("| tw |")][-1]
    assert ratio.count("| 1 ") == 4 and "outside" not in ratio  # at the twill's medians
    assert "not stated" in twill_part and "≈ 45" in plain_part


def test_laboratory_curves_agree_with_the_summary_ranges():
    """The per-laboratory curves and the min / max / median file are the same digitisation:
    at every report angle the curves present give the summary's numbers."""
    import statistics

    bench = load()
    for fabric in ("plain", "twill"):
        curves = bench.measured_curves(fabric)
        assert len(curves) == (7 if fabric == "plain" else 4)
        for angle, ref in bench.measured(fabric=fabric).items():
            values = [f[a.index(angle)] for a, f in curves.values() if angle in a]
            assert min(values) == ref["min_n_mm"], (fabric, angle)
            assert max(values) == ref["max_n_mm"], (fabric, angle)
            assert abs(statistics.median(values) - ref["median_n_mm"]) <= 0.0015, (fabric,
                                                                                  angle)


def test_measured_curves_are_read_by_the_simulated_rows_locking_method():
    bench = load()
    locks = bench.measured_locking("plain")
    assert set(locks) == set(bench.measured_curves("plain"))
    found = {s: r for s, r in locks.items() if r["deg"] is not None}
    assert found, "no measured curve reaches a locking angle"
    for source, r in found.items():
        # the locking point lies past the initial branch and before the curve ends
        assert 20.0 < r["deg"] < r["ends_deg"], source
    for r in locks.values():
        if r["deg"] is None:
            assert r["reason"]
    text = bench.section({})
    for source in found:
        assert f"{source} {found[source]['deg']:.1f}°" in text
