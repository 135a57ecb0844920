"""The cluster projection's log reader, decomposition, rank choice and step scaling (no
LAMMPS)."""

import dataclasses
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

LOG = """\
Loop time of 43.7277 on 2 procs for 2000 steps with 16384 atoms

21.1% CPU use with 2 MPI tasks x 1 OpenMP threads

MPI task timing breakdown:
Section |  min time  |  avg time  |  max time  |%varavg| %total
---------------------------------------------------------------
Pair    | 1.1497     | 1.1903     | 1.2308     |   3.7 |  2.72
Bond    | 0.34689    | 0.38775    | 0.42861    |   6.6 |  0.89
Neigh   | 6.1074     | 6.7833     | 7.4592     |  26.0 | 15.51
Comm    | 14.649     | 16.022     | 17.395     |  34.3 | 36.64
Output  | 8.508e-05  | 0.0088991  | 0.017713   |   9.3 |  0.02
Modify  | 8.37       | 8.6861     | 9.0021     |  10.7 | 19.86
Other   |            | 10.65      |            |       | 24.35

Nlocal:           8192 ave        8194 max        8190 min
Histogram: 1 0 0 0 0 0 0 0 0 1
Nghost:            294 ave         296 max         292 min
Histogram: 1 0 0 0 0 0 0 0 0 1
Neighs:         7039.5 ave        7041 max        7038 min
Histogram: 1 0 0 0 0 0 0 0 0 1

Total # of neighbors = 14079
"""


@pytest.fixture(scope="module")
def bench():
    from .test_benchmarks import load_benchmark

    return load_benchmark("cluster_projection")


def test_the_timing_breakdown_of_the_last_run_is_read(bench):
    first = LOG.replace("43.7277 on 2 procs for 2000", "1.0 on 2 procs for 10")
    closing = "Loop time of 0.001 on 2 procs for 0 steps with 16384 atoms\n"
    got = bench.timing_breakdown(first + "\n" + LOG + closing)
    assert (got["loop_s"], got["ranks"], got["steps"], got["atoms"]) == (43.7277, 2, 2000, 16384)
    assert set(got["sections"]) == set(bench.SECTIONS)
    assert got["sections"]["Comm"] == {"avg_s": 16.022, "pct": 36.64}
    assert got["sections"]["Other"] == {"avg_s": 10.65, "pct": 24.35}
    assert got["nghost"] == {"ave": 294.0, "max": 296.0}
    assert got["nlocal"]["ave"] == 8192.0 and got["cpu_use_pct"] == 21.1
    with pytest.raises(ValueError, match="did not finish"):
        bench.timing_breakdown("Step Time\n 0 0\n")


def test_the_loading_run_is_cut_and_the_relaxation_skipped(bench):
    text = "fix a all nve\nrun 50000\nunfix a\nrun             53868\nrun 0 pre no post no\n"
    assert bench.fixed_steps(text, 6000) == (
        "fix a all nve\nrun 0\nunfix a\nrun 6000\nrun 0 pre no post no\n")


def test_a_sheet_is_cut_across_its_length_and_then_into_patches(bench):
    sheet = bench.Sheet(beads=1e6, lx_m=0.2, ly_m=0.1, ghost_width_m=0.001)
    sigma = sheet.density_per_m2
    g2, side2 = bench.ghosts(sheet, 2)
    assert g2 == pytest.approx(sigma * 0.001 * 0.1) and side2 == pytest.approx(0.1)
    g8, _ = bench.ghosts(sheet, 8)  # 4 x 2 patches of 50 x 50 mm: 2 inner x-edges, 1 y
    assert g8 == pytest.approx(sigma * 0.001 * (2 * 0.05 + 0.05))
    assert bench.ghosts(sheet, 2, factor=1.5)[0] == pytest.approx(1.5 * g2)


def test_ranks_are_the_largest_count_at_the_efficiency(bench):
    sheet = bench.Sheet(beads=1e6, lx_m=0.2, ly_m=0.2, ghost_width_m=0.001)
    model = bench.CostModel(alpha_s=1e-7, beta_s=1e-6, ghost_factor=1.0)
    p = bench.ranks_at_efficiency(model, sheet)
    t1 = bench.step_time_s(model, sheet, 1)

    def efficiency(n):
        return t1 / (n * bench.step_time_s(model, sheet, n))

    assert p > 1 and efficiency(p) >= 0.7
    after = bench.RANK_STEPS[bench.RANK_STEPS.index(p) + 1]
    assert efficiency(after) < 0.7
    # free communication: only the patch width (4 ghost cutoffs) limits the ranks
    free = bench.ranks_at_efficiency(dataclasses.replace(model, beta_s=0.0), sheet)
    assert min(bench.ghosts(sheet, free)[1], 1.0) >= 4 * sheet.ghost_width_m


def run(loop, ghosts, comm, steps=1000, atoms=20_000):
    return {"loop_s": loop, "steps": steps, "atoms": atoms, "nghost": {"ave": ghosts},
            "sections": {"Comm": {"avg_s": comm, "pct": 0.0}}}


def test_the_two_rank_fit_reproduces_the_measured_pair(bench):
    sheet = bench.Sheet(beads=20_000, lx_m=0.12, ly_m=0.04, ghost_width_m=0.001)
    model = bench.fit_two_ranks({"1": run(10.0, 0, 0.01), "2": run(6.0, 400, 0.5)}, sheet)
    assert bench.step_time_s(model, sheet, 1) == pytest.approx(10.0 / 1000)
    assert bench.step_time_s(model, sheet, 2) == pytest.approx(6.0 / 1000)
    assert bench.ghosts(sheet, 2, model.ghost_factor)[0] == pytest.approx(400)


def test_the_ghost_cost_comes_from_the_periodic_copy_on_one_rank(bench):
    sheet = bench.Sheet(beads=20_000, lx_m=0.12, ly_m=0.04, ghost_width_m=0.001)
    pair = {"1": run(10.0, 0, 0.01), "2": run(9.0, 400, 4.0),  # 2 ranks: loaded, waiting
            "plain": run(4.0, 0, 0.01, steps=500), "periodic": run(4.5, 2000, 0.2, steps=500)}
    model = bench.fit(pair, sheet)
    assert model.alpha_s == pytest.approx(10.0 / (1000 * 20_000))
    assert model.beta_s == pytest.approx(0.5 / (500 * 2000))  # the loop difference
    pair["periodic"] = run(4.1, 2000, 0.2, steps=500)  # less than its Comm: the Comm
    assert bench.fit(pair, sheet).beta_s == pytest.approx(0.2 / (500 * 2000))
    rim = sheet.density_per_m2 * sheet.ghost_width_m * 2 * (0.12 + 0.04)
    assert model.ghost_factor == pytest.approx(2000 / rim)
    pair["1"]["cpu_use_pct"] = 50.0  # other jobs had half the core: its own time counts
    assert bench.fit(pair, sheet).alpha_s == pytest.approx(5.0 / (1000 * 20_000))


def test_steps_and_beads_at_more_fibres_follow_the_plan_built_there(bench):
    """The projection's scaling from one fibre (time step ratio, beads × n·d1/dn) against
    the plan and the model fabmd builds at 7 fibres: a small plain-weave coupon."""
    from fabmd.model.transform import tile
    from fabmd.scenefile import load_scene
    from fabmd.stages import periodic_cell, protocol_stage

    scene = load_scene(ROOT / "examples" / "plain_weave.toml")
    protocol = protocol_stage(scene, "tension")
    one = bench.with_fibres(scene, 1)
    model = tile(periodic_cell(one), 3, 1, periodic=False)
    one_protocol = protocol_stage(one, "tension")  # its contact law on the one-fibre fibre
    target = bench.describe_target("t", "tension", model, one_protocol.plan(model).steps, 0,
                                   bench.per_fibres(one, one_protocol.plan_contacts(),
                                                    one_protocol.time_step))
    sheet, steps = bench.at_fibres(target, 7)
    seven = tile(periodic_cell(bench.with_fibres(scene, 7)), 3, 1, periodic=False)
    assert sheet.beads == pytest.approx(seven.n_beads, rel=0.03)
    # the loading time is not the same: the gauge follows the clamped beads' size (at one
    # fibre 0.8 mm beads; on the staggered example 2.76e-4 s at 1 fibre, 2.94e-4 s at 7)
    assert steps == pytest.approx(protocol.plan(seven).steps, rel=0.05)
    assert bench.at_fibres(target, 1)[1] == one_protocol.plan(model).steps
