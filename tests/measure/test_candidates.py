"""Diagnosis's candidate list is checked before anything runs (it was checked after H0's
global calibration: a typo cost 47 s and 84 simulations)."""

from pathlib import Path

import pytest

from sensfw.errors import SensfwError
from sensfw.measure.diagnose import diagnose
from sensfw.measure.hypotheses import candidate_names
from sensfw.study import Study

QUICK = Path(__file__).resolve().parents[2] / "studies" / "quick.toml"


class NoRuns:
    workers = 1

    def run(self, *a, **k):
        raise AssertionError("a simulation was started")


@pytest.mark.parametrize("given,message", [
    ("flexible_mod@driveshaft", "unknown effect 'flexible_mod'"),
    ("flexible_mode@nowhere", "the model has no place 'nowhere' that flexible_mode fits"),
    ("added_mass,,", "an empty effect name"),
    ("micro_slip", "micro_slip: it fits no place of the model shaft_assembly"),
])
def test_a_bad_candidate_is_refused_before_any_run(given, message):
    study = Study.load(QUICK)
    with pytest.raises(SensfwError, match=message):
        diagnose(study, [], NoRuns(), candidates=given.split(","))


def test_a_candidate_given_twice_is_raced_once():
    """``added_mass@driveshaft`` three times (once through ``added_mass``): both finalist
    slots went to the same hypothesis, and the ranking listed it three times."""
    study = Study.load(QUICK)
    notes = []
    got = candidate_names(study, ["added_mass@driveshaft", "added_mass@driveshaft",
                                  "added_mass", "damping@crankshaft"], notes.append)
    assert got == [("added_mass", None), ("damping", "crankshaft")]
    assert any("given twice" in n for n in notes)


def test_augment_refuses_a_place_given_as_an_option():
    """``--effect flexible_mode@driveshaft --option attach=clutch`` calibrated the effect at
    the clutch and wrote it there, without a word."""
    from sensfw.measure.augment import augment

    with pytest.raises(SensfwError, match="its place is not an option; give it as "
                                          "flexible_mode@PLACE"):
        augment(Study.load(QUICK), [], NoRuns(), "flexible_mode", "driveshaft",
                options={"attach": "clutch"})


def test_the_default_candidates_are_the_effects_that_fit_the_model():
    """Without a list, every registered effect at the places it fits: micro_slip (a joint
    effect) fits no place of the shaft model and is left out, not an error."""
    from sensfw.plugins import effects

    got = candidate_names(Study.load(QUICK), None)
    assert "micro_slip" in effects.names() and all(n != "micro_slip" for n, _ in got)
    assert ("added_mass", None) in got and all(p is None for _, p in got)


def test_the_pruned_race_gets_exactly_what_the_signature_classes_left_out():
    """Where no kept candidate explains the screening level, diagnose races the candidates
    the signature classes left out (recovery seeds 2073 and 2082, :func:`pruned`): with
    the classes of seed 2082 (even harmonics alone), the kept and the left-out candidates
    are disjoint, together every candidate, and the left-out ones are those of the effects
    whose classes the measurement does not show (an added mass, a damping among them)."""
    from sensfw.measure import signatures
    from sensfw.measure.calibration import Coordinates
    from sensfw.measure.hypotheses import candidates, pruned
    from sensfw.plugins import effects

    study = Study.load(QUICK)
    base = Coordinates.of(None, [])
    found = {"even_harmonics": True}
    kept = candidates(study, None, found, base)
    left = pruned(study, None, kept, base)
    every = candidates(study, None, {}, base)
    assert {h.name for h in kept}.isdisjoint(h.name for h in left)
    assert sorted(h.name for h in kept + left) == sorted(h.name for h in every)
    assert {h.effect.name for h in left} == {
        n for n in effects.names()
        if not signatures.allows(effects.get(n), found) and any(
            h.effect.name == n for h in every)}
    assert {"added_mass", "damping"} <= {h.effect.name for h in left}
