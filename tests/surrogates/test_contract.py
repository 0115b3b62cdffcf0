"""Every registered surrogate keeps the surrogate contract (issues 5 and 12):
scikit-learn's estimator rules and the declared members reports read
(:class:`sensfw.surrogates.Surrogate`)."""

import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone
from sklearn.exceptions import NotFittedError

from sensfw.errors import SensfwError
from sensfw.plugins import surrogates
from sensfw.surrogates import Surrogate, SurrogateError, make_surrogate, option_problems

rng = np.random.default_rng(0)
X = pd.DataFrame(rng.uniform(-1, 1, (40, 3)), columns=["a", "b", "c"])
Y = 1 + 2 * X["a"] - X["b"] ** 2 + 0.5 * X["a"] * X["c"] + 0.01 * rng.standard_normal(40)
# auto over cheap candidates (each auto fit is 6 fits per candidate; the forest and the GP
# have their own contract tests, and auto passing on their None members is tested below)
LIGHT = {"auto": {"candidates": ("eq18", "polynomial")}}


@pytest.mark.parametrize("name", surrogates.names())
def test_surrogate_contract(name):
    est = make_surrogate(name, **LIGHT.get(name, {}))
    Xc, yc = X.copy(), Y.copy()
    assert est.fit(X, Y) is est
    pd.testing.assert_frame_equal(X, Xc)  # inputs not mutated
    pd.testing.assert_series_equal(Y, yc)
    pred = est.predict(X)
    assert pred.shape == (40,)
    assert np.sqrt(np.mean((pred - Y) ** 2)) < 0.5 * np.std(Y)  # it learned something
    again = clone(est).fit(X, Y).predict(X)
    np.testing.assert_allclose(again, pred, rtol=1e-8, atol=1e-10)  # deterministic
    assert list(est.feature_names_in_) == ["a", "b", "c"]
    bad = X.copy()
    bad.iloc[3, 1] = np.nan
    with pytest.raises(SensfwError, match="NaN"):
        clone(est).fit(bad, Y)
    with pytest.raises(SurrogateError, match="colour: unknown option; known: "):
        make_surrogate(name, colour="red")


@pytest.mark.parametrize("name", surrogates.names())
def test_declared_members(name):
    est = make_surrogate(name, **LIGHT.get(name, {}))
    with pytest.raises(NotFittedError):
        est.predict(X)
    with pytest.raises(NotFittedError):
        est.loo_predict()
    est.fit(X, Y)
    assert isinstance(est, Surrogate)
    assert est.summary_ is None or isinstance(est.summary_, dict)
    for table in (est.coefficient_table_, est.coefficient_table_coded_):
        assert table is None or list(table.columns[:5]) == ["term", "estimate", "se", "t", "p"]
    assert (est.coefficient_table_ is None) == (est.coefficient_table_coded_ is None)
    loo = est.loo_predict()
    assert (loo is None) == (est.loo_method is None)
    if loo is not None:
        assert loo.shape == (40,) and np.all(np.isfinite(loo))
        # a leave-one-out prediction misses more than the fit but still learned something
        fit_err = np.mean((est.predict(X) - Y) ** 2)
        assert fit_err <= np.mean((loo - Y) ** 2) + 1e-12 < np.var(Y)
    interval = est.predict_interval(X.iloc[:5])
    if interval is not None:
        lo, hi = interval
        pred = est.predict(X.iloc[:5])
        assert np.all(lo <= pred) and np.all(pred <= hi)


def test_eq18_declares_its_coefficients_and_auto_passes_them_on():
    eq = make_surrogate("eq18").fit(X, Y)
    assert eq.summary_["n_terms"] == len(eq.coefficient_table_) == 10  # 1 + 2*3 + 3
    auto = make_surrogate("auto", candidates=("eq18", "gaussian_process")).fit(X, Y)
    assert auto.chosen_ == "eq18"  # the true model (a quadratic) has the best Q²
    pd.testing.assert_frame_equal(auto.coefficient_table_, eq.coefficient_table_)
    assert auto.summary_ == eq.summary_ and auto.loo_method == eq.loo_method
    np.testing.assert_allclose(auto.loo_predict(), eq.loo_predict())


def test_option_problems_name_every_bad_option():
    eq18 = surrogates.get("eq18")
    assert option_problems(eq18, {}) == []
    got = dict(option_problems(eq18, {"interaction": "bogus", "coding": "both"}))
    assert set(got) == {"interaction", "coding"}
    assert "'product'" in got["interaction"] and "'ratio'" in got["interaction"]
    got = dict(option_problems(eq18, {"interaction": "ratio"}))  # needs coding="physical"
    assert "physical" in got["interaction"]
    got = dict(option_problems(eq18, {"levelz": 3, "log_response": True}))
    assert got == {"levelz": "unknown option; known: bounds, coding, interaction, "
                             "log_features, log_response"}
    got = dict(option_problems(surrogates.get("auto"), {"candidates": ["eq18", "eq19"]}))
    assert "unknown surrogate 'eq19'" in got["candidates"]


def test_auto_passes_on_the_absence_of_members_too():
    auto = make_surrogate("auto", candidates=("polynomial",)).fit(X, Y)
    assert auto.chosen_ == "polynomial"
    assert auto.summary_ is None and auto.coefficient_table_ is None
    assert auto.loo_method is None and auto.loo_predict() is None
    assert auto.predict_interval(X) is None


@pytest.mark.parametrize("name", ["eq18", "gaussian_process"])
def test_a_log_feature_that_is_no_feature_is_an_error(name):
    """``log_features=["K1"]`` for a feature ``k1``: the Gaussian process fitted without
    any log transform and said nothing (Eq. 18 refused it)."""
    from sensfw.surrogates import SurrogateError, make_surrogate

    rng = np.random.default_rng(0)
    X = pd.DataFrame({"k1": rng.uniform(1, 100, 20), "c1": rng.uniform(0, 1, 20)})
    with pytest.raises(SurrogateError, match=r"log_features \['K1'\] are not features"):
        make_surrogate(name, log_features=["K1"]).fit(X, X["k1"] + X["c1"])
    est = make_surrogate(name, log_features=["k1"]).fit(X, np.log10(X["k1"]) + X["c1"])
    assert list(est.log_mask_) == [True, False]


@pytest.mark.parametrize("n", [12, 32])
def test_gaussian_process_loo_is_the_refit_with_its_kernel_held(n):
    """The closed-form leave-one-out equals n refits with the fitted kernel held fixed,
    each on the other runs (their own mean as the prior mean): on pure noise the former
    form, with every run's mean, gave Q² +0.004 where the refits give -0.156 (n = 12)."""
    from sklearn.gaussian_process import GaussianProcessRegressor

    rng = np.random.default_rng(0)
    Xn = pd.DataFrame(rng.uniform(0, 1, (n, 2)), columns=["a", "b"])
    y = rng.standard_normal(n)
    g = make_surrogate("gaussian_process", bounds=[(0, 1), (0, 1)]).fit(Xn, y)
    Z = Xn.to_numpy()
    ref = np.empty(n)
    for i in range(n):
        k = np.arange(n) != i
        m = y[k].mean()
        gp = GaussianProcessRegressor(g.model_.kernel_, optimizer=None).fit(
            Z[k], (y[k] - m) / g.y_scale_)
        ref[i] = m + g.y_scale_ * gp.predict(Z[i:i + 1])[0]
    np.testing.assert_allclose(g.loo_predict(), ref, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("name", surrogates.names())
def test_a_response_of_strings_is_a_surrogate_error(name):
    """scikit-learn's ``y_numeric`` converts only object arrays: a string array reached the
    fit (Eq18: ValueError 'data type must provide an itemsize'; the GP: TypeError)."""
    y = np.array(["slow", "fast"] * (len(X) // 2))
    with pytest.raises(SurrogateError, match="y must be numeric"):
        make_surrogate(name, **LIGHT.get(name, {})).fit(X, y)


@pytest.mark.parametrize("name", ["eq18", "gaussian_process"])
@pytest.mark.parametrize("alpha", [0, 1, 1.5, -0.1, float("nan"), "5%"])
def test_an_interval_level_outside_0_1_is_an_error(name, alpha):
    """alpha 1.5 gave intervals with lower > upper (Eq18 on X: 1.218 > 1.203), alpha 0
    infinite ones, without a word."""
    est = make_surrogate(name).fit(X, Y)
    with pytest.raises(SurrogateError, match=r"alpha must be in \(0, 1\)"):
        est.predict_interval(X.iloc[:2], alpha=alpha)


def test_eq18_interval_is_the_ols_prediction_interval():
    """Against statsmodels' OLS on the same coded columns: mean +- t(0.95, n - p) * sqrt(s²
    (1 + a (A'A)^-1 a')); equal to round-off (1e-10 relative)."""
    import statsmodels.api as sm

    from sensfw.surrogates.eq18 import design_matrix

    Z = (X - (X.max() + X.min()) / 2) / ((X.max() - X.min()) / 2)
    ref = sm.OLS(Y.to_numpy(), design_matrix(Z.to_numpy(), list("abc"))[0]).fit()
    frame = ref.get_prediction(design_matrix(Z.to_numpy()[:5], list("abc"))[0]) \
        .summary_frame(alpha=0.1)
    lo, hi = make_surrogate("eq18").fit(X, Y).predict_interval(X.iloc[:5], alpha=0.1)
    np.testing.assert_allclose(lo, frame["obs_ci_lower"], rtol=1e-10)
    np.testing.assert_allclose(hi, frame["obs_ci_upper"], rtol=1e-10)


def test_polynomial_lars_on_two_runs_or_a_constant_response():
    """LassoLarsCV raised numpy's 'attempt to get argmin of an empty sequence' for both; a
    constant response is fitted by its mean (every coefficient 0, one term)."""
    with pytest.raises(SurrogateError, match="needs at least 3 runs, got 2"):
        make_surrogate("polynomial", selection="lars").fit(X.iloc[:2], Y[:2])
    est = make_surrogate("polynomial", selection="lars").fit(X, np.full(len(X), 0.1))
    np.testing.assert_allclose(est.predict(X), 0.1, rtol=1e-12)
    assert est.n_terms_ == 1


@pytest.mark.parametrize("name", ["eq18", "polynomial", "gaussian_process"])
@pytest.mark.parametrize("bad", [(1.0, -1.0), (0.5, 0.5)])
def test_bounds_with_low_not_below_high_are_refused(name, bad):
    """Reversed or empty bounds fitted silently with a half-range of 1 in place of theirs:
    Eq. 18's coded coefficients were then in no coding at all."""
    bounds = [(-1.0, 1.0), bad, (-1.0, 1.0)]
    with pytest.raises(SurrogateError, match=r"bounds must have low < high, got b: ") as err:
        make_surrogate(name, bounds=bounds).fit(X, Y)
    assert err.value.option == "bounds"


def test_log_features_need_positive_values_and_bounds_of_the_right_shape():
    """The GP clamped log features at 1e-300: a value <= 0 became log10 = -300 (on X - 0.5
    a fit that predicted 1.21 where the response is 0.92, without a word); Eq18 took
    log10(|low|) of a negative bound; and Eq18 broadcast one (low, high) pair over every
    variable."""
    Xp = X + 2.0  # positive
    for name in ("eq18", "gaussian_process"):
        with pytest.raises(SurrogateError, match="log features need positive values"):
            make_surrogate(name, log_features=["a"]).fit(X, Y)
        with pytest.raises(SurrogateError, match="log features need positive values"):
            make_surrogate(name, log_features=["a"], bounds=[(-1.0, 3.0)] * 3).fit(Xp, Y)
        est = make_surrogate(name, log_features=["a"]).fit(Xp, Y)
        with pytest.raises(SurrogateError, match="log features need positive values"):
            est.predict(X)
    with pytest.raises(SurrogateError, match=r"bounds must be 3 pairs .* shape \(1, 2\)"):
        make_surrogate("eq18", bounds=[(1.0, 3.0)]).fit(Xp, Y)


def test_a_kernel_of_other_dimensions_is_a_surrogate_error():
    """An anisotropic kernel fitted on other inputs raised scikit-learn's bare ValueError
    ('Anisotropic kernel must have the same number of dimensions as data (2!=3)'); one
    fitted on the same inputs is taken (``model_.kernel_`` restarts a search)."""
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    kernel = ConstantKernel() * RBF([1.0, 1.0]) + WhiteKernel()
    with pytest.raises(SurrogateError, match="the kernel has 2 length scales for 3 inputs"):
        make_surrogate("gaussian_process", kernel=kernel).fit(X, Y)
    fitted = make_surrogate("gaussian_process").fit(X, Y).model_.kernel_
    again = make_surrogate("gaussian_process", kernel=fitted, optimize=False).fit(X, Y)
    assert again.model_.kernel_ == fitted
