"""Study files edited with tomlkit (``sensfw augment``): the user's comments and layout stay,
the added lines load back (issue 12, item 4)."""

import tomllib
from pathlib import Path

import pytest

from sensfw.plugins import effects
from sensfw.study import Study
from sensfw.study.edit import add_effect

ROOT = Path(__file__).resolve().parents[1]
QUICK = (ROOT / "studies" / "quick.toml").read_text(encoding="utf-8")


def calibrated(name, scale=1.1):
    return {p.name: {"min": p.min, "nominal": p.nominal * scale, "max": p.max}
            for p in effects.get(name)().parameters()}


def comment_lines(text):
    return [ln for ln in text.splitlines() if "#" in ln]


def test_augmenting_quick_keeps_every_comment_and_loads(tmp_path):
    assert len(comment_lines(QUICK)) >= 3  # full-line and end-of-line comments
    params = calibrated("flexible_mode")
    text = add_effect(QUICK, "flexible_mode", "crankshaft", params, "[augmented 😀]")
    new_lines = text.splitlines()
    for line in QUICK.splitlines():  # every original line, comments included, is still there
        assert line in new_lines, line
    f = tmp_path / "study.toml"
    f.write_text(text, encoding="utf-8")
    study = Study.load(f)
    data = tomllib.loads(text)
    assert data["model"]["options"]["effects"] == [{"name": "flexible_mode",
                                                    "attach": "crankshaft"}]
    for k, v in params.items():
        assert data["parameters"][k] == pytest.approx(v)
        assert study.parameters[k].nominal == pytest.approx(v["nominal"])
    assert data["study"]["description"] == "[augmented 😀]"
    # the rest of the study reads exactly as before
    before = tomllib.loads(QUICK)
    assert data["stages"] == before["stages"] and data["excitation"] == before["excitation"]


@pytest.mark.parametrize("existing", [
    '[model]\nname = "shaft_assembly"  # the model\n'
    'options = { effects = [{ name = "damping" }] }\n',
    '[model]\nname = "shaft_assembly"\n\n# an effect already there\n'
    '[[model.options.effects]]\nname = "damping"\n',
])
def test_an_effect_is_appended_to_the_effects_already_there(existing):
    head = QUICK.split("[model]")[0]
    rest = QUICK.split("[excitation]")[1]
    text = head + existing + "\n[excitation]" + rest
    out = add_effect(text, "flexible_mode", "crankshaft", {}, "")
    assert all(c in out for c in comment_lines(text))
    eff = tomllib.loads(out)["model"]["options"]["effects"]
    assert [e["name"] for e in eff] == ["damping", "flexible_mode"]


def test_non_ascii_strings_round_trip():
    # the hand-written writer this replaces wrote "😀" as a surrogate pair tomllib rejects
    for s in ("😀", "é ü ß", 'quote " and \\ backslash', "tab\tnew\nline", "a\u2028b"):
        out = add_effect(QUICK, "flexible_mode", "crankshaft", {}, s)
        assert tomllib.loads(out)["study"]["description"] == s


def test_augment_command_writes_the_users_file_with_the_effect(tmp_path, monkeypatch):
    """The command's glue (calibration replaced by a stub: it is tested in
    tests/measure): study.toml in the output folder is the user's file plus the effect,
    written by the library (:func:`sensfw.measure.augment.augmented_study`)."""
    from types import SimpleNamespace

    from typer.testing import CliRunner

    import sensfw.measure.augment
    import sensfw.measure.prepared
    import sensfw.report.diagnosis
    from sensfw.cli import app
    from sensfw.measure.augment import augmented_study

    params = {k: v["nominal"] for k, v in calibrated("flexible_mode", 1.2).items()}
    monkeypatch.setattr(sensfw.measure.prepared, "load_measurements",
                        lambda study, files: [SimpleNamespace(file=f) for f in files])

    def stub(study, meas, runner, name, attach, study_text=None, **kw):
        result = {"effect": name, "attach": "crankshaft", "params": params,
                  "trajectory": [{"step": "calibrated", "error": 1.0}]}
        return {**result, "study_text": augmented_study(study_text, study, result, meas)}

    monkeypatch.setattr(sensfw.measure.augment, "augment", stub)
    monkeypatch.setattr(sensfw.report.diagnosis, "write_augment_report", lambda *a, **k: None)
    study = tmp_path / "mine.toml"
    study.write_text("# my study 😀\n" + QUICK, encoding="utf-8")
    out = tmp_path / "aug"
    res = CliRunner().invoke(app, ["augment", str(study), "-m", "m.csv", "--effect",
                                   "flexible_mode", "--out", str(out), "--no-progress"])
    assert res.exit_code == 0, res.output
    text = (out / "study.toml").read_text(encoding="utf-8")
    lines = iter(text.splitlines())  # every line of the user's file, in its order
    assert all(any(new == old for new in lines) for old in ("# my study 😀\n" + QUICK)
               .splitlines())
    data = tomllib.loads(text)
    assert data["model"]["options"]["effects"] == [{"name": "flexible_mode",
                                                    "attach": "crankshaft"}]
    assert data["parameters"]["flex_frequency"]["nominal"] == pytest.approx(
        params["flex_frequency"])
    assert "augmented with flexible_mode@crankshaft, calibrated against m.csv" in \
        data["study"]["description"]


def test_an_effect_is_added_with_its_options():
    """``add_effect(..., options=...)`` writes the effect's own options into its entry, and
    the study built from the file passes them to the model (the beam's micro-slip joint
    with 6 Jenkins elements instead of the default 3)."""
    from sensfw.study import Study

    text = (ROOT / "studies" / "bert.toml").read_text(encoding="utf-8")
    out = add_effect(text, "micro_slip", "joint", {}, "", options={"elements": 6})
    assert all(c in out for c in comment_lines(text))
    eff = tomllib.loads(out)["model"]["options"]["effects"]
    assert eff[-1] == {"name": "micro_slip", "attach": "joint", "elements": 6}
    study = Study.from_dict(tomllib.loads(out), "bert")
    assert study.model.effects[-1].spec() == eff[-1]


def test_augment_command_passes_the_effects_options(tmp_path, monkeypatch):
    """``sensfw augment --option elements=6`` reaches the calibration as an integer and the
    augmented study's effect entry carries it (the glue; the calibration is stubbed)."""
    from types import SimpleNamespace

    from typer.testing import CliRunner

    import sensfw.measure.augment
    import sensfw.measure.prepared
    import sensfw.report.diagnosis
    from sensfw.cli import app
    from sensfw.measure.augment import augmented_study

    monkeypatch.setattr(sensfw.measure.prepared, "load_measurements",
                        lambda study, files: [SimpleNamespace(file=f) for f in files])
    seen = {}

    def stub(study, meas, runner, name, attach, study_text=None, options=None, **kw):
        seen["options"] = options
        result = {"effect": name, "attach": "joint", "params": {}, "options": options,
                  "trajectory": [{"step": "calibrated", "error": 1.0}]}
        return {**result, "study_text": augmented_study(study_text, study, result, meas)}

    monkeypatch.setattr(sensfw.measure.augment, "augment", stub)
    monkeypatch.setattr(sensfw.report.diagnosis, "write_augment_report", lambda *a, **k: None)
    study = tmp_path / "beam.toml"
    study.write_text((ROOT / "studies" / "bert.toml").read_text(encoding="utf-8"),
                     encoding="utf-8")
    out = tmp_path / "aug"
    res = CliRunner().invoke(app, ["augment", str(study), "-m", "m.csv", "--effect",
                                   "micro_slip@joint", "--option", "elements=6", "--out",
                                   str(out), "--no-progress"])
    assert res.exit_code == 0, res.output
    assert seen["options"] == {"elements": 6}
    eff = tomllib.loads((out / "study.toml").read_text(encoding="utf-8"))
    assert eff["model"]["options"]["effects"][-1] == {"name": "micro_slip",
                                                      "attach": "joint", "elements": 6}
    bad = CliRunner().invoke(app, ["augment", str(study), "-m", "m.csv", "--effect",
                                   "micro_slip@joint", "--option", "elements", "--out",
                                   str(out), "--no-progress"])
    assert bad.exit_code != 0 and "KEY=VALUE" in bad.output


def test_augment_rejects_an_effect_option_out_of_range_before_any_run():
    """An effect option the effect's declaration rejects (micro_slip's elements: 1-64) is
    an error naming the option, raised before the calibration's first simulation."""
    from sensfw.errors import SensfwError
    from sensfw.measure.augment import augment
    from sensfw.study import Study

    study = Study.load(ROOT / "studies" / "bert.toml")
    with pytest.raises(SensfwError, match="elements"):
        augment(study, [], None, "micro_slip", "joint", options={"elements": 0})
    with pytest.raises(SensfwError, match="unknown option"):
        augment(study, [], None, "micro_slip", "joint", options={"element": 6})
