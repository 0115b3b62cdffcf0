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


def test_terms_the_runs_cannot_tell_apart_are_named_not_split():
    """A 2^5 full factorial: every square is the intercept column. statsmodels' pseudo-
    inverse split the intercept equally over the six (each 'significant', p 4e-18); the fit
    is refused naming the aliases. On a 3^3 grid the same response fits (full rank)."""
    X = pd.DataFrame(list(itertools.product([-1.0, 1.0], repeat=5)), columns=list("abcde"))
    y = X["a"] + 0.1 * X["b"] * X["c"]
    with pytest.raises(SurrogateError, match=r"a\^2 = 1 \(Intercept\); b\^2 = 1 \(Intercept\)"):
        make_surrogate("eq18").fit(X, y)
    X3 = pd.DataFrame(list(itertools.product([-1.0, 0.0, 1.0], repeat=3)), columns=list("abc"))
    est = make_surrogate("eq18").fit(X3, X3["a"] ** 2)
    assert est.summary_["r2"] == pytest.approx(1.0)


def test_a_validation_refit_that_cannot_be_fitted_leaves_that_number_out():
    """Box-Behnken on 3 variables: 13 runs for Eq. 18's 10 terms fit, but the 5-fold
    refits on 10-11 runs cannot (10 runs for 10 terms): Q² k-fold is None with the reason,
    the rest of the validation stands (it stopped the study after every run)."""
    from sensfw.analysis.validation import validate

    pts = []
    for i, j in [(0, 1), (0, 2), (1, 2)]:
        for a in (-1, 1):
            for b in (-1, 1):
                p = [0.0, 0.0, 0.0]
                p[i], p[j] = a, b
                pts.append(p)
    X = pd.DataFrame([*pts, [0.0, 0.0, 0.0]], columns=["x1", "x2", "x3"])
    rng = np.random.default_rng(0)
    y = 1 + X.x1 - 2 * X.x2 + 1.5 * X.x1**2 + 0.5 * X.x1 * X.x3 + 0.2 * rng.standard_normal(13)
    est = make_surrogate("eq18").fit(X, y)
    v = validate(est, X, y)
    assert v["q2_kfold"] is None
    # its lone centre run has leverage 1: PRESS is undefined (it printed Q2(LOO)=-inf)
    assert v["q2_loo"] is None and "leverage 1" in v["notes"]["q2_loo"]
    assert v["r2_adj"] == pytest.approx(est.summary_["r2_adj"])
    assert v["notes"]["q2_kfold"].startswith(
        "a refit on 10-11 of the 13 runs (5 folds) cannot be fitted")
    const = validate(make_surrogate("polynomial").fit(X, np.ones(13)), X, np.ones(13))
    assert "does not vary" in const["notes"]["r2"]


def test_physical_units_are_fitted_on_equilibrated_columns():
    """Table 2's physical units make Eq. 18's ratio form a matrix of condition 4e18 (a
    stiffness of 3e6 squared beside ratios of 1e-7): statsmodels' pseudo-inverse warned of
    a rank deficiency there. Fitted on columns scaled to unit magnitude (condition 1.2e3)
    it warns of nothing, and its coefficients are numpy's least squares on the same
    columns to 1e-9 (relative)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = make_surrogate("eq18", interaction="ratio", coding="physical").fit(X, Y)
    A, _ = design_matrix(X.to_numpy(float), list(X.columns), "ratio")
    s = np.abs(A).max(axis=0)
    c, *_ = np.linalg.lstsq(A / s, Y.to_numpy(), rcond=None)
    np.testing.assert_allclose(r.coefficients_["estimate"].to_numpy(), c / s, rtol=1e-9)
    np.testing.assert_allclose(r.predict(X), A @ (c / s), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("level", [2.0, 0.1, 1234.5])
def test_a_constant_response_has_undefined_fit_statistics(level):
    """SS_tot = 0 in exact arithmetic: R², R²adj, F and Q² are 0/0. np.full(27, 0.1) has a
    mean off in its last bit; statsmodels then reported R² -2.15, F -1.29 and Q² -9.46
    (and R² -inf, F -1.89 for 2.0)."""
    from sensfw.analysis.validation import validate

    y = np.full(len(X), level)
    est = make_surrogate("eq18").fit(X, y)
    for key in ("r2", "r2_adj", "f_stat", "f_pvalue", "q2"):
        assert np.isnan(est.summary_[key]), key
    out = validate(est, X, y)
    assert np.isnan(out["r2"]) and np.isnan(out["f_stat"]) and out["q2_loo"] is None
    assert "does not vary" in out["notes"]["r2"]
    # a small real spread on a large offset is still a response: R² as statsmodels gives it
    # on the centred response (round-off 1e-16 x 1e3 against a spread of 1e-6: 1e-7 rel.)
    y = 1e3 + 1e-6 * Y.to_numpy()
    import statsmodels.api as sm

    ref = sm.OLS(Y.to_numpy(), design_matrix(Z.to_numpy(), list(X.columns))[0]).fit()
    est = make_surrogate("eq18").fit(X, y)
    assert est.summary_["r2_adj"] == pytest.approx(ref.rsquared_adj, rel=1e-6)


def test_a_variable_that_does_not_vary_is_named_as_zero():
    """A variable held at one value codes to a zero column: its terms are 0, which the
    message said as 'x3 = ; x1:x3 = ; ...' (an empty right-hand side)."""
    Xc = X.assign(x3=5.0)
    with pytest.raises(SurrogateError, match=r"x3 = 0; x1:x3 = 0; x2:x3 = 0; x3\^2 = 0 "):
        make_surrogate("eq18").fit(Xc, Y)


@pytest.mark.parametrize("level", [3.0, 0.1, 7.77])
def test_a_constant_response_flags_no_term(level):
    """On the 3^4 grid a constant response had 4-6 of its 15 terms 'significant' at
    p < 0.05 (7.77: x1 p = 0.008, x2 p = 0.003, ...), t being round-off over round-off;
    Fig. 10b's significance and the agreement criteria read these p-values."""
    X4 = pd.DataFrame(list(itertools.product([-1.0, 0.0, 1.0], repeat=4)), columns=list("abcd"))
    est = make_surrogate("eq18").fit(X4, np.full(81, level))
    for table in (est.coefficient_table_, est.coefficient_table_coded_):
        assert table["p"].isna().all() and table["t"].isna().all()
    assert est.coefficient_table_coded_["estimate"].iloc[0] == pytest.approx(level)
