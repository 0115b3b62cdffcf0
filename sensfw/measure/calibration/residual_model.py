"""A surrogate of the weighted residual vector ``w(z)`` over a calibration's coded box.

A calibration's residual vector has tens to hundreds of entries (band errors of every
channel at every level), far more than the runs that sample it, but its variation over a
box of a few parameters lies near a low-dimensional subspace. So (Higdon et al. 2008,
Sect. 2.1, for computer-model outputs of high dimension):

* the sampled vectors ``W`` (one row per run) are decomposed, uncentred, by the SVD
  ``W = U S V^T``; the components whose mean contribution to chi2 (``S_j^2 / N``) reaches
  ``min_energy`` are kept (at most ``max_components``), so ``w ~ sum_j t_j(z) v_j + e``
  with orthonormal ``v_j`` and ``chi2 = sum_j t_j^2 + |e|^2``;
* each score ``t_j(z)`` gets its own regression surrogate from the registry (default the
  anisotropic Gaussian process, :class:`sensfw.surrogates.gaussian_process.GaussianProcess`,
  whose predictive standard deviation includes the fitted noise: stick-slip makes the
  residuals irregular at fine scale);
* the residual ``|e|^2`` not captured by the kept components is carried as its mean over
  the runs.

Because the whole vector is modelled, a Gauss-Newton step on the surrogate (the mean
scores as a vector function of ``z``) keeps the information a scalar chi2 surrogate throws
away. The lower confidence bound of chi2, ``sum_j max(0, |mu_j| - beta s_j)^2``, is the
optimistic value the search explores (Srinivas et al. 2010 for GP-UCB).
"""

from __future__ import annotations

import numpy as np

from ...plugins import surrogates


class ResidualModel:
    """PCA-reduced surrogate of a residual vector over the coded box ``[-1, 1]^d``.

    Parameters
    ----------
    min_energy : float
        Keep components contributing at least this much to chi2 on average over the runs
        (chi2 units: the residuals are weighted by their standard errors).
    max_components : int
        At most this many components (and fewer than the runs).
    surrogate : str
        Registered surrogate of each component's score; it must offer
        ``predict(X, return_std=True)`` and ``loo_predict()``.
    """

    def __init__(self, min_energy: float = 0.5, max_components: int = 12,
                 surrogate: str = "gaussian_process", random_state: int = 0,
                 previous: ResidualModel | None = None):
        self.previous = previous
        self.min_energy = min_energy
        self.max_components = max_components
        self.surrogate = surrogate
        self.random_state = random_state

    def fit(self, Z: np.ndarray, W: np.ndarray) -> ResidualModel:
        Z = np.atleast_2d(np.asarray(Z, float))
        W = np.atleast_2d(np.asarray(W, float))
        n_runs, d = Z.shape
        _, S, Vt = np.linalg.svd(W, full_matrices=False)
        energy = S**2 / n_runs
        k = int(np.sum(energy >= self.min_energy))
        k = max(1, min(k, self.max_components, max(n_runs - 1, 1)))
        self.components_ = Vt[:k]
        self.scores_ = W @ self.components_.T
        rest = np.sum((W - self.scores_ @ self.components_) ** 2, axis=1)
        self.rest_ = float(np.mean(rest))
        self.Z_, self.chi2_ = Z, np.sum(W**2, axis=1)
        cls = surrogates.get(self.surrogate)
        bounds = [[-1.0, 1.0]] * d
        gp = self.surrogate == "gaussian_process"
        prev = self.previous
        # a GP's hyperparameters are optimised again once the runs grew by a quarter since
        # they were, else the previous kernel is kept (its Cholesky factor only: a search
        # refits after every batch); components are matched by their direction
        reuse = gp and prev is not None and prev.components_.shape[1] == W.shape[1] and \
            n_runs < 1.25 * prev.optimised_at_
        self.optimised_at_ = prev.optimised_at_ if reuse else n_runs
        self.models_ = []
        for j in range(k):
            opts = {"bounds": bounds, "random_state": self.random_state}
            if gp:
                opts["n_restarts_optimizer"] = 0
                if prev is not None and prev.components_.shape[1] == W.shape[1]:
                    m = int(np.argmax(np.abs(prev.components_ @ self.components_[j])))
                    opts["kernel"] = prev.models_[m].model_.kernel_
                    opts["optimize"] = not reuse
            self.models_.append(cls(**opts).fit(Z, self.scores_[:, j]))
        self.previous = None  # not kept: a chain of models would hold every run
        self.fast_ = self._fast_path() if gp else None
        return self

    @property
    def n_components(self) -> int:
        return len(self.models_)

    def scores(self, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and standard deviation of every kept component's score at ``Z``."""
        Z = np.atleast_2d(np.asarray(Z, float))
        if self.fast_ is not None:
            return self._gp_scores(Z)
        out = [m.predict(Z, return_std=True) for m in self.models_]
        return (np.column_stack([o[0] for o in out]),
                np.column_stack([np.asarray(o[1]) for o in out]))

    def _gp_scores(self, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The Gaussian processes' predictions in plain numpy (Rasmussen & Williams 2006,
        Alg. 2.1) from their fitted kernels ``c RBF(l) + white``: the surrogate is evaluated
        thousands of times per search, where scikit-learn's per-call checks cost more than
        the algebra."""
        from scipy.linalg import solve_triangular

        means, sds = [], []
        for f in self.fast_:
            X = (Z - f["lo"]) / f["span"] / f["length"]
            d2 = (np.sum(X**2, 1)[:, None] + f["xx"][None, :] - 2 * X @ f["Xt"].T)
            K = f["c"] * np.exp(-0.5 * np.maximum(d2, 0.0))
            mu = K @ f["alpha"]
            V = solve_triangular(f["L"], K.T, lower=True)
            var = np.maximum(f["c"] + f["noise"] - np.sum(V**2, axis=0), 0.0)
            means.append(mu * f["scale"] + f["mean"])
            sds.append(np.sqrt(var) * f["scale"])
        return np.column_stack(means), np.column_stack(sds)

    def _fast_path(self) -> list[dict] | None:
        """What :meth:`_gp_scores` needs of each fitted Gaussian process, or None when a
        component's surrogate is not one of this structure (then its own ``predict``)."""
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, Product, Sum, WhiteKernel

        out = []
        for m in self.models_:
            inner = getattr(m, "model_", None)
            k = getattr(inner, "kernel_", None)
            noise = 0.0
            if isinstance(k, Sum) and isinstance(k.k2, WhiteKernel):
                k, noise = k.k1, float(k.k2.noise_level)
            if not (isinstance(k, Product) and isinstance(k.k1, ConstantKernel)
                    and isinstance(k.k2, RBF)) or np.any(m.log_mask_):
                return None
            Xt = inner.X_train_ / np.asarray(k.k2.length_scale, float)
            out.append({"lo": m.lo_, "span": m.span_,
                        "length": np.asarray(k.k2.length_scale, float), "Xt": Xt,
                        "xx": np.sum(Xt**2, 1), "c": float(k.k1.constant_value),
                        "noise": noise, "alpha": inner.alpha_, "L": inner.L_,
                        "scale": m.y_scale_, "mean": m.y_mean_})
        return out

    def residuals(self, Z: np.ndarray) -> np.ndarray:
        """Predicted residual vectors (mean) at ``Z``."""
        mu, _ = self.scores(Z)
        return mu @ self.components_

    def chi2(self, Z: np.ndarray) -> np.ndarray:
        """Expected chi2 at ``Z`` (the scores' variances included)."""
        mu, sd = self.scores(Z)
        return np.sum(mu**2 + sd**2, axis=1) + self.rest_

    def lcb(self, Z: np.ndarray, beta: float = 2.0) -> np.ndarray:
        """Lower confidence bound of chi2 at ``Z``: every score moved ``beta`` standard
        deviations towards zero."""
        mu, sd = self.scores(Z)
        return np.sum(np.maximum(np.abs(mu) - beta * sd, 0.0) ** 2, axis=1) + self.rest_

    def quality(self) -> dict:
        """Leave-one-out error of the residual model: the RMS error per residual entry
        (in standard errors of the entries: 1 is the size of the measurement noise) over
        all runs and over the best quarter (where the search ends), and the relative error
        of chi2 predicted at the best quarter. Each component's surrogate predicts its
        score with that run left out (closed form for the Gaussian process); the
        components are those of all runs."""
        loo = [m.loo_predict() for m in self.models_]
        if any(x is None for x in loo):
            return {}
        T = np.column_stack(loo)
        err = np.sum((T - self.scores_) ** 2, axis=1)
        n_entries = self.components_.shape[1]
        best = np.argsort(self.chi2_)[:max(3, len(self.chi2_) // 4)]
        chi2_loo = np.sum(T**2, axis=1) + self.rest_
        rel = np.abs(chi2_loo[best] - self.chi2_[best]) / np.maximum(self.chi2_[best], 1.0)
        return {"loo_rms_per_entry": float(np.sqrt(np.mean(err) / n_entries)),
                "loo_rms_per_entry_best": float(np.sqrt(np.mean(err[best]) / n_entries)),
                "loo_chi2_relative_error_best": float(np.median(rel)),
                "components": self.n_components, "runs": len(self.chi2_)}
