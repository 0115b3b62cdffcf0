"""The recovery benchmark's random cases (:func:`sensfw.measure.cases.draw`): a seed draws the
same case as the benchmark's recorded rows, and the ranges that move a case away from those
the diagnosis was tuned on (``bench/recovery.py --noise / --factors``) hold what they say."""

from __future__ import annotations

import math

import bench_modules
import pytest


@pytest.fixture(scope="module")
def setup():
    from sensfw.measure import cases

    recovery = bench_modules.load("recovery")
    return cases, recovery.bench_study("quick", short=True), recovery.LEVELS["quick"]


def test_a_seed_draws_the_benchmarks_recorded_case(setup):
    # bench/RECOVERY.md, stop 44's table: seed 2029 (case 4) is a contact hardening at
    # bearing l3's shoulder on two levels; the other draws follow from the same stream
    cases, study, levels = setup
    c = cases.draw(study, 2029, levels)
    assert (c["effect"], c["place"], c["levels"]) == (
        "contact_hardening", "bearing_l3_shoulder", [0.05, 0.1])
    assert c["noise"] == pytest.approx(0.019701098326791153, rel=1e-12)
    assert c == cases.draw(study, 2029, levels, noise=cases.NOISE, factors=cases.FACTORS)


@pytest.mark.parametrize("noise, factors", [((0.05, 0.10), (0.6, 1.6)),
                                            ((0.01, 0.05), (0.4, 2.5))])
def test_wider_ranges_are_drawn_from(setup, noise, factors):
    cases, study, levels = setup
    space = study.calibration_space(list(study.spec.calibration.parameters))
    nominal = space.nominal_row()
    bounds = {v.name: (v.low, v.high) for v in space.variables}
    seen = []
    for seed in range(3000, 3030):
        c = cases.draw(study, seed, levels, noise=noise, factors=factors)
        assert noise[0] <= c["noise"] <= noise[1]
        for name, value in c["base"].items():
            lo, hi = bounds[name]
            if lo < value < hi:  # not clipped to a bound
                f = value / nominal[name]
                assert factors[0] * (1 - 1e-12) <= f <= factors[1] * (1 + 1e-12)
                seen.append(math.log(f))
    # log-uniform over the range: the draws reach into both outer fifths of it
    span = math.log(factors[1]) - math.log(factors[0])
    assert min(seen) < math.log(factors[0]) + 0.2 * span
    assert max(seen) > math.log(factors[1]) - 0.2 * span


@pytest.mark.parametrize("kw", [{"noise": (0.0, 0.1)}, {"noise": (0.1, 0.05)},
                                {"factors": (2.0, 1.0)}])
def test_a_bad_range_is_refused(setup, kw):
    cases, study, levels = setup
    with pytest.raises(ValueError, match="range"):
        cases.draw(study, 3000, levels, **kw)
