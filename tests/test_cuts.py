"""Cross-sections are thin cuts: the beads a plane passes through, at true size (issue 19)."""

import csv

import numpy as np
import pytest

from fabmd.analysis import FabricFrame, fabric_cut
from fabmd.errors import InputError
from fabmd.results.cuts import CUT_GID, cut_figure, cut_pngs

from .conftest import run_cli
from .fabrics import plain_weave_cell


def _expected(model, axis, position):
    """Brute force: beads whose centre is within their radius of the plane."""
    return np.flatnonzero(np.abs(model.positions[:, axis] - position)
                          <= 0.5 * model.diameters)


@pytest.fixture(scope="module")
def fabric():
    return plain_weave_cell(periodic=False, cells=(2, 2))  # 8 x 8 mm, open edges


@pytest.mark.parametrize("normal,axis,position", [("x", 0, 5e-3), ("y", 1, 2.9e-3),
                                                  ("x", 0, 0.1e-3)])
def test_cut_holds_exactly_the_beads_within_half_a_diameter(fabric, normal, axis, position):
    cut = fabric_cut(FabricFrame.from_model(fabric), normal, position)
    assert np.array_equal(cut.indices, _expected(fabric, axis, position))
    assert len(cut.indices) > 0
    other = 1 - axis
    assert np.allclose(cut.points_m[:, 0], fabric.positions[cut.indices, other])
    # a thicker slab holds more: the cut is a slice, not a projection
    slab = fabric_cut(FabricFrame.from_model(fabric), normal, position, half_thickness_m=1e-3)
    assert len(slab.indices) > len(cut.indices)


def test_drawn_circles_are_the_cut_beads_at_true_size(fabric):
    fig, cut = cut_figure(fabric, "x", 5e-3)
    try:
        (coll,) = [c for c in fig.axes[0].collections if c.get_gid() == CUT_GID]
        centres = coll.get_offsets()
        assert np.allclose(centres, 1e3 * fabric.positions[_expected(fabric, 0, 5e-3)][:, [1, 2]])
        assert np.allclose(coll.get_widths(), 1e3 * fabric.diameters[cut.indices])
        # axes span the whole fabric: every bead of the model fits across and through
        lo, hi = fig.axes[0].get_xlim()
        d = 1e3 * fabric.diameters.max()
        assert lo <= 1e3 * fabric.positions[:, 1].min() - d / 2 + 1e-9
        assert hi >= 1e3 * fabric.positions[:, 1].max() + d / 2 - 1e-9
    finally:
        import matplotlib.pyplot as plt
        plt.close(fig)


def test_periodic_cut_wraps_the_plane(fabric):
    cell = plain_weave_cell()  # periodic, 4 x 4 mm
    frame = FabricFrame.from_model(cell)
    length = cell.box_hi[0] - cell.box_lo[0]
    a = fabric_cut(frame, "x", 1.1e-3)  # (not on a tie: beads 0.25 mm apart, d 0.5 mm)
    b = fabric_cut(frame, "x", 1.1e-3 + length)
    assert np.array_equal(a.indices, b.indices) and len(a.indices) > 0


def test_cut_outside_the_fabric_is_refused(fabric):
    with pytest.raises(InputError, match="outside the fabric"):
        fabric_cut(FabricFrame.from_model(fabric), "x", 0.02)


def test_cut_pngs_write_one_figure_per_position_and_an_overview(fabric, tmp_path):
    files = cut_pngs(fabric, tmp_path)
    names = sorted(p.name for p in files)
    assert "cuts.png" in names and len(names) == 5  # two planes each way + overview
    assert all(p.stat().st_size > 1000 for p in files)


def test_measure_cut_at_writes_the_cut_of_the_plane(fabric, tmp_path):
    folder = tmp_path / "state"
    folder.mkdir()
    fabric.save(folder, stem="model")
    proc = run_cli("measure", str(folder), "--cut-at", "5mm", timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert (folder / "cut_x_5mm.png").stat().st_size > 1000
    with open(folder / "cut_x_5mm.csv") as f:
        rows = list(csv.DictReader(f))
    ids = sorted(int(r["bead_id"]) - 1 for r in rows)
    assert ids == sorted(_expected(fabric, 0, 5e-3).tolist())
    assert all(abs(float(r["distance_m"])) <= 0.5 * float(r["diameter_m"]) for r in rows)
    two = run_cli("measure", str(folder), "--cut-at", "2mm", "--cut-at", "3.5 mm",
                  "--cut-normal", "y", "--overwrite", timeout=300)
    assert two.returncode == 0, two.stderr
    assert {"cut_y_2mm.png", "cut_y_3.5mm.png", "cuts.png"} <= {p.name for p in
                                                                folder.iterdir()}
    bad = run_cli("measure", str(folder), "--cut-at", "5", "--overwrite", timeout=300)
    assert bad.returncode == 2 and "outside the fabric" in bad.stderr
    assert "5mm" in bad.stderr  # says how to write it
