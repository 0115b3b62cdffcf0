"""The notices of ``sensfw calibrate`` where its result cannot be trusted as it reads:
a budget below what a global search needs, and a point that fits the noise only through
the model's own scatter there (:mod:`sensfw.measure.recalibrate`)."""

import numpy as np
from scipy.stats import chi2 as chi2_dist

from sensfw.measure.recalibrate import least_points, scatter_note, small_budget_note


def test_least_points_is_two_designs_and_two_local_searches():
    # two_searches: a design of 2k+1 points and DFO-LS's k+2 per search
    # (sensfw.measure.calibration._calibrate caps the design at budget - (k + 2))
    assert least_points(3) == 2 * 7 + 2 * 5 == 24
    assert least_points(1) == 12


def test_a_budget_below_a_global_search_says_so_with_the_numbers():
    note = small_budget_note(40, 13, 3, 3)
    assert note is not None
    assert "13 points" in note and "about 24" in note and "72 simulations" in note
    assert "default budget 180" in note
    assert small_budget_note(180, 60, 3, 3) is None
    assert small_budget_note(72, 24, 3, 3) is None  # exactly enough
    assert small_budget_note(40, 13, 3, 3, global_phase=False) is None  # asked for local


def test_a_point_that_fits_only_through_its_own_scatter_is_named():
    n, k = 121, 3
    bound = chi2_dist.ppf(1 - 1e-3, n - k)  # discrepancy.fits's test
    rng = np.random.default_rng(0)
    w = rng.normal(size=n)
    w *= np.sqrt(3 * bound / (w @ w))  # chi2 three times the bound: fails
    widened = w / 2.0  # chi2 0.75 of the bound: passes
    rough = np.full(n, 0.4)
    note = scatter_note(w, widened, rough, k)
    assert note is not None and f"{float(w @ w):.4g} for 121 entries" in note
    assert "largest 0.40 dB" in note
    # fits without the scatter: nothing to say; fails with it: the noise test says so
    assert scatter_note(widened, widened, rough, k) is None
    assert scatter_note(w, w, rough, k) is None
    assert scatter_note(None, widened, rough, k) is None


def test_the_report_headline_does_not_call_a_scatter_masked_fit_plain():
    from sensfw.report.diagnosis import _noise_verdict

    assert _noise_verdict({"fits_noise": True}) == "the noise explains what is left."
    assert "only with the model's own scatter" in _noise_verdict(
        {"fits_noise": True, "fits_noise_without_scatter": False})
    assert _noise_verdict({"fits_noise": False, "fits_noise_without_scatter": False}) \
        == "more is left than the noise explains."
