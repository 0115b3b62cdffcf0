"""Eq. 18 against independent computations (issue 4, item 4)."""

import itertools

import numpy as np
import pandas as pd
import pytest

from sensfw.plugins import surrogates
from sensfw.surrogates import SurrogateError, make_surrogate
from sensfw.surrogates.eq18 import design_matrix

rng = np.random.default_rng(1)
LEVELS = [1.0, 117.5, 234.0], [2.83e6, 3.16e6, 3.45e6], [0.1, 5.05, 10.0]  # Table 2 style
X = pd.DataFrame(list(itertools.product(*LEVELS)), columns=["x1", "x2", "x3"])
Z = (X - X.mean()) / ((X.max() - X.min()) / 2)
Y = 3 + Z["x1"] - 2 * Z["x3"] + 0.7 * Z["x1"] * Z["x3"] + 1.5 * Z["x2"] ** 2 \
    + 0.05 * rng.standard_normal(len(X))


def test_coefficient_count_and_loo_q2_by_brute_force():
    est = make_surrogate("eq18").fit(X, Y)
    m = 3
    assert len(est.coefficients_) == 1 + 2 * m + m * (m - 1) // 2
    press = 0.0
    for i in range(len(X)):
        keep = np.arange(len(X)) != i
        e = make_surrogate("eq18", bounds=[(min(v), max(v)) for v in LEVELS]).fit(
            X[keep], Y[keep])
        press += (Y[i] - e.predict(X.iloc[[i]])[0]) ** 2
    q2 = 1 - press / np.sum((Y - Y.mean()) ** 2)
    assert est.summary_["q2"] == pytest.approx(q2, rel=1e-10)


def test_coded_and_physical_forms_predict_the_same():
    # the model space is invariant under affine coding: a fit in physical units predicts the
    # same (on well-scaled inputs; with x2 ~ 3e6, x2^2 ~ 1e13 makes a physical fit
    # ill-conditioned, which is why the default codes first)
    Xs = X.assign(x2=X["x2"] / 1e6)
    coded = make_surrogate("eq18").fit(Xs, Y)
    phys = make_surrogate("eq18", coding="physical").fit(Xs, Y)
    np.testing.assert_allclose(coded.predict(Xs), phys.predict(Xs), rtol=1e-9)
    # the physical coefficients (exact map from the coded fit) reproduce the predictions
    # through the physical terms, also at the real scale
    coded = make_surrogate("eq18").fit(X, Y)
    A, _ = design_matrix(X.to_numpy(), list(X.columns))
    beta = coded.coefficients_physical_["estimate"].to_numpy()
    np.testing.assert_allclose(A @ beta, coded.predict(X), rtol=1e-8)


def test_ratio_form_and_log_options():
    with pytest.raises(SurrogateError, match=r"'ratio' .* needs coding='physical'"):
        make_surrogate("eq18", interaction="ratio")
    # built directly (scikit-learn's rule: the constructor only stores), fit checks
    with pytest.raises(SurrogateError, match=r"'ratio' .* needs coding='physical'"):
        surrogates.get("eq18")(interaction="ratio").fit(X, Y)
    r = make_surrogate("eq18", interaction="ratio", coding="physical").fit(X, Y)
    assert "x1/x2" in list(r.coefficients_["term"])
    lg = make_surrogate("eq18", log_features="auto", log_response=True).fit(X, Y + 10)
    terms = list(lg.coefficients_["term"])
    assert "log10(x1)" in terms and "log10(x3)" in terms and "x2" in terms  # x2 spans < 10x
    assert np.all(lg.predict(X) > 0)
    with pytest.raises(SurrogateError, match="cannot support"):
        make_surrogate("eq18").fit(X.iloc[:8], Y[:8])
