"""Gaussian-process regression with an anisotropic kernel (scikit-learn)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

import numpy as np
from pydantic import AfterValidator, Field
from scipy import stats
from sklearn.utils.validation import check_is_fitted

from ..options import Bool, Int, Pairs, PluginOptions, Str
from ..plugins import surrogates
from .base import (
    BOUNDS,
    SEED,
    RandomState,
    SurrogateBase,
    SurrogateError,
    check_alpha,
    feature_names,
    scaling,
)


def _kernel(value):
    """A scikit-learn kernel object or none (a study file's string is neither)."""
    from sklearn.gaussian_process.kernels import Kernel

    if value is not None and not isinstance(value, Kernel):
        raise ValueError(f"not a scikit-learn kernel: {value!r}")
    return value


def _parts(kernel) -> list:
    """A kernel and every kernel it is made of (sums, products, exponents)."""
    subs = [getattr(kernel, a) for a in ("k1", "k2", "kernel") if hasattr(kernel, a)]
    return [kernel, *(p for k in subs for p in _parts(k))]


@surrogates.register("gaussian_process")
class GaussianProcess(SurrogateBase):
    """``C * RBF(length scale per input) + White`` on inputs scaled to [0, 1] (``bounds`` or
    the data range), targets standardised here (``y_mean_``, ``y_scale_``: the fitted
    scikit-learn model works on ``(y - y_mean_) / y_scale_``), ``n_restarts_optimizer``
    restarts of the marginal likelihood optimisation (seeded). ``predict(X, return_std=True)``
    gives the predictive standard deviation, which includes the fitted noise. ``kernel``
    (a fitted ``model_.kernel_``) starts the marginal-likelihood optimisation where a
    previous fit ended, and ``optimize=False`` keeps its hyperparameters: a surrogate
    refitted after every few new runs (a calibration's search) needs only its Cholesky
    factor again.
    ``log_features="auto"`` works on log10 of every input whose range spans a factor 10 or
    more (contact stiffnesses, transition velocities), where a response usually varies
    evenly per decade."""

    class Options(PluginOptions):
        bounds: Pairs = Field(description=BOUNDS)
        n_restarts_optimizer: Annotated[Int, Field(ge=0)] = Field(description="an integer >= 0")
        random_state: RandomState = Field(description=SEED)
        noise: Bool = Field(description="true or false")
        log_features: Literal["auto"] | list[Str] | None = Field(
            description="'auto', a list of variable names or none")
        kernel: Annotated[Any, AfterValidator(_kernel)] = Field(
            description="a fitted scikit-learn kernel to start from, or none")
        optimize: Bool = Field(description="true or false")
    loo_method = "closed form (R&W Eq. 5.12)"

    def __init__(self, bounds=None, n_restarts_optimizer: int = 3, random_state: int = 0,
                 noise: bool = True, log_features=None, kernel=None, optimize: bool = True):
        self.kernel = kernel
        self.optimize = optimize
        self.bounds = bounds
        self.n_restarts_optimizer = n_restarts_optimizer
        self.random_state = random_state
        self.noise = noise
        self.log_features = log_features

    def _transform(self, X):
        """log10 of the log features; they must be positive (a clamp at 1e-300 turned a
        value <= 0 into -300 and the predictions into the prior mean)."""
        X = X.copy()
        if np.any(X[:, self.log_mask_] <= 0):
            raise SurrogateError("GaussianProcess: log features need positive values",
                                 option="log_features")
        X[:, self.log_mask_] = np.log10(X[:, self.log_mask_])
        return X

    def fit(self, X, y):
        import warnings

        from sklearn.exceptions import ConvergenceWarning
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        X, y = self._begin_fit(X, y)
        b = None if self.bounds is None else np.asarray(self.bounds, float)
        if b is not None and b.shape != (X.shape[1], 2):
            raise SurrogateError(f"GaussianProcess: bounds must be {X.shape[1]} pairs "
                                 f"(low, high), got shape {b.shape}", option="bounds")
        if isinstance(self.log_features, str):  # "auto"
            lo, hi = (b[:, 0], b[:, 1]) if b is not None else (X.min(0), X.max(0))
            self.log_mask_ = (lo > 0) & (hi >= 10 * lo)
        elif self.log_features is None:
            self.log_mask_ = np.zeros(X.shape[1], bool)
        else:
            names = feature_names(self)
            unknown = sorted(set(self.log_features) - set(names))
            if unknown:  # a typo turned the transform off without a word
                raise SurrogateError(f"GaussianProcess: log_features {unknown} are not "
                                     f"features ({', '.join(names)})", option="log_features")
            self.log_mask_ = np.array([n in self.log_features for n in names])
        X = self._transform(X)
        if b is not None:
            b = self._transform(b.T).T
        mid, half = scaling(self, X, b)
        self.lo_, self.span_ = mid - half, 2 * half
        # standardise y here (as normalize_y=True would) so that leave-one-out predictions
        # can be mapped back without scikit-learn's private normalisation attributes
        self.y_mean_ = float(np.mean(y))
        std = float(np.std(y))
        self.y_scale_ = std if std > 10 * np.finfo(float).eps else 1.0
        d = X.shape[1]
        if self.kernel is not None:  # a fitted kernel (``model_.kernel_``) to start from
            kernel = self.kernel
            scales = [np.size(getattr(k, "length_scale", 1.0)) for k in _parts(kernel)]
            if any(n not in (1, d) for n in scales):
                raise SurrogateError(f"GaussianProcess: the kernel has {max(scales)} length "
                                     f"scales for {d} inputs", option="kernel")
        else:
            kernel = ConstantKernel(1.0, (1e-3, 1e3)) * RBF([0.5] * d, (1e-2, 1e2))
            if self.noise:
                kernel = kernel + WhiteKernel(1e-3, (1e-10, 1e0))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.model_ = GaussianProcessRegressor(
                kernel, normalize_y=False, n_restarts_optimizer=self.n_restarts_optimizer,
                optimizer="fmin_l_bfgs_b" if self.optimize else None,
                random_state=self.random_state).fit((X - self.lo_) / self.span_,
                                                    (y - self.y_mean_) / self.y_scale_)
        return self

    def predict(self, X, return_std: bool = False):
        X = self._transform(self._check_predict(X))
        out = self.model_.predict((X - self.lo_) / self.span_, return_std=return_std)
        if return_std:
            mean, std = out
            return mean * self.y_scale_ + self.y_mean_, np.asarray(std) * self.y_scale_
        return out * self.y_scale_ + self.y_mean_

    def loo_predict(self) -> np.ndarray:
        """Leave-one-out predictions at the training points with the fitted kernel held
        fixed, in closed form (Rasmussen & Williams 2006, Eq. 5.12, with a known prior mean
        ``c``): ``mu_i = z_i - [K^-1 (z - c 1)]_i / [K^-1]_ii`` on the standardised targets
        ``z``. The model's prior mean is the mean of its training targets, so left out,
        run ``i``'s prior mean is that of the others, ``c_i = -z_i / (n - 1)`` (the ``z``
        sum to zero): with the mean of all runs, as before, a run's own value entered its
        prediction and Q² came out about 2/n too high (pure noise, 12 runs: +0.004 where
        refits give -0.156). One Cholesky solve instead of n refits; the hyperparameters are
        not re-optimised per left-out point (R&W Sect. 5.4.2)."""
        from scipy.linalg import cho_solve

        check_is_fitted(self)
        m = self.model_
        n = m.L_.shape[0]
        k_inv = cho_solve((m.L_, True), np.eye(n))
        z = np.asarray(m.y_train_, float)
        c = -z / (n - 1) if n > 1 else np.zeros(n)
        pred = z - (m.alpha_ - c * k_inv.sum(axis=1)) / np.diag(k_inv)
        return pred * self.y_scale_ + self.y_mean_

    def predict_interval(self, X, alpha: float = 0.05):
        """Gaussian (1 - alpha) predictive intervals."""
        alpha = check_alpha(self, alpha)
        mean, std = self.predict(X, return_std=True)
        z = stats.norm.ppf(1 - alpha / 2)
        return mean - z * std, mean + z * std
