"""Report figures: titles, notes and legends never cover data; every axis has a unit;
the summary's quantities are marked on the curve (issue 19).

Every figure a protocol saves during a tiny run is checked as it is saved
(``Figure.savefig`` is wrapped): curves, cut images, previews, drape maps.
"""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from fabmd.engine import Engine  # noqa: E402
from fabmd.results.figure import label_problems, layout_problems  # noqa: E402
from fabmd.results.plots import curves_figure  # noqa: E402

from .fabrics import parallel_fibres, plain_weave_cell  # noqa: E402


@pytest.fixture
def saved(monkeypatch):
    """{file name: problems} of every figure saved while the test runs."""
    found = {}
    original = Figure.savefig

    def checked(self, path, *args, **kwargs):
        found[str(getattr(path, "name", path))] = layout_problems(self) + label_problems(self)
        return original(self, path, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", checked)
    return found


def _clean(found: dict, expected: set[str]) -> None:
    assert expected <= set(found), sorted(found)
    bad = {name: p for name, p in found.items() if p}
    assert not bad, bad


def test_notes_and_legend_sit_beside_the_data():
    x = np.linspace(0, 10, 50)
    fig = curves_figure([{"x": x, "y": x**2, "label": "fabric"}], "elongation [%]",
                        "force per width [N/m]",
                        title="A long title that would run past the right edge of the figure "
                              "if it were not wrapped to the figure's width, as it was before",
                        notes="gauge 16.0 mm, width 8.0 mm\nKE/U after start-up <= 0.0123\n"
                              "4,096 beads",
                        marks=[{"kind": "vline", "x": 3.0, "label": "transition 3 %"},
                               {"kind": "line", "x": [0, 3], "y": [0, 9], "label": "tangent"},
                               {"kind": "point", "x": [5.0], "y": [25.0], "label": "report"}])
    try:
        assert layout_problems(fig) == [] and label_problems(fig) == []
        labels = fig.axes[0].get_legend_handles_labels()[1]
        assert {"transition 3 %", "tangent", "report"} <= set(labels)
    finally:
        plt.close(fig)


def test_the_check_finds_notes_on_the_curve():
    # the old layout: notes in the axes' top-left corner, over a curve that starts there
    fig, ax = plt.subplots(figsize=(6.4, 4.4), layout="constrained")
    x = np.linspace(0, 1, 50)
    ax.plot(x, 1 - x)
    ax.text(0.02, 0.98, "quasi-static: True", transform=ax.transAxes, va="top")
    ax.set_xlabel("time step")
    try:
        problems = layout_problems(fig)
        assert any("overlaps the data region" in p for p in problems)
        assert any("no unit" in p for p in label_problems(fig))
    finally:
        plt.close(fig)


@pytest.mark.lammps
def test_crimp_figures(saved, tmp_path):
    from fabmd.protocols.crimp import Crimp
    from fabmd.scene.outputs import TrajectoryOutput

    Crimp(expansion={"warp": -0.1, "weft": -0.1}, trajectory=TrajectoryOutput(frames=0)).run(
        plain_weave_cell(), tmp_path / "crimp", engine=Engine(progress=False))
    _clean(saved, {"history.png", "sections.png", "cuts.png", "cut_x_1mm.png"})


@pytest.mark.lammps
def test_tension_figure_marks_transition_tangents_and_report_points(saved, tmp_path):
    from fabmd.protocols.tension import Tension
    from fabmd.scene.outputs import TrajectoryOutput

    result = Tension(max_elongation_pct=1.2, trajectory=TrajectoryOutput(frames=0)).run(
        parallel_fibres(n=4), tmp_path / "t", engine=Engine(progress=False))
    _clean(saved, {"curve.png"})
    labels = " ".join(m["label"] for m in result.plots[0]["marks"])
    assert "report points" in labels
    s = result.summary
    if s["transition_elongation_pct"] is not None and 0 < s["transition_elongation_pct"] < 1.2:
        assert "transition" in labels and "tangent" in labels


@pytest.mark.lammps
def test_periodic_figures(saved, tmp_path):
    from fabmd.protocols.periodic import PeriodicShear, PeriodicTension

    from .test_periodic_tests import periodic_parallel_fibres

    cell = periodic_parallel_fibres()
    PeriodicTension(max_strain_pct=0.5).run(cell, tmp_path / "pt", engine=Engine(progress=False))
    PeriodicShear(max_shear_angle_deg=5).run(cell, tmp_path / "ps",
                                             engine=Engine(progress=False))
    _clean(saved, {"curve.png"})


@pytest.mark.lammps
def test_bias_extension_figures(saved, tmp_path):
    from fabmd.protocols.bias_extension import BiasExtension

    from .test_bias_extension import braced_bias_net

    BiasExtension(max_shear_angle_deg=5, speed_fraction=1e-3).run(
        braced_bias_net(), tmp_path / "be", engine=Engine(progress=False))
    _clean(saved, {"curve.png", "shear_angle.png"})


@pytest.mark.lammps
@pytest.mark.slow
def test_drape_figures(saved, tmp_path):
    from fabmd.model.transform import cut, tile
    from fabmd.protocols.crimp import Crimp
    from fabmd.protocols.drape import Drape

    from .test_drape import SMALL

    crimped = Crimp(expansion={"warp": -0.1, "weft": -0.1}).run(
        plain_weave_cell(spacing_ratio=0.9), tmp_path / "crimp", engine=Engine(progress=False))
    blank = cut(tile(crimped.model, 7, 7, periodic=False), 26e-3, 26e-3)
    saved.clear()
    Drape(**SMALL).run(blank, tmp_path / "drape", engine=Engine(progress=False))
    _clean(saved, {"curve.png", "holder_force.png", "shear_angle.png", "shape.png"})


def test_demo_overview_figure(saved, tmp_path):
    from fabmd.cli.demo import _overview
    from fabmd.results.folder import write_csv

    (tmp_path / "t").mkdir()
    (tmp_path / "f").mkdir()
    x = np.linspace(0, 3, 50)
    write_csv(tmp_path / "t" / "curve.csv", {"elongation_pct": x,
                                             "force_per_width_n_m": 1e4 * x**2})
    g = np.linspace(0, 50, 50)
    write_csv(tmp_path / "f" / "curve.csv", {"shear_angle_deg": g,
                                             "normalised_force_n_m": np.exp(g / 10)})
    (tmp_path / "p").mkdir()
    write_csv(tmp_path / "p" / "curve.csv", {"shear_angle_deg": g,
                                             "normalised_force_n_m": 0.5 * np.exp(g / 9)})
    _overview(tmp_path, {"results": str(tmp_path / "t"),
                         "test_summary": {"transition_elongation_pct": 1.81}},
              {"results": str(tmp_path / "f"), "test_summary": {"locking_angle_deg": 40.7}},
              {"results": str(tmp_path / "p"), "test_summary": {"locking_angle_deg": 35.2}})
    _clean(saved, {"demo.png"})


@pytest.mark.lammps
def test_fibre_tension_figure(saved, tmp_path):
    from fabmd.model.material import GLASS, VirtualFibre
    from fabmd.protocols.fibre_tension import FibreTension

    fibre = VirtualFibre.solid(GLASS, 0.5e-3)
    FibreTension(fibre=fibre, length_m=5e-3).run(tmp_path / "ft",
                                                 engine=Engine(progress=False))
    _clean(saved, {"curve.png"})


@pytest.mark.lammps
@pytest.mark.slow
def test_picture_frame_figure(saved, tmp_path):
    from fabmd.protocols.coupon import Coupon
    from fabmd.protocols.crimp import Crimp
    from fabmd.protocols.picture_frame import PictureFrame

    engine = Engine(progress=False)
    crimped = Crimp(expansion={"warp": -0.02, "weft": -0.02}).run(
        plain_weave_cell(spacing_m=1e-3, gap=1.0), tmp_path / "crimp", engine=engine)
    square = Coupon(length_m=6e-3, width_m=6e-3, relax=None).run(
        crimped.model, tmp_path / "coupon", engine=engine).model
    saved.clear()
    result = PictureFrame(max_shear_angle_deg=20).run(square, tmp_path / "pf", engine=engine)
    _clean(saved, {"curve.png"})
    assert any(m["label"] == "report points" for m in result.plots[0]["marks"])
