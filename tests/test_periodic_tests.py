"""Periodic cells loaded by box deformation: closed form on straight fibres, and a crimped
plain-weave cell in tension and trellis shear (seconds)."""

import numpy as np
import pytest

import fabmd
from fabmd.analysis import FabricFrame, zone_shear_angle_deg
from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.bead_model import BeadModel, BondType, Yarn
from fabmd.model.beads import Discretisation, bead_parameters
from fabmd.model.material import VirtualFibre
from fabmd.protocols.crimp import Crimp
from fabmd.protocols.periodic import PeriodicShear, PeriodicTension
from fabmd.results.curves import locking_angle
from fabmd.results.trajectory import read_tilt

from .fabrics import SOFT_GLASS, parallel_fibres, plain_weave_cell

DIAMETER = 0.5e-3


def periodic_parallel_fibres(n=4, length_m=4e-3, gap=1.2) -> BeadModel:
    """``n`` straight fibres along x, each closed across the x faces, ``gap``·d apart in a
    cell periodic in x and y (no contact between them)."""
    fibre = VirtualFibre.solid(SOFT_GLASS, DIAMETER)
    nb = round(length_m / (0.5 * DIAMETER))
    b = bead_parameters(fibre, Discretisation(), bond_length_m=length_m / nb)
    x = np.arange(nb) * b.bond_length_m
    pos = np.vstack([np.column_stack([x, np.full(nb, (j + 0.5) * gap * DIAMETER),
                                      np.zeros(nb)]) for j in range(n)])
    bonds = [(j * nb + i, j * nb + (i + 1) % nb) for j in range(n) for i in range(nb)]
    return BeadModel(
        positions=pos, diameters=DIAMETER, masses=b.mass_kg, atom_types=1,
        fibre_ids=np.repeat(np.arange(1, n + 1), nb), bonds=bonds, bond_types=1,
        family_names=("warp",),
        bond_type_table=[BondType(b.bond_coefficient, b.bond_length_m, "warp",
                                  b.axial_stiffness_n)],
        fibre_yarn=np.arange(1, n + 1), yarns=[Yarn(f"warp-{j}", "warp") for j in range(n)],
        box_lo=[0, 0, -2 * DIAMETER], box_hi=[length_m, n * gap * DIAMETER, 2 * DIAMETER],
        periodic=(True, True, False))


@pytest.mark.lammps
def test_straight_fibres_give_n_ea_over_width(tmp_path):
    n, gap = 4, 1.2
    cell = periodic_parallel_fibres(n=n, gap=gap)
    s = PeriodicTension(max_strain_pct=1.0).run(cell, tmp_path / "pt",
                                                engine=Engine(progress=False)).summary
    ea = SOFT_GLASS.modulus_pa * np.pi * DIAMETER**2 / 4
    width = n * gap * DIAMETER
    assert s["width_m"] == pytest.approx(width)
    assert s["initial_stiffness_n_m_per_width"] == pytest.approx(n * ea / width, rel=0.02)
    assert s["force_per_width_at_strain_n_m"]["0.5"] == pytest.approx(
        n * ea * 0.005 / width, rel=0.02)
    assert s["energy_balance"]["relative_error"] < 0.05
    assert s["max_kinetic_to_strain_energy"] < 0.05


def test_only_periodic_cells_are_accepted():
    with pytest.raises(InputError, match="periodic in x and y"):
        PeriodicTension().prepare(parallel_fibres())
    with pytest.raises(InputError, match="transverse"):
        PeriodicTension(transverse="loose")
    with pytest.raises(InputError, match="max_shear_angle_deg"):
        PeriodicShear(max_shear_angle_deg=80)
    with pytest.raises(InputError, match=r"periodic_shear.locking_initial_deg\[1\]"):
        PeriodicShear(locking_initial_deg=(20.0, 10.0))
    with pytest.raises(InputError, match="periodic_shear.locking_factor"):
        PeriodicShear(locking_factor=1.0)
    with pytest.raises(InputError, match="periodic_shear.release_tension must be true or"):
        PeriodicShear(release_tension="yes")
    with pytest.raises(InputError, match="periodic_shear.release_fraction"):
        PeriodicShear(release_tension=True, release_fraction=0.5)


@pytest.fixture(scope="module")
def woven_cell(tmp_path_factory):
    out = tmp_path_factory.mktemp("cell") / "crimp"
    return Crimp(expansion={"warp": -0.02, "weft": -0.02}).run(
        plain_weave_cell(spacing_m=1e-3, gap=1.0), out, engine=Engine(progress=False)).model


@pytest.mark.lammps
def test_woven_cell_in_tension(woven_cell, tmp_path):
    result = PeriodicTension(max_strain_pct=2.0).run(woven_cell, tmp_path / "pt",
                                                     engine=Engine(progress=False))
    s = result.summary
    assert s["initial_stiffness_n_m_per_width"] > 0
    assert result.curve["force_per_width_n_m"][-1] > result.curve["force_per_width_n_m"][1]
    assert s["energy_balance"]["relative_error"] < 0.05
    assert s["max_kinetic_to_strain_energy"] < 0.05
    assert s["quasi_static_intervals"]["width"] == 0.25  # per 0.25 % of strain
    assert (result.run_dir / "curve.png").exists()


@pytest.mark.lammps
def test_woven_cell_in_trellis_shear(woven_cell, tmp_path):
    result = PeriodicShear(max_shear_angle_deg=45).run(woven_cell, tmp_path / "ps",
                                                       engine=Engine(progress=False))
    s, c = result.summary, result.curve
    assert c["shear_angle_deg"][-1] == pytest.approx(45, abs=0.5)
    assert s["initial_shear_stiffness_n_m_per_rad"] > 0
    assert s["locking"]["found"] and s["locking_angle_deg"] < 45
    # the picture frame's stated method: the same angle wherever the test stops
    g, f = c["shear_angle_deg"], c["normalised_force_n_m"]
    cut = [locking_angle(g[g <= a], f[g <= a])["x"] for a in (s["locking"]["final_range"][1] + 0.5,
                                                             40.0, 45.0)]
    assert max(cut) - min(cut) < 1e-9 and cut[-1] == pytest.approx(s["locking_angle_deg"])
    assert s["locking"]["initial_range"] == [10.0, 20.0]
    assert s["energy_balance"]["relative_error"] < 0.05
    assert s["max_kinetic_to_strain_energy"] < 0.05
    # judged per 5 deg of shear, as the picture frame; each sample carries its interval's
    iv = s["quasi_static_intervals"]
    assert iv["width"] == 5.0 and len(iv["intervals"]) == 9
    assert set(c["interval_quasi_static"]) <= {0.0, 1.0}
    # the trajectory of the sheared (triclinic) cell keeps its tilt: xy = b sin(gamma)
    assert s["trajectory"] == "trajectory.h5"
    b = woven_cell.box_hi[1] - woven_cell.box_lo[1]
    xy = read_tilt(result.run_dir / "trajectory.h5")[0]
    assert xy == pytest.approx(b * np.sin(np.radians(c["shear_angle_deg"][-1])), rel=1e-6)
    u = fabmd.load(result.run_dir)
    u.trajectory[-1]
    assert u.dimensions[5] == pytest.approx(90 - c["shear_angle_deg"][-1], abs=1e-3)
    # the fibres turn with the box: warp stays along x, weft turns to 90 - 45 deg; the
    # closing segments of the fibres are taken across the tilted faces (a sheared cell's
    # nearest image), so they count with their true direction
    *_, final = FabricFrame.iter_trajectory(result.run_dir)
    assert final.tilt[0] == pytest.approx(xy)
    assert zone_shear_angle_deg(final, reference_deg=20.0) == pytest.approx(45, abs=3)


@pytest.mark.lammps
def test_trellis_shear_drag_leaves_the_force_alone(woven_cell, tmp_path):
    """The box carries the fabric: a drag on the absolute velocity is read as shear force
    (on the plain-weave example's cell half the work below 20°), the default drag on the
    motion relative to the box's affine field is not. With the damping time cut 50x
    (1/500 of the test), the work per 10° over 10-30° moves < 0.3 % with the affine drag
    and > 2 % with the absolute one."""
    def work(drag, fraction):
        test = PeriodicShear(max_shear_angle_deg=32, drag=drag,
                             damping_time_s=fraction * PeriodicShear(
                                 max_shear_angle_deg=32).duration_s(woven_cell))
        c = test.run(woven_cell, tmp_path / f"{drag}{fraction}",
                     engine=Engine(progress=False)).curve
        return np.diff(np.interp([10, 20, 30], c["shear_angle_deg"], c["external_work_j"]))

    reference = work("affine", 0.1)
    assert np.abs(work("affine", 0.002) / reference - 1).max() < 0.003
    assert (work("absolute", 0.002) / reference - 1)[0] > 0.02


@pytest.mark.lammps
def test_a_released_cell_loses_its_crimp_tension_and_shears_from_its_own_size(woven_cell,
                                                                              tmp_path):
    """``release_tension``: before the shear the box follows zero membrane force, so the
    crimped cell (its yarns shrunk 2 %, taut) shortens in x and y; the shear then turns the
    released edge (xy = b' sin γ with b' the released ly) and the summary says by how much
    the cell shrank. Without it the cell keeps its size."""
    kept = PeriodicShear(max_shear_angle_deg=10).run(woven_cell, tmp_path / "kept",
                                                     engine=Engine(progress=False))
    assert kept.summary["released"] is None
    result = PeriodicShear(max_shear_angle_deg=10, release_tension=True).run(
        woven_cell, tmp_path / "released", engine=Engine(progress=False))
    released = result.summary["released"]
    assert released["cell_before_m"] == pytest.approx(list(
        (woven_cell.box_hi - woven_cell.box_lo)[:2]))
    assert all(-5 < e < -0.01 for e in released["strain_pct"]), released
    text = (result.run_dir / "in.periodic_shear").read_text()
    assert "press/berendsen x 0.0 0.0" in text and "$(ly:%.15g)" in text
    b = released["cell_after_m"][1]
    xy = read_tilt(result.run_dir / "trajectory.h5")[0]
    g = np.radians(result.curve["shear_angle_deg"][-1])
    assert xy == pytest.approx(b * np.sin(g), rel=1e-4)
    # its membrane forces at the start are far below the taut cell's, and it says so
    n_kept = np.loadtxt(kept.run_dir / "means.dat")[0, 1]
    n_released = np.loadtxt(result.run_dir / "means.dat")[0, 1]
    assert abs(n_released) < 0.2 * abs(n_kept), (n_released, n_kept)
    left = released["membrane_force_at_start_n_m"]
    assert left[0] == pytest.approx(n_released, rel=1e-6)
    assert all(0 < abs(n) < 0.2 * abs(n_kept) for n in left), (left, n_kept)


@pytest.mark.lammps
@pytest.mark.filterwarnings("ignore::fabmd.errors.QuasiStaticWarning")
def test_a_cell_started_with_its_box_needs_no_start_up(woven_cell, tmp_path):
    """Trellis shear at 4e-3: a smooth start puts 0.034 of the box's work over 0-5° into
    the cell's kinetic energy (measured; flagged), a cell started with the box's affine
    velocity field 0.001, and past the start both read the same force."""
    runs = [PeriodicShear(max_shear_angle_deg=25, speed_fraction=4e-3, start=start).run(
        woven_cell, tmp_path / start, engine=Engine(progress=False))
        for start in ("smooth", "affine")]
    smooth, started = ([i["inertia_share"] for i in r.summary["quasi_static_intervals"]
                        ["intervals"][:1]][0] for r in runs)
    assert smooth > 0.02 and started < 0.5 * 0.03 and started < 0.2 * smooth
    ke0 = [r.curve["kinetic_energy_j"][0] for r in runs]
    assert ke0[0] < 1e-6 * ke0[1]  # at rest, or moving with the box
    for angle in ("10", "20"):
        assert (runs[1].summary["normalised_force_at_angle_n_m"][angle]
                == pytest.approx(runs[0].summary["normalised_force_at_angle_n_m"][angle],
                                 rel=0.01))
