"""The statistics ``bench/recovery.py`` prints beside its rates: the Wilson interval of a
rate and the paired comparison of two runs of the same seeds (McNemar's exact test)."""

import math

import bench_modules
import pytest


@pytest.fixture(scope="module")
def recovery():
    return bench_modules.load("recovery")


def test_the_wilson_interval_is_the_score_interval(recovery):
    # Wilson (1927), written out: centre (p + z^2 / 2n) / (1 + z^2 / n), half-width
    # z / (1 + z^2 / n) sqrt(p (1 - p) / n + z^2 / 4 n^2), z the normal's 0.975 quantile
    z = 1.959963984540054
    for hit, n in [(75, 80), (39, 44), (18, 18), (0, 18)]:
        p = hit / n
        centre = (p + z * z / (2 * n)) / (1 + z * z / n)
        half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
        assert recovery.wilson(hit, n) == pytest.approx((centre - half, centre + half),
                                                        abs=1e-12)
    assert recovery.wilson(0, 0) == (0.0, 1.0)  # nothing counted: nothing known


def _row(seed, effect, verdict, noise_reached, chi2_h0=100.0, chi2_truth=40.0):
    """A benchmark row as ``run_case`` writes it (one level of 40 entries)."""
    return {"seed": seed, "effect": effect, "place": "clutch" if effect else None,
            "params": {"extra_damping": 1.0} if effect else {}, "n_entries": 40,
            "k_h0": 3, "k_true": 4 if effect else 3, "chi2_h0": chi2_h0,
            "chi2_truth": chi2_truth, "chi2_true_calibrated": chi2_truth,
            "h0_fits_noise": False, "noise_reached": noise_reached,
            "verdict": verdict, "named": [] if verdict == "parameters" else [verdict]}


def test_two_runs_are_compared_case_by_case(recovery):
    right, wrong = "damping@clutch", "friction@clutch"
    before = [_row(1, "damping", right, True), _row(2, "damping", right, False),
              _row(3, "damping", wrong, False), _row(4, None, "parameters", True),
              *(_row(10 + i, "damping", right, False) for i in range(6))]
    after = [_row(1, "damping", right, True), _row(2, "damping", wrong, True),
             _row(3, "damping", right, True), _row(4, None, right, True),
             *(_row(10 + i, "damping", right, True) for i in range(6)),
             _row(99, None, "parameters", True)]  # a seed only one run has: left out
    lines = {r["line"]: r for r in recovery.paired(before, after)}
    noise = lines["true hypothesis within the noise"]
    # seeds 1 and 4 in both; 2, 3 and the six others only after: 8 discordant, all one way
    assert (noise["cases"], noise["both"], noise["only_before"], noise["only_after"],
            noise["neither"]) == (10, 2, 0, 8, 0)
    assert noise["p"] == pytest.approx(2 * 0.5**8)  # the two-sided binomial tail
    verdicts = lines["right verdict (named, or parameters/none where right)"]
    # seed 2 lost, seed 3 gained, seed 4 a false discovery after: 1 gained, 2 lost
    assert (verdicts["both"], verdicts["only_before"], verdicts["only_after"]) == (7, 2, 1)
    assert verdicts["p"] == pytest.approx(1.0)
    named = lines["data can tell: effect and place named"]
    assert named["cases"] == 9  # the effect cases (H0 at 100, the truth at 40 + log n)
