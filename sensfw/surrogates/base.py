"""The surrogate contract: what every surrogate provides and what reports may read.

A surrogate is a scikit-learn regressor (``fit(X, y)`` returns ``self``, ``predict(X)``,
constructor parameters stored unchanged, fitted attributes end in ``_``; see scikit-learn's
*Developing estimators*) with scikit-learn's input validation (``validate_data``;
``predict`` before ``fit`` raises :class:`sklearn.exceptions.NotFittedError`) and these
declared members, which reports and validation read directly instead of probing:

``summary_`` : dict or None
    Fit statistics of a regression with a parametric form (Eq. 18: ``r2``, ``r2_adj``,
    ``q2`` (leave-one-out), ``f_stat``, ``f_pvalue``, ``n_obs``, ``n_terms``, ``df_resid``,
    ``rmse`` and ``response``, the scale the statistics are on: ``"y"`` or ``"log(y)"``);
    None for the others.
``coefficient_table_`` : DataFrame or None
    Columns ``term, estimate, se, t, p``, in physical units (Fig. 10b); None if the
    surrogate has no coefficients.
``coefficient_table_coded_`` : DataFrame or None
    The same in the coding the fit used (variables coded to [-1, 1] by default).
``loo_method`` : str or None
    How :meth:`loo_predict` obtains leave-one-out predictions without refits; None when it
    cannot (validation then refits n times).
``loo_predict()`` : ndarray or None
    Leave-one-out predictions at the training points, or None (see ``loo_method``).
``predict_interval(X, alpha=0.05)`` : (lower, upper) or None
    (1 - alpha) prediction intervals for new observations, or None where the surrogate has
    no calibrated intervals.

:class:`Surrogate` states this as a :class:`typing.Protocol`; :class:`SurrogateBase` gives
the defaults (no summary, no coefficients, no cheap leave-one-out, no intervals), the input
validation and the option checks. Options are declared in ``Options``
(:mod:`sensfw.options`, the contract of every plugin kind), so a study's bad option is
reported before anything runs; the constructor only stores them (scikit-learn's rule) and
``fit`` checks them again.
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Protocol, runtime_checkable

import numpy as np
import pandas as pd
from pydantic import Field
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from ..errors import OptionError
from ..options import Int, describe, option_problems

#: descriptions shared by the surrogates' declared options
BOUNDS = "a list of (low, high) pairs, one per variable, or none (the data's range)"
SEED = "an integer >= 0 or none"
RandomState = Annotated[Int, Field(ge=0)] | None


class SurrogateError(OptionError):
    """A surrogate got bad options or data (``option`` names the option, where one is at
    fault)."""


@runtime_checkable
class Surrogate(Protocol):
    """A fitted surrogate (``isinstance`` holds after ``fit``; see the module docstring)."""

    summary_: dict[str, Any] | None
    coefficient_table_: pd.DataFrame | None
    coefficient_table_coded_: pd.DataFrame | None
    loo_method: str | None

    def fit(self, X, y) -> Surrogate: ...

    def predict(self, X) -> np.ndarray: ...

    def loo_predict(self) -> np.ndarray | None: ...

    def predict_interval(self, X, alpha: float = 0.05) -> tuple[np.ndarray, np.ndarray] | None:
        ...

    def get_params(self, deep: bool = True) -> dict[str, Any]: ...


class SurrogateBase(RegressorMixin, BaseEstimator):
    """Defaults of the contract for the built-in surrogates (a third-party surrogate may
    inherit it or implement :class:`Surrogate` itself).

    Subclasses declare ``Options`` (:mod:`sensfw.options`: a type, a range and a
    description per constructor argument; constraints between them as a model validator);
    :meth:`fit` starts with :meth:`_begin_fit`, which checks the options and the data, and
    ``predict`` with :meth:`_check_predict`.
    """

    loo_method: ClassVar[str | None] = None

    def _begin_fit(self, X, y) -> tuple[np.ndarray, np.ndarray]:
        """Check options and data; reset the declared fitted attributes."""
        problems = option_problems(type(self), self.get_params(deep=False))
        if problems:
            raise SurrogateError(f"{type(self).__name__}: {describe(problems)}",
                                 option=problems[0][0], problems=problems)
        X, y = check_data(self, X, y, reset=True)
        self.summary_ = None
        self.coefficient_table_ = self.coefficient_table_coded_ = None
        return X, y

    def _check_predict(self, X) -> np.ndarray:
        check_is_fitted(self)
        return check_data(self, X, reset=False)

    def loo_predict(self) -> np.ndarray | None:
        """Leave-one-out predictions without refits; None: not available (``loo_method``)."""
        check_is_fitted(self)
        return None

    def predict_interval(self, X, alpha: float = 0.05):
        """Prediction intervals; None: this surrogate has none."""
        check_is_fitted(self)
        return None


def check_alpha(est, alpha) -> float:
    """``alpha`` of a (1 - alpha) interval, a number in (0, 1); else a
    :class:`SurrogateError` (alpha 1.5 gave a lower bound above the upper one, alpha 0
    an infinite interval)."""
    try:
        a = float(alpha)
    except (TypeError, ValueError):
        a = float("nan")
    if not 0 < a < 1:
        raise SurrogateError(f"{type(est).__name__}: alpha must be in (0, 1) (a (1 - alpha) "
                             f"prediction interval), got {alpha!r}")
    return a


def check_data(est, X, y: Any = "no_validation", *, reset: bool):
    """scikit-learn's ``validate_data`` (finite 2-D float X, 1-D numeric y, the number and
    names of features checked against the fit); its ValueError becomes a
    :class:`SurrogateError` with the same message."""
    try:
        if isinstance(y, str) and y == "no_validation":
            return validate_data(est, X, reset=reset, dtype=np.float64)
        X, y = validate_data(est, X, y, reset=reset, dtype=np.float64, y_numeric=True)
    except ValueError as err:
        raise SurrogateError(f"{type(est).__name__}: {err}") from None
    try:  # y_numeric converts only object arrays: strings got through to the fit
        return X, np.asarray(y, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise SurrogateError(f"{type(est).__name__}: y must be numeric, got dtype "
                             f"{y.dtype} ({err})") from None


def feature_names(est) -> list[str]:
    """Names of the fitted features: the DataFrame's columns, else ``x1 .. xn``."""
    names = getattr(est, "feature_names_in_", None)
    if names is not None:
        return [str(n) for n in names]
    return [f"x{i + 1}" for i in range(est.n_features_in_)]


def scaling(est, X: np.ndarray, bounds) -> tuple[np.ndarray, np.ndarray]:
    """(mid, half-range) per column from ``bounds`` [(low, high), ...] or the data."""
    if bounds is None:
        lo, hi = X.min(axis=0), X.max(axis=0)
    else:
        b = np.asarray(bounds, dtype=float)
        if b.shape != (X.shape[1], 2):
            raise SurrogateError(f"{type(est).__name__}: bounds must be {X.shape[1]} pairs "
                                 f"(low, high), got shape {b.shape}", option="bounds")
        lo, hi = b[:, 0], b[:, 1]
        if not np.all(lo < hi):  # reversed or empty: a coding of the wrong scale, silently
            names = feature_names(est)
            bad = [f"{names[j]}: ({lo[j]:g}, {hi[j]:g})" for j in np.flatnonzero(~(lo < hi))]
            raise SurrogateError(f"{type(est).__name__}: bounds must have low < high, got "
                                 f"{', '.join(bad)}", option="bounds")
    half = (hi - lo) / 2
    half = np.where(half > 0, half, 1.0)
    return (hi + lo) / 2, half
