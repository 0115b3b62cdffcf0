"""Places a screening level cannot tell apart (sensfw/measure/screening.py,
sensfw/measure/diagnose.py): candidates of one effect whose first looks agree to round-off
share one second look, and join the calibrated one where they tie at its optimum."""

import numpy as np

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


def test_a_twin_joins_the_calibrated_candidate_only_where_it_ties():
    lead, twin, other = (hypothesis("damping", p)
                         for p in ("bearing_l3", "driveshaft", "bearing_l3_shoulder"))
    w = np.array([1.0, 2.0, -1.0])
    lead.fit = Fit(lead.coords, Trial({"extra_damping": 0.2}, w), None)
    twin.screen["twin"] = other.screen["twin"] = lead.name
    worse = np.sqrt(w**2 + (TIE_BIC + 1.0) / len(w))  # chi2 larger by the tie + 1
    res = _Residuals(w, {"driveshaft": w.copy(), "bearing_l3_shoulder": worse})
    calibrated = [lead]
    _join_twins(res, [lead, twin, other], calibrated, log=lambda s: None)
    assert calibrated == [lead, twin]
    assert twin.fit.values == lead.fit.values and twin.fit.chi2 == lead.fit.chi2
    assert other.fit is None
    assert sorted(p for p, _ in res.calls) == ["bearing_l3_shoulder", "driveshaft"]
