"""The plugin registry: built-ins, lazy entry points, broken plugins, unknown names."""

from importlib.metadata import EntryPoint

import pytest

import sensfw.registry as registry_module
from sensfw.errors import UnknownPluginError


def test_entry_points_load_lazily_and_broken_ones_warn(monkeypatch):
    eps = [EntryPoint("rms_again", "sensfw.scorers.basic:RMS", "sensfw.scorers"),
           EntryPoint("broken", "no_such_module:Thing", "sensfw.scorers")]
    calls = []

    def fake_entry_points(group):
        calls.append(group)
        return [e for e in eps if e.group == group]

    monkeypatch.setattr(registry_module, "entry_points", fake_entry_points)
    from sensfw.plugins import scorers as reg

    reg.get("thd")  # built-ins imported
    monkeypatch.setattr(reg, "_items", dict(reg._items))
    monkeypatch.setattr(reg, "_origin", dict(reg._origin))
    monkeypatch.setattr(reg, "_entry_points_loaded", False)
    assert reg.get("thd").__name__ == "THD"  # a built-in: no entry-point scan needed
    assert calls == []
    with pytest.warns(RuntimeWarning, match="could not load scorer plugin 'broken'"):
        cls = reg.get("rms_again")
    assert cls.__name__ == "RMS"
    assert reg.origin("rms_again") == "entry point sensfw.scorers.basic:RMS"
    assert reg.origin("thd") == "built-in"
    with pytest.raises(UnknownPluginError, match=r"unknown scorer 'nope'; available: .*rms_again"):
        reg.get("nope")


def test_plugins_command_lists_every_kind(cli):
    proc = cli("plugins")
    assert proc.returncode == 0, proc.stderr
    for name in ("definitive_screening", "frf_scalar", "eq18", "shaft_assembly",
                 "flexible_mode", "built-in"):
        assert name in proc.stdout
