"""What the fabmd command prints: one line per warning (issue 19)."""

import types
import warnings

from fabmd import cli
from fabmd.errors import OverlapWarning


def test_a_warning_is_one_fabmd_line(monkeypatch, capsys):
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)  # restored after

    def run(args):
        warnings.warn("largest overlap 0.12 d\n  is above the limit", OverlapWarning,
                      stacklevel=2)
        return 0

    probe = types.ModuleType("fabmd.cli.probe")
    probe.add_arguments = lambda p: None
    probe.run = run
    monkeypatch.setitem(__import__("sys").modules, "fabmd.cli.probe", probe)
    monkeypatch.setitem(cli.COMMANDS, "probe", ("probe", "test probe"))
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        assert cli.main(["probe"]) == 0
    err = capsys.readouterr().err
    assert err == "fabmd: warning: largest overlap 0.12 d is above the limit\n"
