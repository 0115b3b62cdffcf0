"""The paper's Eq. 18 multiple linear regression (statsmodels OLS), scikit-learn style.

``y = a + sum_i b_i x_i + sum_{i<j} b_ij x_i x_j + sum_i b_ii x_i^2 + e`` with
``1 + 2m + m(m-1)/2`` coefficients for m variables. The printed Eq. 18 writes the pairwise
terms as ratios ``x_i / x_j`` while the paper's coefficient table (Fig. 10b) lists products
``x_i:x_j``; products are the default (``interaction="ratio"`` gives the printed form, in
physical units only). By default the fit is made on coded variables in [-1, 1] (well
conditioned); for the product form the physical-unit coefficients (the units of Fig. 10b)
come from a fit of the same model on physical values, whose predictions are identical (the
model space is invariant under an affine change of variables).
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, RegressorMixin

from ..plugins import surrogates
from ._validation import SurrogateError, check_xy, scaling


def design_matrix(X: np.ndarray, names: list[str], interaction: str = "product"):
    """Columns of Eq. 18 and their term names (intercept first)."""
    cols, terms = [np.ones(len(X))], ["(Intercept)"]
    m = X.shape[1]
    for i in range(m):
        cols.append(X[:, i])
        terms.append(names[i])
    for i, j in combinations(range(m), 2):
        if interaction == "product":
            cols.append(X[:, i] * X[:, j])
            terms.append(f"{names[i]}:{names[j]}")
        else:
            cols.append(X[:, i] / X[:, j])
            terms.append(f"{names[i]}/{names[j]}")
    for i in range(m):
        cols.append(X[:, i] ** 2)
        terms.append(f"{names[i]}^2")
    return np.column_stack(cols), terms


def _table(res, terms) -> pd.DataFrame:
    return pd.DataFrame({"term": terms, "estimate": res.params, "se": res.bse,
                         "t": res.tvalues, "p": res.pvalues})


@surrogates.register("eq18")
class Eq18(RegressorMixin, BaseEstimator):
    """Quadratic regression with pairwise interactions (Eq. 18).

    Parameters
    ----------
    interaction : {"product", "ratio"}
    coding : {"coded", "physical"}
        Fit on variables coded to [-1, 1] (from ``bounds`` or the data range) or as given.
    bounds : list of (low, high), optional
        Coding bounds per variable (e.g. the design's bounds).

    Fitted attributes: ``coefficients_`` (DataFrame term/estimate/se/t/p in the fitted
    coding), ``coefficients_physical_`` (physical units), ``summary_`` (r2, r2_adj, f_stat,
    f_pvalue, n_obs, n_terms, df_resid, q2 = leave-one-out 1 - PRESS/SS_tot, rmse),
    ``result_`` (the statsmodels results).
    """

    def __init__(self, interaction: str = "product", coding: str = "coded", bounds=None):
        self.interaction = interaction
        self.coding = coding
        self.bounds = bounds

    def _check(self):
        if self.interaction not in ("product", "ratio"):
            raise SurrogateError("Eq18: interaction must be 'product' or 'ratio'")
        if self.coding not in ("coded", "physical"):
            raise SurrogateError("Eq18: coding must be 'coded' or 'physical'")
        if self.interaction == "ratio" and self.coding != "physical":
            raise SurrogateError("Eq18: ratio terms x_i/x_j are only meaningful in physical "
                                 "units (coded values cross zero); use coding='physical'")

    def _encode(self, X):
        return (X - self.mid_) / self.half_ if self.coding == "coded" else X

    def fit(self, X, y):
        import statsmodels.api as sm

        self._check()
        X, y = check_xy(self, X, y, fit=True)
        names = list(self.feature_names_in_)
        self.mid_, self.half_ = scaling(self, X, self.bounds)
        A, terms = design_matrix(self._encode(X), names, self.interaction)
        if len(y) <= A.shape[1]:
            raise SurrogateError(f"Eq18: {len(y)} runs cannot support {A.shape[1]} "
                                 f"coefficients (1 + 2m + m(m-1)/2 for m = {X.shape[1]})")
        res = sm.OLS(y, A).fit()
        self.result_ = res
        self.terms_ = terms
        self.coefficients_ = _table(res, terms)
        if self.coding == "coded" and self.interaction == "product":
            Ap, _ = design_matrix(X, names, self.interaction)
            self.coefficients_physical_ = _table(sm.OLS(y, Ap).fit(), terms)
        else:
            self.coefficients_physical_ = self.coefficients_
        h = res.get_influence().hat_matrix_diag
        e = res.resid
        ss_tot = float(np.sum((y - y.mean()) ** 2))
        press = float(np.sum((e / (1 - h)) ** 2)) if np.all(h < 1 - 1e-12) else np.inf
        self.summary_ = {
            "r2": float(res.rsquared), "r2_adj": float(res.rsquared_adj),
            "f_stat": float(res.fvalue), "f_pvalue": float(res.f_pvalue),
            "n_obs": int(res.nobs), "n_terms": int(A.shape[1]), "df_resid": float(res.df_resid),
            "q2": float(1 - press / ss_tot) if ss_tot > 0 else float("nan"),
            "rmse": float(np.sqrt(np.mean(e**2))),
        }
        return self

    def _matrix(self, X):
        X = check_xy(self, X)
        A, _ = design_matrix(self._encode(X), list(self.feature_names_in_), self.interaction)
        return A

    def predict(self, X):
        return self.result_.predict(self._matrix(X))

    def predict_interval(self, X, alpha: float = 0.05):
        """(lower, upper) (1 - alpha) prediction intervals for new observations."""
        frame = self.result_.get_prediction(self._matrix(X)).summary_frame(alpha=alpha)
        return frame["obs_ci_lower"].to_numpy(), frame["obs_ci_upper"].to_numpy()
