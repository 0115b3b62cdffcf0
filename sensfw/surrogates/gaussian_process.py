"""Gaussian-process regression with an anisotropic kernel (scikit-learn)."""

from __future__ import annotations

import numpy as np
from scipy import stats
from sklearn.base import BaseEstimator, RegressorMixin

from ..plugins import surrogates
from ._validation import check_xy, scaling


@surrogates.register("gaussian_process")
class GaussianProcess(RegressorMixin, BaseEstimator):
    """``C * RBF(length scale per input) + White`` on inputs scaled to [0, 1] (``bounds`` or
    the data range), normalised targets, ``n_restarts_optimizer`` restarts of the marginal
    likelihood optimisation (seeded). ``predict(X, return_std=True)`` gives the predictive
    standard deviation, which includes the fitted noise."""

    def __init__(self, bounds=None, n_restarts_optimizer: int = 3, random_state: int = 0,
                 noise: bool = True):
        self.bounds = bounds
        self.n_restarts_optimizer = n_restarts_optimizer
        self.random_state = random_state
        self.noise = noise

    def fit(self, X, y):
        import warnings

        from sklearn.exceptions import ConvergenceWarning
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        X, y = check_xy(self, X, y, fit=True)
        mid, half = scaling(self, X, self.bounds)
        self.lo_, self.span_ = mid - half, 2 * half
        d = X.shape[1]
        kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF([0.5] * d, (1e-2, 1e2))
        if self.noise:
            kernel = kernel + WhiteKernel(1e-3, (1e-10, 1e0))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.model_ = GaussianProcessRegressor(
                kernel, normalize_y=True, n_restarts_optimizer=self.n_restarts_optimizer,
                random_state=self.random_state).fit((X - self.lo_) / self.span_, y)
        return self

    def predict(self, X, return_std: bool = False):
        X = check_xy(self, X)
        return self.model_.predict((X - self.lo_) / self.span_, return_std=return_std)

    def predict_interval(self, X, alpha: float = 0.05):
        mean, std = self.predict(X, return_std=True)
        z = stats.norm.ppf(1 - alpha / 2)
        return mean - z * std, mean + z * np.asarray(std)
