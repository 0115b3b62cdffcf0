"""The calibration engine (sensfw/measure/calibrate.py) and the residual statistics
(sensfw/measure/discrepancy.py) on problems with known answers."""

import math

import numpy as np
import pytest

from sensfw.measure import discrepancy
from sensfw.measure.calibrate import Axis, Coordinates, Evaluation, calibrate
from sensfw.params import Parameter


def decay_problem(noise=0.02, seed=0):
    """Weighted residuals of ``y = a exp(-t / tau)`` (a in [0.5, 5], tau in [0.01, 1] on a
    log axis) against data made at a = 2, tau = 0.1 with Gaussian noise of known sigma."""
    t = np.linspace(0, 0.5, 60)
    rng = np.random.default_rng(seed)
    y = 2.0 * np.exp(-t / 0.1) + noise * rng.standard_normal(len(t))
    coords = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 5.0),
                                   Parameter("tau", "s", 0.3, 0.01, 1.0)])
    calls = []

    def evaluate(points):
        calls.append(len(points))
        return [(p["a"] * np.exp(-t / p["tau"]) - y) / noise for p in points]

    return coords, evaluate, t, y, calls


def test_axes_code_log_ranges_and_round_trip():
    lin = Axis.of("m", 0.0, 0.1, 0.02, "kg")
    log = Axis.of("k", 1e4, 1e6, 1e5, "N/mm")
    assert not lin.log and log.log
    assert log.code(1e5) == pytest.approx(0.0)  # the middle decade
    assert lin.code(0.0) == -1 and lin.decode(1.0) == pytest.approx(0.1)
    for a, x in ((lin, 0.037), (log, 3.3e5)):
        assert a.decode(a.code(x)) == pytest.approx(x, rel=1e-12)


def test_calibration_finds_the_least_squares_optimum_with_laplace_intervals():
    coords, evaluate, t, y, calls = decay_problem()
    start = {"a": 1.0, "tau": 0.3}
    fit = calibrate(evaluate, coords, Evaluation(start, evaluate([start])[0]))
    # reference: scipy's least squares on the same residuals, from the same start
    from scipy.optimize import least_squares

    ref = least_squares(lambda x: (x[0] * np.exp(-t / x[1]) - y) / 0.02, [1.0, 0.3],
                        bounds=([0.5, 0.01], [5.0, 1.0]))
    assert fit.values["a"] == pytest.approx(ref.x[0], rel=2e-3)
    assert fit.values["tau"] == pytest.approx(ref.x[1], rel=2e-3)
    assert fit.chi2 == pytest.approx(float(np.sum(ref.fun**2)), rel=1e-2)
    # the Laplace interval of a against the exact linear-regression standard error at the
    # optimum (J from scipy, sigma = 1 after weighting): within 10 % (the engine's J is a
    # forward difference at 5 % of the coded range)
    J = ref.jac
    cov = np.linalg.inv(J.T @ J) * max(1.0, float(np.sum(ref.fun**2)) / (len(t) - 2))
    row = next(r for r in fit.summary() if r["name"] == "a")
    half = 0.5 * (row["interval"][1] - row["interval"][0])
    assert half == pytest.approx(1.96 * math.sqrt(cov[0, 0]), rel=0.1)
    assert not row["flags"]
    assert sum(calls) < 60  # a handful of Jacobians of 2 runs and trial pairs


def test_never_worse_than_the_start_and_bounds_are_flagged():
    coords, evaluate, *_ = decay_problem()
    best = {"a": 2.0, "tau": 0.1}
    fit = calibrate(evaluate, coords, Evaluation(best, evaluate([best])[0]))
    assert fit.chi2 <= np.sum(evaluate([best])[0] ** 2)
    # data that want a beyond its upper bound: it ends on the bound, flagged
    coords2 = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 1.5),
                                    Parameter("tau", "s", 0.3, 0.01, 1.0)])
    start = {"a": 1.0, "tau": 0.3}
    fit = calibrate(evaluate, coords2, Evaluation(start, evaluate([start])[0]))
    row = next(r for r in fit.summary() if r["name"] == "a")
    assert row["value"] == pytest.approx(1.5, rel=0.02)
    assert "on its upper bound" in row["flags"]


def test_a_parameter_the_data_cannot_see_is_flagged_unidentified():
    coords = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 5.0),
                                   Parameter("ghost", "", 1.0, 0.0, 2.0)])
    t = np.linspace(0, 1, 30)

    def evaluate(points):  # ghost does not enter the model
        return [(p["a"] * t - 2.0 * t) / 0.01 for p in points]

    start = {"a": 1.0, "ghost": 1.0}
    fit = calibrate(evaluate, coords, Evaluation(start, evaluate([start])[0]))
    rows = {r["name"]: r for r in fit.summary()}
    assert rows["a"]["value"] == pytest.approx(2.0, rel=1e-3)
    assert "not identified by these data" in rows["ghost"]["flags"]
    assert not rows["a"]["flags"]


def test_chi_square_test_and_bic_on_gaussian_residuals():
    """For standard normal residuals the test rejects about alpha of the time (here over
    2000 draws of 50 entries: 0.1 % expected, at most 0.5 % allowed by the binomial
    spread), and BIC grows by ln n per parameter."""
    rng = np.random.default_rng(3)
    rejected = sum(not discrepancy.fits(rng.standard_normal(50), k=2) for _ in range(2000))
    assert rejected <= 10
    w = rng.standard_normal(50)
    assert discrepancy.bic(w, 3) - discrepancy.bic(w, 1) == pytest.approx(2 * math.log(50))
    # a 30 % misfit on top of the noise is rejected
    assert not discrepancy.fits(rng.standard_normal(50) + 3.0, k=2)
