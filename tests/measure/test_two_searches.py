"""``sensfw calibrate`` calibrates the base variables by two searches
(sensfw/measure/diagnose.py, two_searches): DFO-LS from the best points of a
space-filling design, then the surrogate search seeded with all of those runs. Over the
recovery benchmark's 40 cases each search alone stalled far from the lowest chi2 found in
about one case in five where the two did not (bench/h0_search.py; bench/RECOVERY.md,
stop 42); here, on an analytic residual vector, the contract: the design's local searches
run first, the second search adds no design and sees every run of the first, the result is
the lowest run of both and the global optimum, and a local calibration is one search."""

import numpy as np

import sensfw.measure.diagnose as diagnose
from sensfw.measure.calibration import Axis, Coordinates, Trial
from sensfw.measure.diagnose import LOCAL_ONLY, two_searches
from sensfw.measure.hypotheses import Hypothesis

#: the global optimum (coded) of the residuals below: a narrow basin, chi2 0.09 at its
#: centre, next to a broad one of chi2 100 around ``BROAD``
NARROW = np.array([0.55, -0.6, 0.3])
BROAD = np.array([-0.5, 0.5, -0.4])


class _Analytic:
    """The base variables' residuals as an analytic function of the coded point (no
    simulation): one entry with a narrow Gaussian basin around ``NARROW`` and three
    pulling gently toward ``BROAD``; every run is kept as a trial, as
    :class:`~sensfw.measure.residuals.Residuals` keeps them."""

    def __init__(self, coords: Coordinates):
        self.coords, self.pool, self.runs = coords, [], 0

    def w(self, z: np.ndarray) -> np.ndarray:
        deep = 10.0 * (1.0 - 0.97 * np.exp(-np.sum((z - NARROW) ** 2) / (2 * 0.15**2)))
        return np.concatenate([[deep], 0.05 * (z - BROAD)])

    def evaluate(self, effects, points, label, levels=None):
        out = [self.w(self.coords.code(p)) for p in points]
        self.pool += [Trial(dict(p), w) for p, w in zip(points, out, strict=True)]
        self.runs += len(points)
        return out

    def trials(self, effects=None, levels=None, extra=None):
        return [Trial({**t.values, **(extra or {})}, t.w) for t in self.pool]


def h0():
    coords = Coordinates([Axis.of(n, 1.0, 2.0, 1.5) for n in ("a", "b", "c")])
    return Hypothesis(None, "", coords)


def test_the_design_searches_first_then_the_surrogate_seeded_with_them(monkeypatch):
    calls = []
    real = diagnose.calibrate_hypothesis

    def spy(res, h, budget, **kw):
        seen = len(res.trials())
        fit = real(res, h, budget, **kw)
        calls.append({"budget": budget, "seen": seen, "ran": len(fit.trials), **kw})
        return fit

    monkeypatch.setattr(diagnose, "calibrate_hypothesis", spy)
    h = h0()
    res = _Analytic(h.coords)
    fit = two_searches(res, h, 40, {"q": 2, "local": "dfols"})
    first, second = calls
    assert first["global_share"] == 0.0 and "n_design" not in first  # design + DFO-LS
    assert second["n_design"] == 0 and "global_share" not in second   # surrogate, default
    assert first["budget"] == second["budget"] == 20
    assert second["seen"] == first["ran"] > 0  # seeded with every run of the first
    assert res.runs <= 40
    lowest = min(float(t.w @ t.w) for t in res.pool)
    assert fit.chi2 == lowest
    # the global optimum: within the narrow basin (chi2 100 outside it)
    assert fit.chi2 < 1.0
    assert np.max(np.abs(h.coords.code(fit.values) - NARROW)) < 0.05


def test_without_a_global_phase_one_local_search(monkeypatch):
    calls = []
    monkeypatch.setattr(diagnose, "calibrate_hypothesis",
                        lambda res, h, budget, **kw: calls.append({**kw, "budget": budget})
                        or "fit")
    assert two_searches(None, h0(), 30, {"q": 2, "local": "lm", **LOCAL_ONLY}) == "fit"
    # one search with every point
    assert [{k: v for k, v in kw.items() if k != "log"} for kw in calls] == [
        {"q": 2, "local": "lm", **LOCAL_ONLY, "budget": 30}]
