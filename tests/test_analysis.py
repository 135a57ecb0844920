"""Analysis helpers against closed form on synthetic fabrics (pure numpy, no LAMMPS)."""

import math

import numpy as np
import pytest

from fabmd import analysis as A
from fabmd.analysis.synthetic import sinusoid_crimp, sinusoid_curvature, woven_sheet
from fabmd.errors import InputError


def ellipse_frame(a=1.0e-3, b=0.3e-3, pitch=0.04e-3, length=4e-3, beads=41):
    """Straight fibres along x whose centres fill an ellipse of semi-axes a (y) and b (z)."""
    ys = np.arange(-a, a + pitch / 2, pitch)
    zs = np.arange(-b, b + pitch / 2, pitch * math.sqrt(3) / 2)
    centres = [(y + (pitch / 2 if k % 2 else 0.0), z) for k, z in enumerate(zs) for y in ys]
    centres = [(y, z) for y, z in centres if (y / a) ** 2 + (z / b) ** 2 <= 1.0]
    x = np.linspace(0.0, length, beads)
    pos = np.vstack([np.column_stack([x, np.full(beads, y), np.full(beads, z)])
                     for y, z in centres])
    n = len(centres)
    return A.FabricFrame(positions=pos, fibre_ids=np.repeat(np.arange(1, n + 1), beads),
                         fibre_yarn=np.ones(n, int), yarn_names=["warp-0"],
                         yarn_families=["warp"], box_lo=[-1, -1, -1], box_hi=[1, 1, 1])


def test_sinusoidal_yarn_crimp_and_curvature():
    model = woven_sheet(fibres=(3, 2), spacing_m=2e-3)
    frame = A.FabricFrame.from_model(model)
    assert frame.closed.all()  # periodic fibres close across the box
    amp = model.info["amplitude_m"]
    wavelength = 2 * model.info["spacing_m"]
    expected = sinusoid_crimp(amp, wavelength)
    assert expected > 0.005
    crimps = A.crimp_by_yarn(frame)
    assert set(crimps) == {"warp-0", "warp-1", "weft-0", "weft-1"}
    for value in crimps.values():
        assert value == pytest.approx(expected, abs=2e-5)
    by_family = A.crimp_by_family(frame)
    assert by_family["warp"] == pytest.approx(expected, abs=2e-5)

    line = A.yarn_centreline(frame, "warp-0")
    # the centreline of a yarn is the mean of its 6 fibres: the sinusoid through y = s/2
    assert np.allclose(line[:, 1], 0.5 * model.info["spacing_m"], atol=1e-12)
    assert line[-1, 0] - line[0, 0] == pytest.approx(wavelength, rel=1e-9)  # one period
    kappa = A.curvature(line)
    x = line[:, 0] - 0.5 * model.info["spacing_m"]
    exact = sinusoid_curvature(amp, wavelength, x)
    inner = slice(2, -2)
    assert np.max(np.abs(kappa[inner] - exact[inner])) < 0.01 * exact.max()
    assert kappa.max() == pytest.approx(amp * (2 * math.pi / wavelength) ** 2, rel=0.01)


def test_straight_path_has_no_crimp_or_curvature():
    path = np.column_stack([np.linspace(0, 1e-2, 50), np.zeros(50), np.zeros(50)])
    assert A.crimp(path) == pytest.approx(0.0, abs=1e-12)
    assert np.allclose(A.curvature(path), 0.0)
    # a path along the fabric normal has no in-plane length
    with pytest.raises(InputError, match="coincide"):
        A.crimp(path[:, [1, 2, 0]])


@pytest.mark.parametrize("shear_deg", [0.0, 12.5, 35.0, -20.0])
def test_imposed_shear_angle_is_recovered(shear_deg):
    model = woven_sheet(warp_yarns=4, weft_yarns=4, fibres=(2, 1), shear_deg=shear_deg,
                        periodic=False)
    frame = A.FabricFrame.from_model(model)
    field = A.shear_angle_field(frame, cells=(5, 5))
    values = field.values[np.isfinite(field.values)]
    assert values.size >= 8
    assert np.allclose(values, shear_deg, atol=1e-6)
    assert field.mean() == pytest.approx(shear_deg, abs=1e-6)
    warp = A.in_plane_angle_field(frame, "warp", cells=(5, 5)).values
    assert np.allclose(warp[np.isfinite(warp)], 0.0, atol=1e-6)
    weft = field.extra["weft_angle_deg"]
    # yarn directions are axial: 110° is reported as -70°
    assert np.allclose(np.mod(weft[np.isfinite(weft)], 180.0), 90.0 - shear_deg, atol=1e-6)
    assert field.label == "shear angle γ [°]"


def test_shear_field_of_a_periodic_unsheared_sheet_covers_the_box():
    frame = A.FabricFrame.from_model(woven_sheet(warp_yarns=2, weft_yarns=2, fibres=(3, 1)))
    field = A.shear_angle_field(frame, cells=(2, 2))
    assert field.x_edges_m[0] == 0.0 and field.x_edges_m[-1] == pytest.approx(4e-3)
    assert np.allclose(field.values, 0.0, atol=1e-9)
    with pytest.raises(InputError, match="family must be one of"):
        A.shear_angle_field(frame, weft="binder")


def test_ellipse_cross_section_width_and_height():
    a, b = 1.0e-3, 0.3e-3
    frame = ellipse_frame(a, b)
    section = A.cross_section(frame, "warp-0", station=0.5)
    assert np.allclose(np.abs(section.tangent), [1, 0, 0])
    assert len(section.points_m) == frame.n_fibres
    # extent of the fibre centres (no diameters given): 2a wide, 2b high, within a pitch
    assert section.width_m == pytest.approx(2 * a, abs=0.05e-3)
    assert section.height_m == pytest.approx(2 * b, abs=0.05e-3)
    # moment-fitted ellipse and hull area against the ellipse itself
    assert section.ellipse_major_m == pytest.approx(2 * a, rel=0.03)
    assert section.ellipse_minor_m == pytest.approx(2 * b, rel=0.05)
    assert abs(math.sin(section.ellipse_angle_rad)) < 1e-6  # major axis across the yarn
    assert section.area_m2 == pytest.approx(math.pi * a * b, rel=0.08)


def test_cross_section_of_woven_yarn_includes_fibre_diameter():
    model = woven_sheet(fibres=(3, 2), fibre_diameter_m=0.1e-3, pitch=1.05)
    section = A.cross_section(A.FabricFrame.from_model(model), "weft-1", station=0.3)
    assert section.width_m == pytest.approx(2 * 0.105e-3 + 0.1e-3, rel=1e-3)
    assert section.height_m == pytest.approx(0.105e-3 + 0.1e-3, rel=1e-2)
    with pytest.raises(InputError, match="station"):
        A.cross_section(A.FabricFrame.from_model(model), "weft-1", station=1.5)


def test_convex_hull_of_a_square_with_inner_points():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5], [0.2, 0.7], [1, 0.5]])
    hull = A.convex_hull(pts)
    assert len(hull) == 4
    assert {tuple(p) for p in hull} == {(0, 0), (1, 0), (1, 1), (0, 1)}


def test_frame_queries_and_errors():
    frame = A.FabricFrame.from_model(woven_sheet())
    assert frame.families == ["warp", "weft"]
    assert frame.yarns("weft") == ["weft-0", "weft-1"]
    assert len(frame.fibres_of_yarn("warp-1")) == 6
    with pytest.raises(InputError, match="family"):
        frame.yarns("binder")
    with pytest.raises(InputError, match="no yarn named"):
        frame.yarn_id("binder-0")
    with pytest.raises(InputError, match="even numbers"):
        woven_sheet(warp_yarns=3)
