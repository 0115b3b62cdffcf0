"""A fixed-seed subset of the recovery benchmark (``bench/recovery.py``, issue 25): cases
drawn by :func:`sensfw.measure.cases.draw` from the benchmark's seeds, diagnosed with the
default budget on the short quick study, must end as the benchmark counts right: the effect
and place named when the data can tell, "parameters"/"none" otherwise, and the true
hypothesis calibrated to within its noise (chi2/n <= 1 + 3 sqrt(2/n), three standard
deviations of a chi-square's mean). The rates over random draws are the benchmark's
(README, "Benchmarks"; ``bench/RECOVERY.md``); these cases keep its machinery honest in
the suite."""

from __future__ import annotations

import bench_modules
import pytest

pytestmark = pytest.mark.slow

#: benchmark case index -> seed 2025 + index (bench/recovery.py --seed 2025): 4, a contact
#: hardening at bearing l3's shoulder, named with its place and calibrated to the noise;
#: 48, a damping at slide bearing 2 on two levels that the signature classes, read off H0's poor fit
#: (chi2 3111 for 93 entries), leave out: named since the candidates they left out race
#: where none they kept explains the screening level (a contact hardening at bearing l3
#: was named before, at chi2 1089 where the truth's values give 63). Cases 1 (no
#: effect), 15 (a limit stop the data cannot tell: "parameters") and 16 (a friction H0
#: passes the noise's test on while the truth beats it by far) were here too; they are in
#: every run of the benchmark (``--first 0``) and the suite's 20 minutes could not hold them
#: (the no-effect verdict is also test_diagnose.py's noise case)
CASES = [4, 48]


@pytest.fixture(scope="module")
def recovery():
    return bench_modules.load("recovery")


@pytest.mark.parametrize("index", CASES)
def test_a_benchmark_case_ends_right(index, recovery):
    from sensfw.measure import cases

    study = recovery.bench_study("quick", short=True)
    case = cases.draw(study, 2025 + index, recovery.LEVELS["quick"])
    row = recovery.run_case(study, case, recovery.DEFAULT_METHOD, workers=2)
    assert row["outcome"] in ("right", "correct", "correct (cannot tell)"), row
    assert row["noise_reached"], row
    # the default budget, plus H0's rematch before a candidate is credited: at most as many
    # simulations as the leader spent, itself within the budget, plus what the race spent
    # beyond it (sensfw.measure.diagnose)
    assert row["simulations"] <= 2 * (150 + 50 * len(case["levels"])) + \
        row["beyond_budget"], row
