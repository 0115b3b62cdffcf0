"""Input validation shared by the surrogates (scikit-learn style)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import SensfwError


class SurrogateError(SensfwError, ValueError):
    """A surrogate got bad options or data."""


def check_xy(est, X, y=None, fit: bool = False):
    """Finite arrays X (n, d) and y (n,); a fit records feature_names_in_ / n_features_in_."""
    name = type(est).__name__
    if isinstance(X, pd.DataFrame):
        names = [str(c) for c in X.columns]
        arr = X.to_numpy(dtype=float)
    else:
        arr = np.asarray(X, dtype=float)
        if arr.ndim == 1:
            arr = arr[:, None]
        names = [f"x{i + 1}" for i in range(arr.shape[1])]
    if arr.ndim != 2:
        raise SurrogateError(f"{name}: X must be 2-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise SurrogateError(f"{name}: X contains NaN or inf")
    if fit:
        est.feature_names_in_ = np.array(names, dtype=object)
        est.n_features_in_ = arr.shape[1]
    elif arr.shape[1] != getattr(est, "n_features_in_", arr.shape[1]):
        raise SurrogateError(f"{name}: X has {arr.shape[1]} features, the fit had "
                             f"{est.n_features_in_}")
    if y is None:
        return arr
    yy = np.asarray(y, dtype=float).ravel()
    if len(yy) != len(arr):
        raise SurrogateError(f"{name}: X has {len(arr)} rows but y has {len(yy)}")
    if not np.all(np.isfinite(yy)):
        raise SurrogateError(f"{name}: y contains NaN or inf")
    return arr, yy


def scaling(est, X: np.ndarray, bounds) -> tuple[np.ndarray, np.ndarray]:
    """(mid, half-range) per column from ``bounds`` [(low, high), ...] or the data."""
    if bounds is None:
        lo, hi = X.min(axis=0), X.max(axis=0)
    else:
        b = np.asarray(bounds, dtype=float)
        if b.shape != (X.shape[1], 2):
            raise SurrogateError(f"{type(est).__name__}: bounds must be {X.shape[1]} pairs "
                                 f"(low, high), got shape {b.shape}")
        lo, hi = b[:, 0], b[:, 1]
    half = (hi - lo) / 2
    half = np.where(half > 0, half, 1.0)
    return (hi + lo) / 2, half
