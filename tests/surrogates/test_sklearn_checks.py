"""scikit-learn's own estimator checks on every registered surrogate (issue 12, item 3).

Each surrogate runs through ``check_estimator`` (clone, get/set_params, no attributes set in
``__init__``, input validation of X and y, NaN/inf refused, NotFittedError before fit,
feature-name consistency, pickling, idempotent fits, ...). The checks that cannot fit a
regressor of a given kind are listed with the reason; everything else must pass.
"""

import pytest
from sklearn.utils.estimator_checks import check_estimator

from sensfw.plugins import surrogates

# Eq. 18 has 1 + 2m + m(m-1)/2 terms for m inputs (66 for the checks' 10-column data) and
# refuses to fit fewer rows than terms (an exactly determined fit has no residual degree of
# freedom, so no R²adj, F or p-values); the full-degree polynomial likewise. These checks use
# 10-56 rows with 3-10 columns, fewer rows than terms.
TOO_FEW_ROWS = "needs more rows than its 1 + 2m + m(m-1)/2 terms; the check gives fewer"
FEW_ROWS_CHECKS = ("check_estimators_dtypes", "check_dtype_object",
                   "check_regressors_no_decision_function", "check_regressors_int")
EXPECTED_FAILURES = {
    "eq18": {c: TOO_FEW_ROWS for c in (*FEW_ROWS_CHECKS, "check_n_features_in_after_fitting",
                                      "check_estimators_nan_inf")},
    "polynomial": dict.fromkeys(FEW_ROWS_CHECKS, TOO_FEW_ROWS),
    # Auto over eq18 and polynomial has no candidate that fits those data either
    "auto": {c: "no candidate (eq18, polynomial) " + TOO_FEW_ROWS
             for c in (*FEW_ROWS_CHECKS, "check_n_features_in_after_fitting",
                       "check_estimators_nan_inf")},
}
# lighter settings so the checks take seconds (the contract does not depend on them)
LIGHT = {"gaussian_process": {"n_restarts_optimizer": 0},
         "random_forest": {"n_estimators": 20},
         "auto": {"candidates": ("eq18", "polynomial")}}
# statsmodels' OLS on the checks' 200-row data and the GP's likelihood optimisation take
# 10-140 s on 2 shared cores
SLOW = {"eq18", "auto", "gaussian_process"}


def params() -> list:
    return [pytest.param(name, marks=[pytest.mark.slow] if name in SLOW else [], id=name)
            for name in surrogates.names()]


@pytest.mark.filterwarnings("ignore")
@pytest.mark.parametrize("name", params())
def test_scikit_learn_estimator_checks(name):
    est = surrogates.get(name)(**LIGHT.get(name, {}))
    expected = EXPECTED_FAILURES.get(name, {})
    results = check_estimator(est, expected_failed_checks=expected, on_fail=None)
    failed = [(r["check_name"], str(r["exception"]).splitlines()[:1])
              for r in results if r["status"] == "failed"]
    assert not failed, failed
    # the listed failures still fail for the stated reason (not silently for another one)
    xfail = {r["check_name"]: r for r in results if r["status"] == "xfail"}
    assert set(xfail) == set(expected)
    for r in xfail.values():
        assert "n_samples" in str(r["exception"]), (r["check_name"], r["exception"])
