"""Compaction between rigid platens: a tiny periodic plain-weave cell (seconds)."""

import numpy as np
import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.contact import ContactModel, ToolContact
from fabmd.protocols.compaction import Compaction, thickness_at
from fabmd.results.folder import read_csv

from .fabrics import plain_weave_cell


def test_thickness_at_interpolates_the_first_crossing():
    p = np.array([0.0, 500.0, 1500.0, 20000.0])
    h = np.array([2.0, 1.8, 1.6, 1.0])
    got = thickness_at(p, h, (1e3, 1e4, 1e6))
    assert got["1000"] == pytest.approx(1.7)
    assert thickness_at(p[2:], h[2:], (1e3,))["1000"] is None  # starts above 1 kPa
    assert got["10000"] == pytest.approx(1.6 - 0.6 * (1e4 - 1500) / 18500)
    assert got["1e+06"] is None


def test_bad_settings_fail_before_lammps():
    with pytest.raises(InputError, match="compaction.max_pressure_pa must be > 0"):
        Compaction(max_pressure_pa=0)
    with pytest.raises(InputError, match="compaction.max_travel_fraction"):
        Compaction(max_travel_fraction=1.0)
    assert Compaction(max_pressure_pa="50 kPa").max_pressure_pa == 5e4
    with pytest.raises(InputError, match="periodic in x and y"):
        Compaction().input_text(plain_weave_cell(periodic=False))


@pytest.mark.lammps
def test_thickness_falls_monotonically_with_pressure(tmp_path):
    cell = plain_weave_cell()
    # soft contact (per unit length): the crossings and platen contacts give way visibly
    soft = {"normal_stiffness_pa": "10 MPa"}
    test = Compaction(max_pressure_pa="20 kPa", datasheet_pressure_pa="5 kPa",
                      speed_fraction=1e-4, samples=100, contact=ContactModel(**soft),
                      tool=ToolContact(friction=0.2, **soft))
    s = test.run(cell, tmp_path / "c", engine=Engine(progress=False)).summary
    assert s["pressure_reached"]
    assert s["thickness_monotone"]
    assert s["quasi_static"]["ok"], s["quasi_static"]["problems"]
    h = s["thickness_at_pressure_m"]
    assert h["5000"] > h["10000"]
    # the curve starts where both platens carry the load; below that nothing is reported
    assert (h["1000"] is None) == (s["contact_pressure_pa"] > 1e3)
    assert h["100000"] is None  # the platen turned back at 20 kPa
    # the platens touched the outermost beads at the start: h(0) = the cell's z extent
    z, r = cell.positions[:, 2], 0.25e-3
    assert s["starting_gap_m"] == pytest.approx(z.max() - z.min() + 2 * r)
    # two stacked single-fibre yarns cannot get thinner than two diameters (less overlap)
    assert s["min_thickness_m"] > 2 * 0.5e-3 * (1 - 2 * s["max_overlap_ratio"])
    curve = read_csv(tmp_path / "c" / "curve.csv")
    assert set(curve) >= {"pressure_pa", "thickness_m", "phase"}
    assert (curve["phase"] < 0).any()  # it unloaded
    assert (tmp_path / "c" / "curve.png").exists()


def test_scene_table_and_contact_reach_the_protocol():
    from fabmd.pipeline import build_protocol

    c = build_protocol("compaction", {"max_pressure_pa": "150 kPa",
                                      "datasheet_pressure_pa": "100 kPa",
                                      "tool": {"friction": 0.1}},
                       contact=ContactModel(normal_stiffness_pa="1 GPa"))
    assert c.max_pressure_pa == 1.5e5 and c.datasheet_pressure_pa == 1e5
    assert c.contact.normal_stiffness_pa == 1e9 and c.tool.friction == 0.1
