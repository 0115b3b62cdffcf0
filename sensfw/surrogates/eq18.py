"""The paper's Eq. 18 multiple linear regression (statsmodels OLS), scikit-learn style.

``y = a + sum_i b_i x_i + sum_{i<j} b_ij x_i x_j + sum_i b_ii x_i^2 + e`` with
``1 + 2m + m(m-1)/2`` coefficients for m variables. The printed Eq. 18 writes the pairwise
terms as ratios ``x_i / x_j`` while the paper's coefficient table (Fig. 10b) lists products
``x_i:x_j``; products are the default (``interaction="ratio"`` gives the printed form, in
physical units only). By default the fit is made on coded variables in [-1, 1] (well
conditioned); for the product form the physical-unit coefficients (the units of Fig. 10b)
come from a fit of the same model on physical values, whose predictions are identical (the
model space is invariant under an affine change of variables); they are computed from the
coded fit by that exact linear map (with its covariance), not by refitting an
ill-conditioned physical design matrix.

Factor-10 ranges (contact stiffness, stiction velocities, damping in Table 1) are often
better described on a logarithmic scale: ``log_features="auto"`` regresses on ``log10(x)``
for every variable whose range spans at least a factor 10 (or give a list of names), and
``log_response=True`` fits ``log(y)`` (predictions are transformed back). Both are off by
default, which is the paper's Eq. 18.
"""

from __future__ import annotations

from itertools import combinations
from typing import Literal

import numpy as np
import pandas as pd
from pydantic import Field, model_validator
from sklearn.utils.validation import check_is_fitted

from ..analysis.validation import total_ss
from ..options import Bool, Pairs, PluginOptions, Str
from ..plugins import surrogates
from .base import (
    BOUNDS,
    SurrogateBase,
    SurrogateError,
    check_alpha,
    feature_names,
    scaling,
)


def aliased_terms(A: np.ndarray, terms: list[str], rtol: float = 1e-8) -> list[str]:
    """The columns of ``A`` that are linear combinations of the columns before them, each
    as ``"term = combination"`` (empty where ``A`` has full column rank). statsmodels fits
    such a matrix by its pseudo-inverse without an error: it splits the one estimable
    effect equally between the aliased terms and reports each as significant."""
    out, kept = [], []
    for j in range(A.shape[1]):
        col = A[:, j]
        norm = float(np.linalg.norm(col))
        if kept:
            B = A[:, kept]
            c, *_ = np.linalg.lstsq(B, col, rcond=None)
            if norm == 0 or np.linalg.norm(col - B @ c) <= rtol * norm:
                parts = [f"{v:+.3g} {terms[k]}" for v, k in zip(c, kept, strict=True)
                         if abs(v) > 1e-6 * max(np.abs(c).max(), 1e-300)]
                out.append(f"{terms[j]} = {' '.join(parts).lstrip('+') or '0'}")
                continue
        elif norm == 0:
            out.append(f"{terms[j]} = 0")
            continue
        kept.append(j)
    return out


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


def _table(res, terms, scale: np.ndarray) -> pd.DataFrame:
    """The coefficient table in the design matrix's own units (the fit's columns were
    divided by ``scale``; t and p do not change with it)."""
    return pd.DataFrame({"term": terms, "estimate": res.params / scale,
                         "se": res.bse / scale, "t": res.tvalues, "p": res.pvalues})


def column_scale(A: np.ndarray) -> np.ndarray:
    """Each column's largest magnitude (1 for a zero column): the fit runs on ``A /
    scale``. In physical units Eq. 18's columns span many decades (a stiffness of 3e6 N/mm
    squared beside a ratio of 1e-5), and the pseudo-inverse behind statsmodels' OLS then
    cuts singular values that equilibrated columns keep: a rank-deficiency warning and
    coefficients that are not the least-squares solution. Scaling columns changes neither
    the fitted values nor the t statistics."""
    s = np.max(np.abs(A), axis=0)
    return np.where(s > 0, s, 1.0)


def coded_to_physical(m: int, mid: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Matrix T with ``beta_physical = T beta_coded`` for the product form of Eq. 18 when
    ``z = (u - mid) / half``: substitute ``z_i = c_i u_i + d_i`` (``c = 1/half``,
    ``d = -mid/half``) and collect the terms."""
    c, d = 1.0 / half, -mid / half
    pairs = list(combinations(range(m), 2))
    n = 1 + 2 * m + len(pairs)
    lin = {i: 1 + i for i in range(m)}
    pair = {pq: 1 + m + k for k, pq in enumerate(pairs)}
    sq = {i: 1 + m + len(pairs) + i for i in range(m)}
    T = np.zeros((n, n))
    T[0, 0] = 1.0
    for i in range(m):
        T[0, lin[i]] = d[i]
        T[lin[i], lin[i]] = c[i]
        T[0, sq[i]] = d[i] ** 2
        T[lin[i], sq[i]] = 2 * c[i] * d[i]
        T[sq[i], sq[i]] = c[i] ** 2
    for (i, j), k in pair.items():
        T[0, k] = d[i] * d[j]
        T[lin[i], k] = c[i] * d[j]
        T[lin[j], k] = c[j] * d[i]
        T[k, k] = c[i] * c[j]
    return T


@surrogates.register("eq18")
class Eq18(SurrogateBase):
    """Quadratic regression with pairwise interactions (Eq. 18).

    Parameters
    ----------
    interaction : {"product", "ratio"}
    coding : {"coded", "physical"}
        Fit on variables coded to [-1, 1] (from ``bounds`` or the data range) or as given.
    bounds : list of (low, high), optional
        Coding bounds per variable (e.g. the design's bounds).

    Fitted attributes: ``coefficient_table_`` (DataFrame term/estimate/se/t/p in physical
    units) and ``coefficient_table_coded_`` (in the fitted coding), also named
    ``coefficients_physical_`` and ``coefficients_``; ``summary_`` (r2, r2_adj, f_stat,
    f_pvalue, n_obs, n_terms, df_resid, q2 = leave-one-out 1 - PRESS/SS_tot, rmse, response);
    ``result_`` (the statsmodels results). Leave-one-out by the hat matrix (``loo_method``);
    prediction intervals from the OLS fit.
    """

    class Options(PluginOptions):
        interaction: Literal["product", "ratio"] = Field(description="'product' or 'ratio'")
        coding: Literal["coded", "physical"] = Field(description="'coded' or 'physical'")
        bounds: Pairs = Field(description=BOUNDS)
        log_features: Literal["auto"] | list[Str] | None = Field(
            description="'auto', a list of variable names or none")
        log_response: Bool = Field(description="true or false")

        @model_validator(mode="after")
        def _ratio_in_physical_units(self):
            if self.interaction == "ratio" and self.coding != "physical":
                raise SurrogateError("interaction 'ratio' (terms x_i/x_j) needs "
                                     "coding='physical': coded values cross zero",
                                     option="interaction")
            return self
    loo_method = "hat matrix (PRESS)"

    def __init__(self, interaction: str = "product", coding: str = "coded", bounds=None,
                 log_features=None, log_response: bool = False):
        self.interaction = interaction
        self.coding = coding
        self.bounds = bounds
        self.log_features = log_features
        self.log_response = log_response

    def _logs(self, X: np.ndarray, names: list[str]) -> np.ndarray:
        """Which columns are regressed on log10 (decided at fit)."""
        lf = self.log_features
        if lf is None:
            return np.zeros(len(names), bool)
        if isinstance(lf, str):  # "auto" (checked by Options)
            lo, hi = (np.asarray(self.bounds, float).T if self.bounds is not None
                      else (X.min(axis=0), X.max(axis=0)))
            return (lo > 0) & (hi >= 10 * lo)
        unknown = set(lf) - set(names)
        if unknown:
            raise SurrogateError(f"Eq18: log_features {sorted(unknown)} are not features "
                                 f"({', '.join(names)})", option="log_features")
        return np.array([n in lf for n in names])

    def _features(self, X: np.ndarray) -> np.ndarray:
        U = X.copy()
        if self.log_mask_.any():
            if np.any(X[:, self.log_mask_] <= 0):
                raise SurrogateError("Eq18: log features need positive values",
                                     option="log_features")
            U[:, self.log_mask_] = np.log10(X[:, self.log_mask_])
        return U

    def _encode(self, U):
        return (U - self.mid_) / self.half_ if self.coding == "coded" else U

    def fit(self, X, y):
        import statsmodels.api as sm

        X, y = self._begin_fit(X, y)
        if self.log_response:
            if np.any(y <= 0):
                raise SurrogateError("Eq18: log_response needs positive responses")
            y = np.log(y)
        names = feature_names(self)
        b = None if self.bounds is None else np.asarray(self.bounds, float)
        if b is not None and b.shape != (X.shape[1], 2):
            raise SurrogateError(f"Eq18: bounds must be {X.shape[1]} pairs (low, high), got "
                                 f"shape {b.shape}", option="bounds")
        self.log_mask_ = self._logs(X, names)
        U = self._features(X)
        bounds = None if b is None else self._features(b.T).T
        self.mid_, self.half_ = scaling(self, U, bounds)
        fnames = [f"log10({n})" if lg else n for n, lg in zip(names, self.log_mask_,
                                                               strict=True)]
        A, terms = design_matrix(self._encode(U), fnames, self.interaction)
        if len(y) <= A.shape[1]:
            raise SurrogateError(f"Eq18: {len(y)} runs (n_samples = {len(y)}) cannot support "
                                 f"{A.shape[1]} "
                                 f"coefficients (1 + 2m + m(m-1)/2 for m = {X.shape[1]})")
        aliased = aliased_terms(A, terms)
        if aliased:
            raise SurrogateError(
                "Eq18: the runs cannot tell apart " + "; ".join(aliased) + " (a term the "
                "design does not vary independently: a square on two levels, a variable "
                "left at one or two levels by failed runs); Eq. 18 needs three levels of every "
                "variable: a 3-level or response-surface design, or another surrogate")
        self.scale_ = column_scale(A)
        A = A / self.scale_
        res = sm.OLS(y, A).fit()
        self.result_ = res
        self.terms_ = terms
        self.coefficients_ = _table(res, terms, self.scale_)
        if self.coding == "coded" and self.interaction == "product":
            from scipy import stats

            T = coded_to_physical(X.shape[1], self.mid_, self.half_)
            S = np.diag(1.0 / self.scale_)  # the fit's coefficients -> the coded ones
            beta = T @ S @ res.params
            se = np.sqrt(np.maximum(np.diag(T @ S @ res.cov_params() @ S @ T.T), 0.0))
            with np.errstate(divide="ignore", invalid="ignore"):
                t = beta / se
            p = 2 * stats.t.sf(np.abs(t), res.df_resid)
            self.coefficients_physical_ = pd.DataFrame({"term": terms, "estimate": beta,
                                                        "se": se, "t": t, "p": p})
        else:
            self.coefficients_physical_ = self.coefficients_
        h = res.get_influence().hat_matrix_diag
        e = res.resid
        ss_tot = total_ss(y)
        if ss_tot == 0:  # a constant response: every t is round-off over round-off
            for table in (self.coefficients_, self.coefficients_physical_):
                table[["se", "t", "p"]] = [0.0, np.nan, np.nan]
        # a run of leverage 1 (a lone centre point of a saturated design) is fitted exactly
        # whatever its value: its left-out prediction, and so PRESS, is undefined
        press = float(np.sum((e / (1 - h)) ** 2)) if np.all(h < 1 - 1e-9) else np.nan
        nan = float("nan")  # a constant response: statsmodels divides round-off by 0
        self.summary_ = {
            "r2": float(res.rsquared) if ss_tot > 0 else nan,
            "r2_adj": float(res.rsquared_adj) if ss_tot > 0 else nan,
            "f_stat": float(res.fvalue) if ss_tot > 0 else nan,
            "f_pvalue": float(res.f_pvalue) if ss_tot > 0 else nan,
            "n_obs": int(res.nobs), "n_terms": int(A.shape[1]), "df_resid": float(res.df_resid),
            "q2": float(1 - press / ss_tot) if ss_tot > 0 else float("nan"),
            "rmse": float(np.sqrt(np.mean(e**2))),
            "response": "log(y)" if self.log_response else "y",
        }
        with np.errstate(divide="ignore", invalid="ignore"):  # leverage 1: undefined
            self.press_residuals_ = np.where(h < 1 - 1e-9, e / (1 - h), np.nan)
        self.coefficient_table_ = self.coefficients_physical_
        self.coefficient_table_coded_ = self.coefficients_
        return self

    def _matrix(self, X):
        X = self._check_predict(X)
        A, _ = design_matrix(self._encode(self._features(X)), feature_names(self),
                             self.interaction)
        return A / self.scale_

    def _back(self, v):
        return np.exp(v) if self.log_response else v

    def predict(self, X):
        A = self._matrix(X)
        return self._back(self.result_.predict(A))

    def loo_predict(self) -> np.ndarray:
        """Leave-one-out predictions at the training runs from the hat matrix,
        ``y_i - e_i / (1 - h_ii)`` (on the response scale of the fit, see ``summary_``)."""
        check_is_fitted(self)
        return self._back(self.result_.model.endog - self.press_residuals_)

    def predict_interval(self, X, alpha: float = 0.05):
        """(lower, upper) (1 - alpha) prediction intervals for new observations."""
        alpha = check_alpha(self, alpha)
        A = self._matrix(X)
        frame = self.result_.get_prediction(A).summary_frame(alpha=alpha)
        return (self._back(frame["obs_ci_lower"].to_numpy()),
                self._back(frame["obs_ci_upper"].to_numpy()))
