"""The calibration engine (sensfw/measure/calibration/) and the residual statistics
(sensfw/measure/discrepancy.py) on problems with known answers."""

import math
import threading

import numpy as np
import pytest
from scipy.optimize import least_squares

from sensfw.measure import discrepancy
from sensfw.measure.calibration import Axis, Coordinates, ResidualModel, Trial, calibrate
from sensfw.measure.calibration.refine import Batcher
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


def start_trial(evaluate, values):
    return Trial(values, evaluate([values])[0])


def test_axes_code_log_ranges_and_round_trip():
    lin = Axis.of("m", 0.0, 0.1, 0.02, "kg")
    log = Axis.of("k", 1e4, 1e6, 1e5, "N/mm")
    zero_log = Axis.of("k3", 0.0, 1e12, 1e8, "N/mm^3")
    assert (lin.scale, log.scale, zero_log.scale) == ("linear", "log", "log1p")
    assert log.code(1e5) == pytest.approx(0.0)  # the middle decade
    assert lin.code(0.0) == -1 and lin.decode(1.0) == pytest.approx(0.1)
    # zero-based decades: 0 at -1, the top at +1, 1e8 (x0 = 1e8, log10(2) of 4.0 decades)
    # at -1 + 2 * 0.301 / 4.0
    assert zero_log.code(0.0) == -1 and zero_log.code(1e12) == pytest.approx(1.0)
    assert zero_log.code(1e8) == pytest.approx(-1 + 2 * math.log10(2) / math.log10(1 + 1e4))
    for a, x in ((lin, 0.037), (log, 3.3e5), (zero_log, 2.2e9)):
        assert a.decode(a.code(x)) == pytest.approx(x, rel=1e-12)


@pytest.mark.parametrize("refine", ["dfols", "lm"])
def test_calibration_finds_the_least_squares_optimum_with_laplace_intervals(refine):
    coords, evaluate, t, y, calls = decay_problem()
    start = {"a": 1.0, "tau": 0.3}
    fit = calibrate(evaluate, coords, 40, evidence=[start_trial(evaluate, start)],
                    refine=refine)
    # reference: scipy's least squares on the same residuals, from the same start
    ref = least_squares(lambda x: (x[0] * np.exp(-t / x[1]) - y) / 0.02, [1.0, 0.3],
                        bounds=([0.5, 0.01], [5.0, 1.0]))
    assert fit.values["a"] == pytest.approx(ref.x[0], rel=2e-3)
    assert fit.values["tau"] == pytest.approx(ref.x[1], rel=2e-3)
    assert fit.chi2 == pytest.approx(float(np.sum(ref.fun**2)), rel=1e-2)
    # the Laplace interval of a against the exact linear-regression standard error at the
    # optimum (J from scipy, sigma = 1 after weighting): within 10 % (the engine's J is
    # the refinement's model Jacobian, or a forward difference)
    J = ref.jac
    cov = np.linalg.inv(J.T @ J) * max(1.0, float(np.sum(ref.fun**2)) / (len(t) - 2))
    row = next(r for r in fit.summary() if r["name"] == "a")
    half = 0.5 * (row["interval"][1] - row["interval"][0])
    assert half == pytest.approx(1.96 * math.sqrt(cov[0, 0]), rel=0.1)
    assert not row["flags"]
    assert sum(calls) - 1 <= 40  # the budget holds (the start was evaluated before)


@pytest.mark.parametrize("refine", ["dfols", "lm"])
def test_a_refinement_stopped_by_its_budget_says_so_in_dfols_words(refine):
    """Diagnosis refines a hypothesis further only where its refinement ended on the budget
    (``budget_spent``; "max evals" in the message, DFO-LS's words): both solvers must
    report it so, and neither where it converged. From a = 1, tau = 0.3 six points do not
    reach the optimum (chi2 > 2x scipy's), 40 do."""
    coords, evaluate, t, y, _ = decay_problem()
    start = {"a": 1.0, "tau": 0.3}
    ref = least_squares(lambda x: (x[0] * np.exp(-t / x[1]) - y) / 0.02, [1.0, 0.3],
                        bounds=([0.5, 0.01], [5.0, 1.0]))
    messages, spent = {}, {}
    for budget in (6, 40):
        fit = calibrate(evaluate, coords, budget, evidence=[start_trial(evaluate, start)],
                        refine=refine, global_share=0.0, n_design=0)
        messages[budget] = " ".join(r["message"] for r in fit.info["refinement"])
        spent[budget] = any(r["budget_spent"] for r in fit.info["refinement"])
        if budget == 6:
            assert fit.chi2 > 2 * float(np.sum(ref.fun**2))
        else:
            assert fit.chi2 == pytest.approx(float(np.sum(ref.fun**2)), rel=1e-2)
    assert "max evals" in messages[6] and spent[6]
    assert "max evals" not in messages[40] and not spent[40]


def sine_problem():
    """A frequency to find, ``y = sin(2 pi f t)`` over 0.25 s with f = 13.3 Hz in [1, 20] Hz
    (linear axis): chi2 against f has a valley about every 4 Hz (a whole number of cycles
    more or less over the record), so a local method from f = 3 Hz stops in the first
    valley it meets. The amplitude (true 1) is the second axis."""
    t = np.linspace(0, 0.25, 200)
    rng = np.random.default_rng(1)
    y = np.sin(2 * np.pi * 13.3 * t) + 0.05 * rng.standard_normal(len(t))
    coords = Coordinates.of(None, [Parameter("f", "Hz", 3.0, 1.0, 20.0),
                                   Parameter("amp", "", 0.5, 0.1, 2.0)])

    def evaluate(points):
        return [(p["amp"] * np.sin(2 * np.pi * p["f"] * t) - y) / 0.05 for p in points]

    return coords, evaluate


def test_the_global_phase_finds_the_optimum_a_local_search_misses():
    """On the multimodal sine problem the former local method (Levenberg-Marquardt from
    the start, no global phase) ends in a side valley; the global calibration finds the
    true frequency within 0.1 % and chi2 within the noise (n = 200 entries: chi2 about
    200), with the same budget."""
    coords, evaluate = sine_problem()
    start = start_trial(evaluate, {"f": 3.0, "amp": 0.5})
    local = calibrate(evaluate, coords, 60, evidence=[start], refine="lm", global_share=0.0,
                      n_design=0)
    found = calibrate(evaluate, coords, 60, evidence=[start])
    assert abs(local.values["f"] - 13.3) > 0.5, local.values  # the local one stalls
    assert found.values["f"] == pytest.approx(13.3, rel=1e-3), found.values
    assert found.values["amp"] == pytest.approx(1.0, rel=0.02)
    assert discrepancy.fits(found.best.w, 2), found.chi2


def test_never_worse_than_the_evidence_and_bounds_are_flagged():
    coords, evaluate, *_ = decay_problem()
    best = start_trial(evaluate, {"a": 2.0, "tau": 0.1})
    fit = calibrate(evaluate, coords, 20, evidence=[best])
    assert fit.chi2 <= best.chi2
    # data that want a beyond its upper bound: it ends on the bound, flagged
    coords2 = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 1.5),
                                    Parameter("tau", "s", 0.3, 0.01, 1.0)])
    fit = calibrate(evaluate, coords2, 40,
                    evidence=[start_trial(evaluate, {"a": 1.0, "tau": 0.3})])
    row = next(r for r in fit.summary() if r["name"] == "a")
    assert row["value"] == pytest.approx(1.5, rel=0.02)
    assert "on its upper bound" in row["flags"]


def test_a_parameter_the_data_cannot_see_is_flagged_unidentified():
    coords = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 5.0),
                                   Parameter("ghost", "", 1.0, 0.0, 2.0)])
    t = np.linspace(0, 1, 30)

    def evaluate(points):  # ghost does not enter the model
        return [(p["a"] * t - 2.0 * t) / 0.01 for p in points]

    fit = calibrate(evaluate, coords, 30,
                    evidence=[start_trial(evaluate, {"a": 1.0, "ghost": 1.0})])
    rows = {r["name"]: r for r in fit.summary()}
    assert rows["a"]["value"] == pytest.approx(2.0, rel=1e-3)
    assert "not identified by these data" in rows["ghost"]["flags"]
    assert not rows["a"]["flags"]


def test_parameters_that_trade_are_reported_with_their_correlation():
    """``y = m k t`` sees only the product of m and k: their estimates are perfectly
    anti-correlated (in log coordinates, -1); an independent offset is not part of a
    trade."""
    t = np.linspace(0.1, 1, 40)
    rng = np.random.default_rng(0)
    y = 2.0 * t + 0.3 + 0.01 * rng.standard_normal(len(t))
    coords = Coordinates.of(None, [Parameter("m", "kg", 1.0, 0.5, 4.0),
                                   Parameter("k", "N/mm", 1.0, 0.5, 4.0),
                                   Parameter("c", "", 0.0, -1.0, 1.0)])

    def evaluate(points):
        return [(p["m"] * p["k"] * t + p["c"] - y) / 0.01 for p in points]

    fit = calibrate(evaluate, coords, 40,
                    evidence=[start_trial(evaluate, {"m": 1.0, "k": 1.0, "c": 0.0})])
    assert fit.values["m"] * fit.values["k"] == pytest.approx(2.0, rel=1e-2)
    trades = fit.trades()
    assert [(t["a"], t["b"]) for t in trades] == [("m", "k")]
    assert trades[0]["correlation"] < -0.95


def test_the_residual_surrogate_reproduces_a_smooth_residual_vector():
    """A residual vector linear in two coded inputs plus a fixed 'noise' vector (as a
    measurement's noise is the same for every run): its chi2 is reproduced at new points
    within 1 %, with three components at most (the noise vector, two directions), and
    its leave-one-out error per entry is far below one standard error."""
    rng = np.random.default_rng(0)
    n = 40
    a, b, e = rng.standard_normal((3, n))

    def w(z):
        return 3 * z[0] * a - 2 * z[1] * b + e

    Z = rng.uniform(-1, 1, (25, 2))
    model = ResidualModel().fit(Z, np.array([w(z) for z in Z]))
    assert model.n_components <= 3
    new = rng.uniform(-0.9, 0.9, (10, 2))
    true = np.array([w(z) @ w(z) for z in new])
    assert np.allclose(model.chi2(new), true, rtol=0.01)
    q = model.quality()
    assert q["loo_rms_per_entry"] < 0.05, q


def serve_clients(batcher, client) -> None:
    """Run ``client(0)`` and ``client(1)`` in threads while this one serves their batches."""
    threads = [threading.Thread(target=client, args=(i,)) for i in (0, 1)]
    for th in threads:
        th.start()
    batcher.serve()
    for th in threads:
        th.join()


def test_the_batcher_gathers_the_requests_of_its_clients_into_batches():
    """Two solver threads each ask for six points one at a time: the serving thread runs
    them in six batches of two (a batch waits for every live client)."""
    batches = []

    def evaluate(zs):
        batches.append(len(zs))
        return [np.array([float(z[0])]) for z in zs]

    batcher = Batcher(evaluate, 2)
    answers = {0: [], 1: []}

    def client(i):
        try:
            for k in range(6):
                answers[i].append(float(batcher(np.array([10 * i + k]))[0]))
        finally:
            batcher.leave()

    serve_clients(batcher, client)
    assert batches == [2] * 6
    assert answers == {0: [0, 1, 2, 3, 4, 5], 1: [10, 11, 12, 13, 14, 15]}


def test_a_batch_runs_in_the_order_of_the_clients_not_of_their_arrival():
    """Client 1 always asks first, client 0 a moment later: every batch still runs client
    0's point first (the runs' order is every later trial's order, and so the surrogates'
    and the calibration's: arrival order made two calibrations of one case differ)."""
    import time

    batches = []

    def evaluate(zs):
        batches.append([float(z[0]) for z in zs])
        return [np.array([float(z[0])]) for z in zs]

    batcher = Batcher(evaluate, 2)

    def client(i):
        try:
            for k in range(3):
                if i == 0:
                    time.sleep(0.02)
                batcher(np.array([10 * i + k]), i)
        finally:
            batcher.leave()

    serve_clients(batcher, client)
    assert batches == [[0, 10], [1, 11], [2, 12]]


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


def test_the_surrogates_numpy_predictions_are_scikit_learns():
    """The residual model predicts its Gaussian processes in plain numpy (speed); the means
    and standard deviations are scikit-learn's own to round-off."""
    rng = np.random.default_rng(0)
    Z = rng.uniform(-1, 1, (30, 3))
    base = np.column_stack([np.sin(3 * Z[:, 0]) + Z[:, 1] ** 2, Z[:, 2] * Z[:, 0],
                            np.cos(Z[:, 1])])
    W = base @ rng.standard_normal((3, 20)) + 0.01 * rng.standard_normal((30, 20))
    model = ResidualModel().fit(Z, W)
    assert model.fast_ is not None
    Q = rng.uniform(-1, 1, (50, 3))
    mu, sd = model.scores(Q)
    ref = [m.predict(Q, return_std=True) for m in model.models_]
    assert np.allclose(mu, np.column_stack([r[0] for r in ref]), rtol=0, atol=1e-9)
    assert np.allclose(sd, np.column_stack([r[1] for r in ref]), rtol=0, atol=1e-9)


def test_ctrl_c_during_the_local_search_stops_it():
    """A KeyboardInterrupt while DFO-LS's points run was caught as one start's error: the
    calibration went on and wrote a worse result with exit 0. It now stops the search (and
    the command: exit 130) once the solver threads have left; an ordinary error of a
    simulation batch stays one start's error."""
    import numpy as np
    import pytest

    from sensfw.measure.calibration.refine import dfols_solves

    calls = []

    def evaluate(zs, fail=KeyboardInterrupt):
        calls.append(len(zs))
        if len(calls) == 3:
            raise fail()
        return [np.array([z[0] - 0.3, 2 * (z[1] + 0.1)]) for z in zs]

    starts = [np.zeros(2), np.full(2, 0.5)]
    with pytest.raises(KeyboardInterrupt):
        dfols_solves(evaluate, starts, [40, 40], np.full(2, 1e3))
    calls.clear()
    out = dfols_solves(lambda zs: evaluate(zs, RuntimeError), starts, [40, 40],
                       np.full(2, 1e3))
    assert all("RuntimeError" in o["error"] for o in out)


def test_an_interval_holds_the_runs_that_fit_as_well_as_the_best():
    """A response symmetric in ``p`` (the data see ``p^2``): two basins, at ``p = -1`` and
    ``p = +1``, equally deep. The Laplace interval describes the one the search ended in;
    the run in the other basin has the same chi2, so by the likelihood ratio it belongs in
    the 95 % interval (every point within 3.84 s^2 of the best does), and the interval is
    widened to it and flagged. A point 10 above the best (beyond 3.84) is not taken."""
    from sensfw.measure.calibration import Fit, Trial

    coords = Coordinates.of(None, [Parameter("p", "", 0.5, -2.0, 2.0)])
    t = np.linspace(0, 1, 40)
    noise = 0.01 * np.sin(37 * t)  # a fixed misfit: chi2 0.04 at either optimum

    def w(p):
        return (p * p * t - t) / 0.01 + noise / 0.01

    trials = [Trial({"p": p}, w(p)) for p in (1.0, -1.0, 0.0)]
    J = (w(1.0 + 1e-6) - w(1.0)) / 1e-6 * 2.0  # d w / d z (coded: p = 2 z)
    fit = Fit(coords, trials[0], J[:, None], trials)
    row = fit.summary()[0]
    lo, hi = row["interval"]
    assert lo <= -1.0 and hi >= 1.0, row
    assert any("widened" in f for f in row["flags"])
    # the Laplace interval alone: +-1.96 sd around +1 (sd from J), far from -1
    sd = math.sqrt(fit.covariance()[0, 0]) * 2.0  # coded -> physical (p = 2 z)
    assert 1.96 * sd < 0.05
    # a run in the other basin but 10 above the best in chi2 is outside the bound
    far = Trial({"p": -1.0}, w(-1.0) + np.sqrt(10.0 / len(t)))
    fit2 = Fit(coords, trials[0], J[:, None], [trials[0], far])
    row2 = fit2.summary()[0]
    assert row2["interval"][0] > 0.9 and not row2["flags"], row2
