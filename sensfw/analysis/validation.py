"""Regression validation: fit quality, predictive quality and confirmation runs.

R^2 of a 15-term model on 81 runs flatters it; cross-validated Q^2 (leave-one-out and
k-fold), residual plots, variance inflation factors and confirmation runs at new points tell
whether it predicts.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats
from sklearn.base import clone
from sklearn.model_selection import KFold

from ..errors import AnalysisError, SensfwError

#: a response whose spread is at most this fraction of its largest magnitude is constant up
#: to round-off: ``np.full(27, 0.1)`` has a mean that differs from 0.1 in its last bit, and
#: an SS_tot of 1e-31 made R² -2.1 and Q² -9.5 out of nothing
ROUND_OFF = 1e-12


def total_ss(y) -> float:
    """SS_tot of ``y`` about its mean; 0 where ``y`` is constant up to :data:`ROUND_OFF`
    (then R², R²adj, F and Q² are undefined)."""
    y = np.asarray(y, float)
    if y.size == 0 or np.ptp(y) <= ROUND_OFF * np.max(np.abs(y)):
        return 0.0
    return float(np.sum((y - y.mean()) ** 2))


def _arrays(X, y):
    """X and y as float arrays; an :class:`AnalysisError` where their lengths differ or a
    response is not finite (a failed run: leave it out before validating)."""
    Xa = X.to_numpy(dtype=float) if isinstance(X, pd.DataFrame) else np.asarray(X, float)
    ya = np.asarray(y, float).ravel()
    if len(ya) != len(Xa):
        raise AnalysisError(f"{len(ya)} responses for {len(Xa)} runs")
    bad = int(np.sum(~np.isfinite(ya)))
    if bad:
        raise AnalysisError(f"{bad} of the {len(ya)} responses are not finite (failed runs): "
                            "leave them out first")
    return Xa, ya


def q2_cv(estimator, X, y, splitter) -> float:
    """Predictive Q^2 = 1 - PRESS / SS_tot from refits on the training folds."""
    Xa, ya = _arrays(X, y)
    frame = X if isinstance(X, pd.DataFrame) else None
    pred = np.empty_like(ya)
    for train, test in splitter.split(Xa):
        est = clone(estimator)
        if frame is not None:
            est.fit(frame.iloc[train], ya[train])
            pred[test] = est.predict(frame.iloc[test])
        else:
            est.fit(Xa[train], ya[train])
            pred[test] = est.predict(Xa[test])
    ss = total_ss(ya)
    return float(1 - np.sum((ya - pred) ** 2) / ss) if ss > 0 else float("nan")


def vif(X) -> dict[str, float]:
    """Variance inflation factors of the columns of X (1 = orthogonal; inf for a column that
    does not vary, which the intercept reproduces exactly)."""
    from statsmodels.stats.outliers_influence import variance_inflation_factor

    Xa, _ = _arrays(X, np.zeros(len(X)))
    names = list(X.columns) if isinstance(X, pd.DataFrame) else [f"x{i + 1}" for i in
                                                                 range(Xa.shape[1])]
    # a column that does not vary lies in the intercept's span: leaving it out changes no
    # other column's R^2_j, and keeps the matrix the others are regressed on of full rank
    varies = [i for i in range(Xa.shape[1]) if total_ss(Xa[:, i]) > 0]
    A = np.column_stack([np.ones(len(Xa)), Xa[:, varies]])
    at = {i: k + 1 for k, i in enumerate(varies)}
    return {n: float(variance_inflation_factor(A, at[i])) if i in at else float("inf")
            for i, n in enumerate(names)}


def validate(estimator, X, y, k: int = 5, seed: int = 0) -> dict:
    """Quality of a fitted ``estimator`` (a :class:`~sensfw.surrogates.Surrogate`) on its
    training data ``X, y`` (JSON-serialisable). Leave-one-out Q^2 comes from its
    ``summary_`` (Eq. 18's hat matrix), else its ``loo_predict()``, else n refits. A
    number that cannot be computed (a score that does not vary; a refit on fewer runs that
    the surrogate cannot fit, e.g. Eq. 18 on 4/5 of a 13-run Box-Behnken design) is None,
    with the reason in ``"notes"``, keyed by the number it concerns (``"r2"``, ``"q2_loo"``,
    ``"q2_kfold"``)."""
    Xa, ya = _arrays(X, y)
    n = len(ya)
    if n < 3:
        raise AnalysisError(f"validation needs at least 3 runs, got {n}")
    fitted = np.asarray(estimator.predict(X), float)
    resid = ya - fitted
    ss = total_ss(ya)
    summary = estimator.summary_ or {}
    r2 = float(1 - np.sum(resid**2) / ss) if ss > 0 else float("nan")
    # statistics on the scale of y (a surrogate may fit a transformed response)
    same_scale = summary.get("response", "y") == "y"
    p = summary.get("n_terms")
    out = {
        "n_obs": n,
        "r2": r2,
        "r2_adj": (1 - (1 - r2) * (n - 1) / (n - p)) if p and n > p else None,
        "rmse": float(np.sqrt(np.mean(resid**2))),
        "f_stat": summary.get("f_stat") if same_scale else None,
        "f_pvalue": summary.get("f_pvalue") if same_scale else None,
        "q2_loo": summary.get("q2") if same_scale else None,
        "q2_kfold": None,
        "fitted": fitted.tolist(),
        "residuals": resid.tolist(),
        "notes": {},
    }
    if not ss > 0:
        out["notes"]["r2"] = (f"the score does not vary over the {n} runs (every one "
                              f"{ya[0]:.4g}): R², R²adj and Q² are undefined")
    undefined = out["q2_loo"] is not None and not np.isfinite(out["q2_loo"])
    if undefined:
        out["q2_loo"] = None
        if ss > 0:
            out["notes"]["q2_loo"] = ("a run has leverage 1 (the fit passes through it "
                                      "whatever its value), so its left-out prediction is "
                                      "undefined")
    out["q2_loo_method"] = "hat matrix" if out["q2_loo"] is not None else None
    loo = estimator.loo_predict() if out["q2_loo"] is None and not undefined else None
    if loo is not None:
        loo = np.asarray(loo, float)
        if np.all(np.isfinite(loo)) and ss > 0:
            out["q2_loo"] = float(1 - np.sum((ya - loo) ** 2) / ss)
            out["q2_loo_method"] = estimator.loo_method
    if out["q2_loo"] is None and not undefined:
        try:
            out["q2_loo"] = q2_cv(estimator, X, ya, KFold(n_splits=n))
            out["q2_loo_method"] = f"{n} refits"
        except SensfwError as err:
            out["notes"]["q2_loo"] = f"a refit on {n - 1} runs failed ({err})"
    kk = min(k, n)
    if kk >= 2:
        try:
            out["q2_kfold"] = q2_cv(estimator, X, ya, KFold(n_splits=kk, shuffle=True,
                                                              random_state=seed))
        except SensfwError as err:
            lo, hi = n - -(-n // kk), n - n // kk  # training folds' sizes
            size = f"{lo}" if lo == hi else f"{lo}-{hi}"
            out["notes"]["q2_kfold"] = (f"a refit on {size} of the {n} runs ({kk} folds) "
                                        f"cannot be fitted ({err})")
    (osm, osr), (slope, intercept, _) = stats.probplot(resid, dist="norm")
    out["qq"] = {"theoretical": osm.tolist(), "ordered": osr.tolist(), "slope": float(slope),
                 "intercept": float(intercept)}
    if Xa.shape[1] >= 2 and n > Xa.shape[1] + 1:
        out["vif"] = vif(X)
    return out


def confirmation(estimator, X_new, y_new, alpha: float = 0.05) -> dict:
    """Prediction error at new points, and the coverage of (1 - alpha) prediction intervals
    where the estimator provides them (``predict_interval`` not None)."""
    _, ya = _arrays(X_new, y_new)
    if len(ya) == 0:
        raise AnalysisError("no confirmation runs finished")
    pred = np.asarray(estimator.predict(X_new), float)
    err = ya - pred
    ss = total_ss(ya)
    out = {"n": len(ya), "rmse": float(np.sqrt(np.mean(err**2))),
           "max_abs_error": float(np.max(np.abs(err))),
           "r2": float(1 - np.sum(err**2) / ss) if ss > 0 else float("nan"),
           "level": 1 - alpha, "coverage": None}
    interval = estimator.predict_interval(X_new, alpha=alpha)
    if interval is not None:
        lo, hi = interval
        out["coverage"] = float(np.mean((ya >= lo) & (ya <= hi)))
    return out
