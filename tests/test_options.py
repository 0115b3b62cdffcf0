"""One option contract for every plugin kind (issue 26, item 2): declared options with types,
ranges and descriptions, checked by one function (sensfw.options), every problem at once."""

import inspect
import re
from pathlib import Path

import pytest

from sensfw.errors import OptionError, SensfwError
from sensfw.options import build, option_defaults, option_problems, options_model
from sensfw.plugins import ALL, models
from sensfw.scorers import Scorer

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("kind", ["designs", "scorers", "surrogates", "models", "effects"])
def test_every_builtin_declares_its_options_with_what_they_accept(kind):
    """Each built-in option has a description (quoted by the messages); a surrogate
    declares exactly its constructor's arguments (scikit-learn's get_params), and its
    declared defaults are the constructor's."""
    registry = ALL[kind]
    for name in registry.names():
        if registry.origin(name) != "built-in":
            continue
        cls = registry.get(name)
        fields = options_model(cls).model_fields
        for option, field in fields.items():
            assert field.description, (kind, name, option)
        if kind == "surrogates":
            params = {p for p in inspect.signature(cls).parameters}
            assert set(fields) == params, (name, set(fields) ^ params)
            assert option_defaults(cls) == cls().get_params(deep=False), name


def test_all_problems_at_once_and_the_constructors_own():
    """Type and range problems, unknown options and what the constructor finds (a model's
    effects at their places) in one pass."""
    plugin, problems = build(models.get("shaft_assembly"), {
        "linearised": 1, "effects": [{"name": "clearance", "attach": "moon"}], "colour": 2})
    assert plugin is None
    got = dict(problems)
    assert got["colour"] == "unknown option; known: effects, geometry, linearised"
    assert got["linearised"] == "linearised must be true or false, got 1"
    assert "cannot attach to 'moon'" in got["effects[0].attach"]
    plugin, problems = build(models.get("shaft_assembly"), {"effects": ["clearance"]})
    assert problems == [] and plugin.effects[0].attach == "clutch_drive"


def test_the_readme_plugin_example_declares_typed_options():
    """The worked scorer of the README, run as written: its option is typed and checked
    like a built-in's."""
    text = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(# mypkg/peak\.py\n.*?)```", text, re.S).group(1)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)
    peak = namespace["PeakFRF"]
    assert peak(band=[100, 200]).options == {"band": [100, 200]}
    assert peak().options == {"band": (50.0, 5000.0)}
    with pytest.raises(SensfwError, match=r"scorer 'peak_frf': band must be \[fmin, fmax\] in "
                                          r"Hz, got 'wide'"):
        peak(band="wide")


def test_a_plugin_without_declared_options_keeps_untyped_ones():
    """A third-party plugin written against the older contract: a scorer's ``defaults`` dict,
    a surrogate's or model's constructor arguments are its options; unknown keys are still
    named, and what its constructor raises is a problem of its options."""

    class Old(Scorer):
        name = "old"
        defaults = {"width": 3}  # noqa: RUF012  (as a third-party plugin writes it)

        def score(self, signals, reference=None):
            return {"value": 0.0}

    assert option_problems(Old, {"width": "any"}) == []
    assert option_problems(Old, {"widht": 1}) == [("widht", "unknown option; known: width")]

    class Estimator:
        def __init__(self, alpha=1.0, seed=None):
            if alpha <= 0:
                raise ValueError("alpha must be positive")

    assert option_defaults(Estimator) == {"alpha": 1.0, "seed": None}
    assert option_problems(Estimator, {"beta": 1}) == [
        ("beta", "unknown option; known: alpha, seed")]
    assert build(Estimator, {"alpha": -1}) == (
        None, [(None, "invalid options (ValueError: alpha must be positive)")])


def test_an_option_error_names_every_problem():
    from sensfw.designs import make_design

    with pytest.raises(OptionError) as info:
        make_design("morris", trajectories=1, levels=3, colour="red")
    assert [p for p, _ in info.value.problems] == ["colour", "trajectories", "levels"]
    assert info.value.option == "colour"
    assert str(info.value).startswith("design 'morris': colour: unknown option")


def test_an_effect_without_its_own_options_takes_its_constructors():
    """The README: a plugin without ``Options`` takes its constructor's keyword arguments
    (untyped). An effect inherits ``Effect.Options`` (attach only), which hid them: a
    study's ``power = 2.0`` was 'unknown option; known: attach'. And an option at other
    than its default enters the effect's spec, so the runs' hash: two powers are two runs."""
    from sensfw.effects import Effect

    class Scaled(Effect):
        name = "scaled_test"
        fits = ("contact",)

        def __init__(self, attach=None, power=1.0):
            super().__init__(attach)
            self.power = float(power)

        def apply(self, place, hooks, p):
            pass

    assert option_problems(Scaled, {"attach": "x", "power": 2.0}) == []
    assert option_problems(Scaled, {"pwer": 2.0}) == [
        ("pwer", "unknown option; known: attach, power")]
    assert Scaled("x", power=2.0).spec() == {"name": "scaled_test", "attach": "x", "power": 2.0}
    assert Scaled("x").spec() == {"name": "scaled_test", "attach": "x"}
