"""Contact and friction in LAMMPS: exclusion, overlap monitor, tool friction, the checks."""

import json
import math

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import OverlapWarning, UnstableRun
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import bead_parameters
from fabmd.model.contact import ContactModel, ToolContact
from fabmd.model.material import GLASS, VirtualFibre
from fabmd.protocols.common import overlap_summary, run_folder, write_run_folder
from fabmd.results.folder import read_print_file
from fabmd.scene import blocks
from fabmd.scene.templates import render

from .conftest import run_cli

pytestmark = pytest.mark.lammps

FIBRE = VirtualFibre.solid(GLASS, 0.1e-3)
B = bead_parameters(FIBRE)  # d = 0.1 mm, s/d = 0.5
D, L0 = B.diameter_m, B.bond_length_m
QUIET = Engine(progress=False)


def fibres(lines: list[np.ndarray], diameters=None) -> BeadModel:
    """One virtual fibre per array of bead positions (bonded in order)."""
    pos = np.vstack(lines)
    ids = np.concatenate([np.full(len(p), i + 1) for i, p in enumerate(lines)])
    starts = np.cumsum([0] + [len(p) for p in lines[:-1]])
    bonds = np.vstack([s + np.column_stack([np.arange(len(p) - 1), np.arange(1, len(p))])
                       for s, p in zip(starts, lines, strict=True)])
    pad = 5 * D
    return BeadModel(positions=pos, diameters=D if diameters is None else diameters,
                     masses=B.mass_kg, atom_types=1, fibre_ids=ids, bonds=bonds, bond_types=1,
                     family_names=("fibre",),
                     bond_type_table=[BondType(B.bond_coefficient, L0, "fibre",
                                               B.axial_stiffness_n)],
                     fibre_yarn=np.ones(len(lines), np.int64), yarns=[Yarn("y", "fibre")],
                     box_lo=pos.min(axis=0) - pad, box_hi=pos.max(axis=0) + pad)


def along_x(n: int, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    return np.column_stack([L0 * np.arange(n), np.full(n, y), np.full(n, z)])


def run_scene(folder, model, contact, body, steps, tools=(), every=1, pair_text=None):
    dt = 0.25 * B.critical_time_step_s(B.spring_n_per_m)
    text = "\n".join([
        blocks.setup(model, "probe", "model.data", dt), blocks.bonds(model),
        pair_text if pair_text is not None else blocks.contact(model, contact, [B]),
        body,
        blocks.overlap_monitor(model, contact, [B], every=every, tool_fixes=tools),
        render("run", steps=steps), render("finish", final_data="final.data")])
    run_dir = write_run_folder(folder, "probe", model, text, {})
    run_folder(QUIET, run_dir, "probe")
    return run_dir


def hairpin() -> BeadModel:
    """One fibre folded back on itself: legs 0.8 d apart, every bond exactly l0 long."""
    leg = along_x(9)
    apex = np.array([[8 * L0 + 0.3 * D, 0.4 * D, 0.0]])
    return fibres([np.vstack([leg, apex, along_x(9, y=0.8 * D)[::-1]])])


def test_beads_of_one_fibre_never_touch(tmp_path):
    """A fibre folded back on itself (legs overlapping by 0.2 d) feels no self-contact.

    (LAMMPS's default special_bonds already drop pairs up to three bonds apart; the
    molecule exclusion covers the rest.) The control run without the exclusion shows
    that the test would catch its loss: the monitor sees the overlap and the legs part.
    """
    model = hairpin()
    contact = ContactModel()
    run_dir = run_scene(tmp_path / "excluded", model, contact, "fix move_all all nve", 300)
    s = overlap_summary(run_dir, contact)
    final = BeadModel.load(run_dir / "final.data", run_dir / "model.json")
    assert s["max_overlap_ratio"] == 0.0
    np.testing.assert_allclose(final.positions, model.positions, atol=1e-9 * D)

    control = blocks.contact(model, contact, [B]).replace(
        "neigh_modify    exclude molecule/intra all", "")
    with pytest.warns(OverlapWarning):
        run_dir = run_scene(tmp_path / "control", model, contact, "fix move_all all nve", 300,
                            pair_text=control)
        s = overlap_summary(run_dir, contact)
    final = BeadModel.load(run_dir / "final.data", run_dir / "model.json")
    assert s["max_overlap_ratio"] == pytest.approx(0.2, rel=1e-6)
    assert np.ptp(final.positions[:, 1]) > 0.85 * D  # the legs were pushed apart


def test_overlap_monitor_sees_an_imposed_overlap(tmp_path):
    model = fibres([along_x(5), along_x(5, y=0.8 * D)])  # held still: no integration
    contact = ContactModel()
    run_dir = run_scene(tmp_path / "a", model, contact, "", 3)
    with pytest.warns(OverlapWarning, match="largest overlap 0.2 d"):
        s = overlap_summary(run_dir, contact)
    assert s["max_overlap_ratio"] == pytest.approx(0.2, rel=1e-9)
    assert s["warnings"] and s["overlap_warning_ratio"] == contact.overlap_warning


def test_overlap_with_two_bead_diameters(tmp_path):
    """Several diameters: the overlap follows from the largest contact force through k_n."""
    big = 2 * D
    model = fibres([along_x(5), along_x(5, y=0.5 * (D + big) - 0.1 * D)],
                   diameters=np.r_[np.full(5, D), np.full(5, big)])
    contact = ContactModel()
    run_dir = run_scene(tmp_path / "b", model, contact, "", 3)
    s = overlap_summary(run_dir, contact, warn=False)
    assert s["max_overlap_ratio"] == pytest.approx(0.1, rel=1e-6)  # 0.1 d over the small d


def test_runaway_overlap_stops_the_run(tmp_path):
    model = fibres([along_x(5), along_x(5, y=0.4 * D)])
    with pytest.raises(UnstableRun) as err:
        run_scene(tmp_path / "c", model, ContactModel(), "", 3)
    assert err.value.cause == "overlap" and "overlap" in str(err.value)


@pytest.mark.parametrize("kind", ["plane", "region"])
def test_tool_overlap_is_reported(tmp_path, kind):
    """Beads 0.05 d into a wall (LAMMPS 22Jul2025: contacts columns 5-7 = contact point)."""
    model = fibres([along_x(3, z=0.45 * D)])
    if kind == "plane":
        wall = blocks.tool_plane(ToolContact(), [B], "z", lo_m=0.0, fix_id="floor")
    else:  # a cylinder along x under the fibre, touching it along its length
        radius = 2 * D
        wall = (f"region drum cylinder x 0.0 {-radius:.10g} {radius:.10g} INF INF side out\n"
                + blocks.tool_region(ToolContact(), [B], "drum", fix_id="floor"))
    run_dir = run_scene(tmp_path / kind, model, None, wall, 2, tools=("floor",),
                        pair_text=render("contact_none"))
    s = overlap_summary(run_dir, None, warn=False)
    assert s["max_tool_overlap_ratio"] == pytest.approx(0.05, rel=1e-6)
    assert s["max_pair_overlap_ratio"] == 0.0


def test_tool_friction_is_coulomb_at_slow_sliding(tmp_path):
    """A fibre pressed on a wall and dragged slowly: F_t/F_n = μ (the tangential spring
    carries it; LAMMPS's classic hooke/history wall gives about 0.01 here)."""
    mu, load = 0.3, 0.5e-3 * B.axial_stiffness_n
    model = fibres([along_x(2, z=0.5 * D)])
    body = "\n".join([
        blocks.tool_plane(ToolContact(friction=mu), [B], "z", lo_m=0.0, fix_id="floor"),
        "variable zero equal 0.0", "variable v equal 0.05", "variable u equal 0.05*time",
        "fix drag all move variable v_u v_zero NULL v_v v_zero NULL",
        f"fix press all addforce 0.0 0.0 {-load / 2:.10g}",
        "compute f all reduce sum fx fz",
        "fix out all ave/time 1 1000 1000 c_f[1] c_f[2] file forces.dat"])
    run_dir = run_scene(tmp_path / "e", model, None, body, 20000, tools=("floor",), every=100,
                        pair_text=render("contact_none"))
    raw = np.loadtxt(run_dir / "forces.dat")
    fx, fz = raw[-1, 1], raw[-1, 2]
    normal = fz + load  # the wall's push (the load is in f as well)
    assert -fx / normal == pytest.approx(mu, rel=1e-3)


def test_capstan_check_passes(tmp_path):
    out = run_cli("validate", "capstan", "--json", "--quiet", "--out", str(tmp_path / "cap"))
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["passed"] and len(result["cases"]) == 4
    cases = {(c["mu"], round(c["theta_rad"], 6)) for c in result["cases"]}
    assert cases == {(mu, round(t, 6)) for mu in (0.1, 0.3) for t in (math.pi / 2, math.pi)}
    for c in result["cases"]:
        assert {"mu", "theta_rad", "expected_ratio", "measured_ratio", "rel_error"} <= set(c)
        assert c["expected_ratio"] == pytest.approx(math.exp(c["mu"] * c["theta_rad"]))
        assert c["rel_error"] < 0.05
        assert c["max_overlap_ratio"] < 0.01
    curve = read_print_file(tmp_path / "cap" / "mu0.3-theta180" / "curve.dat")
    assert curve["load_n"][-1] > 0


def test_sliding_check_passes(tmp_path):
    from fabmd.verification import sliding

    result = sliding.check(out=tmp_path / "sl", engine=QUIET)
    assert result["passed"], result
    for c in result["cases"]:
        assert abs(c["measured_ratio"] / c["mu"] - 1) < 0.05
        # the ripple is reported and is the bead-chain bump: it spans the mean
        assert c["ratio_min"] < c["measured_ratio"] < c["ratio_max"]
        assert c["ratio_std"] > 0
    summary = json.loads((tmp_path / "sl" / "mu0.3-hooke" / "summary.json").read_text())
    assert summary["pair_style"] == "gran/hooke/history" and summary["warnings"] == []
