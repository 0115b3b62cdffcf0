"""Places a screening level cannot tell apart (sensfw/measure/screening.py,
sensfw/measure/diagnose.py): candidates of one effect whose first looks agree to round-off
share one second look, and join the calibrated one where they tie at its optimum."""

from types import SimpleNamespace

import numpy as np
import pytest

from sensfw.measure.calibration import Coordinates, Fit, Trial
from sensfw.measure.diagnose import _join_twins
from sensfw.measure.hypotheses import Hypothesis
from sensfw.measure.ranking import TIE_BIC
from sensfw.measure.screening import _same_look
from sensfw.plugins import effects


def hypothesis(name: str, place: str) -> Hypothesis:
    eff = effects.get(name)(attach=place)
    return Hypothesis(eff, place, Coordinates.of(None, eff.parameters()))


def test_first_looks_equal_to_round_off_are_one_look():
    w = np.array([3.0, -2.0, 0.5])
    a, b, c = (hypothesis("damping", p) for p in ("bearing_l3", "driveshaft", "flange"))
    d = hypothesis("friction", "bearing_l3")
    a.screen["_w"], b.screen["_w"] = w, w * (1 + 1e-12)
    c.screen["_w"], d.screen["_w"] = w * (1 + 1e-6), w
    assert _same_look(a, b)
    assert not _same_look(a, c)  # a difference the level shows
    assert not _same_look(a, d)  # another effect: other parameters, never shared
    assert not _same_look(a, hypothesis("damping", "bearing_l1"))  # no first look


class _Residuals:
    """Each place's residuals at any point: the calibrated place's, the same (a twin), or
    larger by more than the tie."""

    def __init__(self, w: np.ndarray, by_place: dict[str, np.ndarray]):
        self.w, self.by_place, self.calls = w, by_place, []

    def evaluate(self, specs, points, label, levels=None):
        self.calls.append((specs[0]["attach"], label))
        return [self.by_place[specs[0]["attach"]] for _ in points]


class _Entries:
    """Residuals of ``n`` entries, no runs: what the steps read to rank by BIC."""

    def __init__(self, n: int):
        self.entries = SimpleNamespace(size=lambda: n)


def test_a_twin_joins_the_calibrated_candidate_only_where_it_ties():
    lead, twin, other = (hypothesis("damping", p)
                         for p in ("bearing_l3", "driveshaft", "bearing_l3_shoulder"))
    w = np.array([1.0, 2.0, -1.0])
    J = np.arange(3.0)[:, None]
    lead.fit = Fit(lead.coords, Trial({"extra_damping": 0.2}, w), J)
    twin.screen["twin"] = other.screen["twin"] = lead.name
    worse = np.sqrt(w**2 + (TIE_BIC + 1.0) / len(w))  # chi2 larger by the tie + 1
    res = _Residuals(w, {"driveshaft": w.copy(), "bearing_l3_shoulder": worse})
    calibrated = [lead]
    _join_twins(res, [lead, twin, other], calibrated, log=lambda s: None)
    assert calibrated == [lead, twin]
    assert twin.fit.values == lead.fit.values and twin.fit.chi2 == lead.fit.chi2
    # the same residuals to round-off: the lead's Jacobian (its intervals) stands for both
    assert twin.fit.jacobian is J and twin.fit.info["twin_of"] == lead.name
    assert other.fit is None
    assert sorted(p for p, _ in res.calls) == ["bearing_l3_shoulder", "driveshaft"]


def test_the_leaders_effect_at_places_never_calibrated(monkeypatch):
    """Every place the race never calibrated is run at the leader's optimum; places whose
    runs agree to round-off are one group; the best ``final`` groups that beat the leader
    there are refined (one place each) and the group's other places join where they tie."""
    import sensfw.measure.diagnose as diagnose

    lead, *others = (hypothesis("damping", p) for p in (
        "bearing_l1", "bearing_l3", "bearing_l3_shoulder", "flange", "clutch", "driveshaft"))
    raced = hypothesis("damping", "crankshaft")
    raced.screen["calibrated"] = 30.0  # calibrated in the race: not this step's
    lead.fit = Fit(lead.coords, Trial({"extra_damping": 0.2}, np.full(3, 3.0)), None)  # 27
    at_lead = {"bearing_l3": 2.0, "bearing_l3_shoulder": 2.0, "flange": 2.5, "clutch": 2.9,
               "driveshaft": 4.0}  # chi2 12, 12, 18.75, 25.2, 48
    refined = np.full(3, 1.0)  # chi2 3 after the refinement

    class Res:
        def __init__(self):
            self.calls = []

        def evaluate(self, specs, points, label, levels=None):
            place = specs[0]["attach"]
            self.calls.append((place, label))
            at_refined = "optimum" in label and "bearing_l1" not in label
            return [refined.copy() if at_refined else np.full(3, at_lead[place])]

    def calibrate(res, h, budget, **kw):
        return Fit(h.coords, Trial({"extra_damping": 0.3}, refined.copy()), None)

    monkeypatch.setattr(diagnose, "calibrate_hypothesis", calibrate)
    res, calibrated = Res(), [lead]
    diagnose._places_never_calibrated(res, [lead, raced, *others], lead, calibrated, 2, {},
                                      log=lambda s: None)
    names = [h.place for h in calibrated]
    # bearing_l3 refined, its twin joined at its optimum, flange refined (second group);
    # clutch beat the leader but is third, driveshaft did not
    assert names == ["bearing_l1", "bearing_l3", "bearing_l3_shoulder", "flange"]
    assert calibrated[2].fit.values == calibrated[1].fit.values
    runs = [p for p, label in res.calls if label.endswith("damping@bearing_l1's optimum")]
    assert sorted(runs) == sorted(at_lead)  # one run each, the raced place not again
    assert all(h.fit is None for h in others if h not in calibrated)


def test_the_runner_up_is_refined_only_where_it_stopped_on_its_budget(monkeypatch):
    """The best calibrated candidate after the leader is refined further where its
    DFO-LS ended on its evaluation budget short of the noise, never otherwise."""
    import sensfw.measure.diagnose as diagnose

    n = 40
    lead, second, third = (hypothesis("damping", p)
                           for p in ("bearing_l1", "bearing_l3", "flange"))
    calls = []

    def calibrate(res, h, budget, **kw):
        calls.append((h.place, budget))
        return Fit(h.coords, Trial({"extra_damping": 0.3}, np.ones(n)), None)

    monkeypatch.setattr(diagnose, "calibrate_hypothesis", calibrate)

    def setup(message, scale, lead_scale=1.5):
        for h, s in ((lead, lead_scale), (second, scale), (third, 20.0)):
            h.fit = Fit(h.coords, Trial({"extra_damping": 0.2}, np.full(n, s)), None,
                        info={"refinement": [{"nf": 11, "message": message,
                                              "budget_spent": "max evals" in message}]})
        calls.clear()
        diagnose._finish_runner_up(_Entries(n), [third, lead, second], {},
                                   log=lambda s: None)

    setup("Warning (max evals): Objective has been called MAXFUN times", 3.0)
    assert calls == [("bearing_l3", 6 * second.k + 6)]  # the runner-up only
    assert second.fit.chi2 == n and "refined further" in second.notes[-1]
    setup("Success: rho has reached rhoend", 3.0)  # converged: its optimum
    assert calls == []
    setup("Warning (max evals): Objective has been called MAXFUN times", 1.0, 0.9)
    assert calls == []  # at the noise already
    for h in (lead, second):  # the budget ended before a local least squares ran
        h.fit.info["refinement"] = []
    second.fit.best = Trial({"extra_damping": 0.2}, np.full(n, 3.0))
    diagnose._finish_runner_up(_Entries(n), [lead, second], {}, log=lambda s: None)
    assert calls == [("bearing_l3", 6 * second.k + 6)]


def test_the_named_are_refined_while_they_stop_on_their_budget(monkeypatch):
    """The leader and those within the tie of it are refined further, a round at a time
    (``4 (k + 1)`` points), while their DFO-LS ends on its evaluation budget short of the
    noise and a round gains 5 %; at most ``POLISH_ROUNDS`` rounds; a candidate beyond
    the tie is left alone; a twin joined to a refined place is run at its new optimum."""
    import sensfw.measure.diagnose as diagnose

    n = 40
    maxed = [{"nf": 11, "message": "Warning (max evals): Objective has been called MAXFUN",
              "budget_spent": True}]
    lead, tied, third, twin = (hypothesis("damping", p) for p in
                               ("bearing_l1", "bearing_l3", "flange", "driveshaft"))
    calls = []
    chi2_next = {}

    def calibrate(res, h, budget, **kw):
        calls.append((h.place, budget))
        chi2 = chi2_next[h.place].pop(0)
        return Fit(h.coords, Trial({"extra_damping": 0.3 + len(calls) / 100},
                                   np.full(n, np.sqrt(chi2 / n))), None,
                   info={"refinement": maxed})

    monkeypatch.setattr(diagnose, "calibrate_hypothesis", calibrate)

    class Res(_Entries):
        def __init__(self):
            super().__init__(n)
            self.runs = []

        def evaluate(self, specs, points, label, levels=None):
            self.runs.append((specs[0]["attach"], dict(points[0])))
            return [np.full(n, np.sqrt(100.0 / n))]  # the twin ties at 100

    def fit(h, chi2, message=maxed):
        h.fit = Fit(h.coords, Trial({"extra_damping": 0.2}, np.full(n, np.sqrt(chi2 / n))),
                    None, info={"refinement": message})

    fit(lead, 1000.0)
    fit(tied, 1001.0)
    fit(third, 1100.0)
    twin.fit = diagnose._twin_fit(twin, lead, lead.fit.best.w)
    # the leader gains every round: three rounds; the tied one gains 2 %: one round
    chi2_next.update(bearing_l1=[500.0, 200.0, 100.0, 50.0], bearing_l3=[980.0, 900.0])
    res = Res()
    diagnose._polish_named(res, [third, lead, tied, twin], {}, log=lambda s: None)
    budget = 4 * (lead.k + 1)
    assert calls == [("bearing_l1", budget)] * 3 + [("bearing_l3", budget)]
    assert [h.fit.chi2 for h in (lead, tied, third)] == pytest.approx([100.0, 980.0, 1100.0])
    assert res.runs == [("driveshaft", lead.fit.values)]
    assert twin.fit.values == lead.fit.values and twin.fit.info["twin_of"] == lead.name

    calls.clear()  # converged, or at the noise: its optimum, nothing to refine
    fit(lead, 1000.0, [{"nf": 9, "message": "Success: rho has reached rhoend",
                        "budget_spent": False}])
    fit(tied, float(n), maxed)
    diagnose._polish_named(Res(), [lead, tied], {}, log=lambda s: None)
    assert calls == []
