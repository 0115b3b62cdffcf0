"""The verdict's rules (sensfw/measure/ranking.py): a candidate that beats "parameters" by
the margin is named even where "parameters" passes the noise's chi-square test; the test
decides between "parameters" and "none" only where no candidate does."""

import math

import numpy as np
from scipy.stats import chi2 as chi2_dist

from sensfw.measure.calibration import Coordinates, Fit, Trial
from sensfw.measure.hypotheses import Hypothesis
from sensfw.measure.ranking import verdict
from sensfw.plugins import effects

N = 100  # entries


def with_chi2(h: Hypothesis, chi2: float) -> Hypothesis:
    h.fit = Fit(h.coords, Trial({}, np.full(N, math.sqrt(chi2 / N))), None)
    return h


def h0(chi2: float) -> Hypothesis:
    return with_chi2(Hypothesis(None, "", Coordinates.of(None, [])), chi2)


def candidate(chi2: float) -> Hypothesis:
    eff = effects.get("added_mass")(attach="crankshaft")  # one parameter: k = 1
    return with_chi2(Hypothesis(eff, "crankshaft", Coordinates.of(None, eff.parameters())),
                     chi2)


def test_a_candidate_beating_h0_by_the_margin_is_named_even_where_h0_passes_the_test():
    bound = chi2_dist.ppf(1 - 1e-3, N)  # the test's bound for H0 (k = 0): 149.4
    base = h0(0.9 * bound)  # passes the test
    # dBIC = 0.9 bound - 40 - ln 100 = 90: named (an effect's distortion counted as noise
    # lets H0 pass the test while the effect explains far more)
    text, _, named = verdict(base, [candidate(40.0)], N, 10.0, 1)
    assert text == "added_mass@crankshaft" and len(named) == 1
    # dBIC = 10 - ln 100 = 5.4 < 10: the test decides, "parameters"
    text, reason, named = verdict(base, [candidate(0.9 * bound - 10.0)], N, 10.0, 1)
    assert text == "parameters" and not named and "noise" in reason


def test_without_a_winner_h0_failing_the_test_gives_none():
    bound = chi2_dist.ppf(1 - 1e-3, N)
    text, _, named = verdict(h0(1.5 * bound), [candidate(1.5 * bound - 5.0)], N, 10.0, 1)
    assert text == "none" and not named
