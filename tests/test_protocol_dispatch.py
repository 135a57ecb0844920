"""Test names and settings tables to protocol objects (``fabmd.pipeline.build_protocol``)."""

import pytest

from fabmd.engine import Engine
from fabmd.errors import InputError
from fabmd.model.contact import ContactModel
from fabmd.pipeline import TESTS, build_protocol
from fabmd.protocols.bias_extension import BiasExtension
from fabmd.protocols.compaction import Compaction
from fabmd.protocols.periodic import PeriodicShear, PeriodicTension
from fabmd.protocols.picture_frame import PictureFrame
from fabmd.protocols.tension import Tension

from .test_periodic_tests import periodic_parallel_fibres


def test_names_map_to_the_protocols():
    assert isinstance(build_protocol("tension"), Tension)
    assert isinstance(build_protocol("picture-frame"), PictureFrame)
    assert isinstance(build_protocol("bias-extension"), BiasExtension)
    assert isinstance(build_protocol("periodic-tension"), PeriodicTension)
    assert isinstance(build_protocol("periodic-shear"), PeriodicShear)
    assert isinstance(build_protocol("compaction"), Compaction)
    assert set(TESTS) == {"tension", "picture-frame", "bias-extension", "periodic-tension",
                          "periodic-shear", "drape", "compaction"}


def test_settings_tables_become_objects():
    pf = build_protocol("picture-frame", {"max_shear_angle_deg": 55,
                                          "contact": {"friction": 0.1},
                                          "frame_length_m": "105 mm",
                                          "report_angles_deg": [15, 25]})
    assert pf.max_shear_angle_deg == 55
    assert pf.contact == ContactModel(friction=0.1)
    assert pf.frame_length_m == pytest.approx(0.105)
    assert pf.report_angles_deg == (15, 25)


@pytest.mark.parametrize("name,settings,words", [
    ("hemisphere", {}, "must be one of"),
    ("picture-frame", {"max_angle": 40}, "has no key 'max_angle'"),
    ("picture-frame", {"contact": {"mu": 0.2}}, r"\[picture_frame.contact\]"),
    ("bias-extension", {"max_shear_angle_deg": -5}, "bias_extension.max_shear_angle_deg"),
])
def test_bad_settings_are_refused(name, settings, words):
    with pytest.raises(InputError, match=words):
        build_protocol(name, settings)


@pytest.mark.lammps
def test_built_protocol_runs(tmp_path):
    test = build_protocol("periodic-tension", {"max_strain_pct": 0.5})
    result = test.run(periodic_parallel_fibres(), tmp_path / "run", engine=Engine(progress=False))
    assert (tmp_path / "run" / "summary.json").exists()
    assert result.summary["energy_balance"]["relative_error"] < 0.05
