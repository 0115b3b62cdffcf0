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
validation and the option checks. Options are declared in ``_parameter_constraints``
(scikit-learn's parameter validation), so :func:`option_problems` reports a bad option of a
study before anything runs.
"""

from __future__ import annotations

import inspect
import re
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils._param_validation import InvalidParameterError, validate_parameter_constraints
from sklearn.utils.validation import check_is_fitted, validate_data

from ..errors import OptionError


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

    Subclasses set ``_parameter_constraints`` and, for constraints between options,
    override :meth:`_check_options`; :meth:`fit` starts with :meth:`_begin_fit`, which
    validates the options and the data, and ``predict`` with :meth:`_check_predict`.
    """

    _parameter_constraints: ClassVar[dict] = {}
    loo_method: ClassVar[str | None] = None

    def _check_options(self) -> None:
        """Constraints between options; raise :class:`SurrogateError` naming the option."""

    def _begin_fit(self, X, y) -> tuple[np.ndarray, np.ndarray]:
        """Validate options and data; reset the declared fitted attributes."""
        self._validate_params()
        self._check_options()
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


def check_data(est, X, y: Any = "no_validation", *, reset: bool):
    """scikit-learn's ``validate_data`` (finite 2-D float X, 1-D numeric y, the number and
    names of features checked against the fit); its ValueError becomes a
    :class:`SurrogateError` with the same message."""
    try:
        if isinstance(y, str) and y == "no_validation":
            return validate_data(est, X, reset=reset, dtype=np.float64)
        return validate_data(est, X, y, reset=reset, dtype=np.float64, y_numeric=True)
    except InvalidParameterError:
        raise
    except ValueError as err:
        raise SurrogateError(f"{type(est).__name__}: {err}") from None


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
    half = (hi - lo) / 2
    half = np.where(half > 0, half, 1.0)
    return (hi + lo) / 2, half


_PARAM = re.compile(r"The '([^']+)' parameter")


def option_problems(cls, options: dict[str, Any]) -> list[tuple[str | None, str]]:
    """Every problem of ``options`` for the surrogate class ``cls``, as (option, message);
    option None: the options together. Unknown options list the known ones; values are
    checked against ``_parameter_constraints`` one by one (all reported), then the
    constraints between options."""
    if isinstance(cls, type) and issubclass(cls, BaseEstimator):
        known = list(cls._get_param_names())
    else:
        known = [p for p in inspect.signature(cls).parameters if p not in ("self", "kwargs")]
    problems: list[tuple[str | None, str]] = [
        (k, f"unknown option; known: {', '.join(known) or '(none)'}")
        for k in options if k not in known]
    if problems:
        return problems
    try:
        est = cls(**options)
    except Exception as err:  # a third-party constructor may raise anything on a bad value
        return [(getattr(err, "option", None), str(err))]
    constraints = getattr(cls, "_parameter_constraints", {}) or {}
    params = est.get_params(deep=False) if hasattr(est, "get_params") else options
    for key, value in params.items():
        if key not in constraints or constraints[key] == "no_validation":
            continue
        try:
            validate_parameter_constraints({key: constraints[key]}, {key: value},
                                           caller_name=cls.__name__)
        except (InvalidParameterError, TypeError, ValueError) as err:
            m = _PARAM.match(str(err))
            problems.append((m.group(1) if m else key, str(err)))
    if problems:
        return problems
    check = getattr(est, "_check_options", None)
    if check is not None:
        try:
            check()
        except Exception as err:
            problems.append((getattr(err, "option", None), str(err)))
    return problems
