"""Global, surrogate-assisted calibration of a model's parameters against measurements.

One calibration minimises ``chi2 = |w(z)|^2``, the squared weighted residual vector of
:mod:`sensfw.measure.discrepancy`, over a coded box (:mod:`.coordinates`):

1. **design** — a space-filling design (scrambled Sobol') over the box, or over the part of
   it the caller names (a candidate effect's own axes around where the base parameters were
   calibrated), next to the evidence already run for the same hypothesis (the
   "parameters only" runs are every candidate's runs at its neutral values);
2. **search** — batches of ``q`` points (one per worker) chosen on a surrogate of the
   residual *vector* (:mod:`.residual_model`, :mod:`.search`): its Gauss-Newton optimum and
   its lowest confidence bounds, until the surrogate sees nothing lower;
3. **refinement** — local derivative-free least squares from the best two points of
   distinct places (:mod:`.refine`: DFO-LS by default, or the former Levenberg-Marquardt).

The result (:class:`~.fit.Fit`) holds every point run, the best, the Jacobian there (the
refinement's, else the surrogate's) for intervals and correlations, and the surrogate's
leave-one-out quality, so a report can say when the search can be trusted. Budgets count
points (the caller turns simulations into points: one simulation per point and level).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from .coordinates import Axis, Coordinates
from .fit import Fit, Trial
from .refine import dfols_solves, levenberg_marquardt
from .residual_model import ResidualModel
from .search import search, space_filling

__all__ = ["Axis", "Coordinates", "Fit", "ResidualModel", "Trial", "calibrate",
           "surrogate_jacobian"]

Log = Callable[[str], None]
#: Evaluate physical points: list of value dicts -> weighted residual vectors (None: failed)
Evaluate = Callable[[list[dict[str, float]]], list[np.ndarray | None]]


def surrogate_jacobian(model: ResidualModel, z: np.ndarray, h: float = 1e-3) -> np.ndarray:
    """Central differences of the surrogate's mean residual vector at ``z`` (coded)."""
    d = len(z)
    cols = []
    for i in range(d):
        e = np.zeros(d)
        e[i] = h
        lo, hi = np.clip(z - e, -1, 1), np.clip(z + e, -1, 1)
        r = model.residuals(np.vstack([lo, hi]))
        cols.append((r[1] - r[0]) / max(hi[i] - lo[i], 1e-12))
    return np.column_stack(cols)


def _valid(trials: Sequence[Trial]) -> list[Trial]:
    return [t for t in trials if t.w is not None and np.all(np.isfinite(t.w))]


def calibrate(evaluate: Evaluate, coords: Coordinates, budget: int, *,
              evidence: Sequence[Trial] = (), fixed: Mapping[str, float] | None = None,
              q: int = 2, design_box: tuple[np.ndarray, np.ndarray] | None = None,
              n_design: int | None = None, global_share: float = 0.6,
              refine: str = "dfols", seed: int = 0, log: Log = lambda s: None) -> Fit:
    """Calibrate ``coords`` (module docstring) with at most ``budget`` new points.

    Parameters
    ----------
    evaluate
        Physical points (every axis, plus ``fixed``) -> weighted residual vectors, one
        batch of parallel simulations per call.
    coords
        The calibrated axes.
    budget
        Points this calibration may run (design, search and refinement together).
    evidence
        Trials of the same hypothesis already run (their ``values`` hold every axis): they
        seed the surrogate and count as candidates for the best point, at no cost.
    fixed
        Values passed through unchanged with every point.
    q
        Points per batch of the search (the number of workers).
    design_box, n_design
        The coded sub-box of the space-filling design (default the whole box) and its size
        (default ``2 d + 1`` less the evidence already inside the box).
    global_share
        Share of ``budget`` for design and search; the refinement gets the rest.
    refine
        ``"dfols"`` or ``"lm"`` (:mod:`.refine`).
    """
    if refine not in ("dfols", "lm"):
        raise ValueError(f"refine must be 'dfols' or 'lm', not {refine!r}")
    from threadpoolctl import threadpool_limits

    # the surrogates' small dense algebra runs in this process while the simulations use
    # the cores: one BLAS thread (oversubscribed, it was 4x slower here)
    with threadpool_limits(limits=1):
        return _calibrate(evaluate, coords, budget, evidence, fixed, q, design_box, n_design,
                          global_share, refine, seed, log)


def _calibrate(evaluate, coords, budget, evidence, fixed, q, design_box, n_design,
               global_share, refine, seed, log) -> Fit:
    fixed = dict(fixed or {})
    d = len(coords)
    pool = _valid(evidence)
    own: list[Trial] = []

    def run_coded(zs: list[np.ndarray]) -> list[np.ndarray | None]:
        points = [{**fixed, **coords.decode(z)} for z in zs]
        ws = evaluate(points) if points else []
        new = [Trial(p, None if w is None else np.asarray(w, float))
               for p, w in zip(points, ws, strict=True)]
        own.extend(new)
        pool.extend(_valid(new))
        return [t.w for t in new]

    def best_of(trials: Sequence[Trial]) -> Trial | None:
        return min(trials, key=lambda t: t.chi2, default=None)

    info: dict = {"budget": budget, "refine": refine}
    if d == 0:
        if not pool:
            run_coded([np.zeros(0)])
        best = best_of(pool) or (own[0] if own else Trial(dict(fixed), None))
        return Fit(coords, best, None, own, info)

    # 1. space-filling design
    low, high = design_box if design_box is not None else (-np.ones(d), np.ones(d))
    low, high = np.asarray(low, float), np.asarray(high, float)
    if n_design is None:
        inside = [t for t in pool
                  if np.all((coords.code(t.values) >= low - 1e-9) &
                            (coords.code(t.values) <= high + 1e-9))]
        n_design = max(2 * d + 1 - len(inside), 0)
    n_design = min(n_design, max(budget - (d + 2), 0))
    if n_design:
        run_coded(list(space_filling(n_design, low, high, seed=seed)))
        log(f"    design: {n_design} points, best chi2 {best_of(pool).chi2:.4g}"
            if pool else f"    design: {n_design} points, every run failed")
    info["design"] = n_design

    # 2. search on the residual surrogate
    model = None
    global_budget = int(global_share * budget) - len(own)
    if global_budget >= q and len(pool) >= 3:
        Z = np.array([coords.code(t.values) for t in pool])
        W = np.array([t.w for t in pool])
        model, done = search(lambda zs: list(zip(zs, run_coded(zs), strict=True)), Z, W,
                             np.sum(W**2, axis=1), global_budget, q=q, seed=seed, log=log)
        info["search"] = done

    # 3. local least squares from the best points of two places
    best = best_of(pool)
    if best is None:
        return Fit(coords, own[0] if own else Trial(dict(fixed), None), None, own, info)
    left = budget - len(own)
    jac, refined = None, []
    z_best = coords.code(best.values)
    if refine == "lm" and left >= d + 2:
        res = levenberg_marquardt(run_coded, z_best, best.w, left, log=log)
        refined = [res]
    elif refine == "dfols" and left >= d + 3:
        starts = [z_best]
        far = [t for t in pool if np.max(np.abs(coords.code(t.values) - z_best)) >= 0.1]
        second = best_of(far)
        if second is not None and left >= 6 * (d + 1):  # else one start, more iterations
            starts.append(coords.code(second.values))
        budgets = [left // len(starts)] * len(starts)
        worst = max(t.chi2 for t in pool)
        failed = np.full(len(best.w), np.sqrt(4 * worst / len(best.w)))
        refined = dfols_solves(run_coded, starts, budgets, failed, log=log)
    info["refinement"] = [{k: v for k, v in r.items()
                           if k in ("nf", "message", "error", "budget_spent")}
                          for r in refined]
    best = best_of(pool)
    z_best = coords.code(best.values)
    for r in refined:
        if r.get("jacobian") is not None and np.max(np.abs(r["x"] - z_best)) < 1e-9:
            jac = r["jacobian"]
    # the surrogate of every run made: its leave-one-out quality, and the Jacobian where
    # the refinement left none at the best point
    valid = pool
    if len(valid) >= 4:
        Z = np.array([coords.code(t.values) for t in valid])
        model = ResidualModel(random_state=seed).fit(Z, np.array([t.w for t in valid]))
        info["surrogate"] = model.quality()
        if jac is None:
            jac = surrogate_jacobian(model, z_best)
            info["jacobian"] = "surrogate"
    info["points"] = len(own)
    return Fit(coords, best, jac, own, info)
