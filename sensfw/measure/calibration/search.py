"""The global phase of a calibration: a space-filling design over the coded box, then
batches of points chosen on the residual surrogate (:mod:`.residual_model`) until it sees
nothing left to gain.

Stick-slip makes a contact model's discrepancy rough and multimodal in its parameters, so a
local search from one start stops wherever the first valley ends. Here every batch of ``q``
points (one per worker) holds

* the surrogate's own optimum: a Gauss-Newton solve of the predicted residual vector (its
  mean scores, :func:`surrogate_minimum`) from the best few runs: exploitation with the
  vector's information;
* points of lowest lower confidence bound of chi2 (:meth:`ResidualModel.lcb`) over a
  scrambled Sobol' pool and perturbations of the best runs, each at least ``spacing``
  (coded) from every run and from each other: exploration where the surrogate is uncertain
  and could hide a lower chi2 (Srinivas et al. 2010; the greedy spacing is a simple form of
  local penalisation, Gonzalez et al. 2016).

The phase ends when its budget is spent, or when two batches in a row gained nothing and
the lowest bound of the batch is not below the best chi2 found (the surrogate, with its
uncertainty, sees nothing lower).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import qmc

from .residual_model import ResidualModel

Log = Callable[[str], None]


def space_filling(n: int, low: np.ndarray, high: np.ndarray, seed: int = 0) -> np.ndarray:
    """``n`` points of a scrambled Sobol' sequence (Owen scrambling, scipy.stats.qmc) in the
    box ``[low, high]`` (coded)."""
    low, high = np.asarray(low, float), np.asarray(high, float)
    if n <= 0:
        return np.empty((0, len(low)))
    m = int(np.ceil(np.log2(n)))
    u = qmc.Sobol(len(low), scramble=True, seed=seed).random_base2(m)[:n]
    return low + u * (high - low)


def surrogate_minimum(model: ResidualModel, starts: Sequence[np.ndarray]
                      ) -> tuple[np.ndarray, float]:
    """The coded point that minimises the surrogate's mean chi2 (bounded Gauss-Newton on
    the predicted component scores, scipy's trust-region reflective ``least_squares``)
    from each of ``starts``; returns the best and its expected chi2."""
    best, best_val = None, np.inf
    h = 1e-4

    def fun(z):
        return model.scores(z[None, :])[0][0]

    def jac(z):  # one batched prediction per component instead of d + 1
        zs = np.vstack([z, z + h * np.eye(len(z))])
        mu = model.scores(zs)[0]
        return ((mu[1:] - mu[0]) / h).T

    for z0 in starts:
        z0 = np.clip(np.asarray(z0, float), -1 + 1e-6, 1 - 1e-6)
        res = least_squares(fun, z0, jac=jac, bounds=(-1.0, 1.0), max_nfev=40)
        val = float(model.chi2(res.x[None, :])[0])
        if val < best_val:
            best, best_val = res.x, val
    return best, best_val


def lcb_points(model: ResidualModel, Z: np.ndarray, n: int, beta: float, spacing: float,
               rng: np.random.Generator, taken: Sequence[np.ndarray] = ()) -> list[np.ndarray]:
    """``n`` points of lowest lower confidence bound, each at least ``spacing`` (max-norm,
    coded) from the runs ``Z``, from ``taken`` and from each other."""
    d = Z.shape[1]
    pool = [space_filling(1024, -np.ones(d), np.ones(d), seed=int(rng.integers(2**31)))]
    order = np.argsort(model.chi2_)[:5]
    for i in order:
        pool.append(np.clip(Z[i] + 0.1 * rng.standard_normal((64, d)), -1, 1))
    pool = np.vstack(pool)
    bound = model.lcb(pool, beta)
    chosen: list[np.ndarray] = []
    near = [*Z, *taken]
    for i in np.argsort(bound):
        z = pool[i]
        if all(np.max(np.abs(z - y)) >= spacing for y in [*near, *chosen]):
            chosen.append(z)
            if len(chosen) == n:
                break
    return chosen


def search(run: Callable[[list[np.ndarray]], list], Z: np.ndarray, W: np.ndarray,
           chi2: np.ndarray, budget: int, q: int = 2, beta: float = 2.0,
           spacing: float = 0.03, patience: int = 2, seed: int = 0,
           log: Log = lambda s: None) -> tuple[ResidualModel | None, dict]:
    """Batches chosen on the surrogate (module docstring) after the runs ``Z`` (coded,
    with residual vectors ``W`` and their ``chi2``; failed runs left out). ``run`` maps
    coded points to ``(z, w or None)`` pairs and records them; at most ``budget`` points
    are run. Returns the last surrogate and what the phase did."""
    rng = np.random.default_rng(seed)
    Z, W, chi2 = np.array(Z, float), np.array(W, float), np.array(chi2, float)
    used, stall, batches = 0, 0, 0
    model = None
    while used + q <= budget and len(Z) >= 3:
        model = ResidualModel(random_state=seed, previous=model).fit(Z, W)
        best = float(np.min(chi2))
        starts = [Z[i] for i in np.argsort(chi2)[:3]]
        z_opt, predicted = surrogate_minimum(model, starts)
        proposals = []
        if np.min(np.max(np.abs(Z - z_opt), axis=1)) >= 1e-3:
            proposals.append(z_opt)
        proposals += lcb_points(model, Z, q - len(proposals), beta, spacing, rng, proposals)
        if not proposals:
            break
        bound = float(np.min(model.lcb(np.array(proposals), beta)))
        done = run(proposals)
        used += len(proposals)
        batches += 1
        ok = [(z, w) for z, w in done if w is not None]
        if ok:
            Z = np.vstack([Z, [z for z, _ in ok]])
            W = np.vstack([W, [w for _, w in ok]])
            chi2 = np.concatenate([chi2, [float(w @ w) for _, w in ok]])
        gained = float(np.min(chi2)) < best - max(1.0, 1e-3 * best)
        stall = 0 if gained else stall + 1
        log(f"    batch {batches}: surrogate optimum {predicted:.4g}, lowest bound "
            f"{bound:.4g}, best chi2 {float(np.min(chi2)):.4g}")
        if stall >= patience and bound >= float(np.min(chi2)) - 1.0:
            break
    return model, {"points": used, "batches": batches}
