"""``fabmd.cli.test_protocols``: protocol names and settings tables to protocol objects."""

import pytest

from fabmd.cli.test_protocols import PROTOCOLS, build_protocol, run_protocol, summary_line
from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.contact import ContactModel
from fabmd.protocols.bias_extension import BiasExtension
from fabmd.protocols.periodic import PeriodicShear, PeriodicTension
from fabmd.protocols.picture_frame import PictureFrame

from .test_periodic_tests import periodic_parallel_fibres


def test_names_map_to_the_protocols():
    assert isinstance(build_protocol("picture-frame"), PictureFrame)
    assert isinstance(build_protocol("bias-extension"), BiasExtension)
    assert isinstance(build_protocol("periodic-tension"), PeriodicTension)
    assert isinstance(build_protocol("periodic-shear"), PeriodicShear)
    assert set(PROTOCOLS) == {"picture-frame", "bias-extension", "periodic-tension",
                              "periodic-shear"}


def test_settings_tables_become_objects():
    pf = build_protocol("picture-frame", {"max_shear_angle_deg": 55,
                                          "contact": {"friction": 0.1},
                                          "report_angles_deg": [15, 25]})
    assert pf.max_shear_angle_deg == 55
    assert pf.contact == ContactModel(friction=0.1)
    assert pf.report_angles_deg == (15, 25)


@pytest.mark.parametrize("name,settings,words", [
    ("hemisphere", {}, "must be one of"),
    ("picture-frame", {"max_angle": 40}, "unknown setting"),
    ("picture-frame", {"contact": {"mu": 0.2}}, "picture-frame.contact"),
    ("bias-extension", {"max_shear_angle_deg": -5}, "bias_extension.max_shear_angle_deg"),
])
def test_bad_settings_are_refused(name, settings, words):
    with pytest.raises(InputError, match=words):
        build_protocol(name, settings)


@pytest.mark.lammps
def test_run_protocol_runs_and_reports(tmp_path):
    result = run_protocol("periodic-tension", periodic_parallel_fibres(),
                          {"max_strain_pct": 0.5}, tmp_path / "run",
                          engine=Engine(progress=False))
    assert (tmp_path / "run" / "summary.json").exists()
    line = summary_line("periodic-tension", result.summary)
    assert "initial stiffness" in line and "energy balance" in line
