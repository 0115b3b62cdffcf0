"""Calibration of model parameters against measurements: bounded, derivative-free
Levenberg-Marquardt on the weighted residual vector of :mod:`sensfw.measure.discrepancy`.

Simulations are costly and each returns a whole residual vector (tens of band errors), so a
Gauss-Newton method that uses the vector (not just its norm) needs far fewer of them than a
scalar surrogate or Bayesian optimisation over the same space: a forward-difference
Jacobian costs ``d`` simulations, run in parallel, and a few iterations converge where the
discrepancy is smooth (Nocedal & Wright 2006, Ch. 10; Moré 1978 for the trust-region
Levenberg-Marquardt). Each step tries two damping values at once (parallel) and accepts
only a step that lowers ``chi2``, so the result is never worse than the start.

Parameters are coded to ``[-1, 1]`` (logarithmically for ranges of a factor 10 or more).
The difference step is a few per cent of the range, not an infinitesimal: where stick-slip
makes the discrepancy rough at fine scale (measured in ``tests/measure/test_diagnose.py``)
it averages the roughness out.

At the optimum, the Laplace approximation gives the coded covariance
``s^2 (J^T J)^-1`` (``s^2 = max(1, chi2 / (n - k))``: inflated where the model does not fit
to the noise) and from it 95 % intervals in physical units and identifiability flags: a
parameter whose interval spans more than half its range is not identified by the data; a
parameter within 2 % of a bound is reported as on it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..params import DesignSpace

Evaluate = Callable[[list[dict[str, float]]], list[np.ndarray | None]]


@dataclass(frozen=True)
class Axis:
    """One calibrated quantity: a design variable (its lead member's unit) or an effect
    parameter, with its bounds and its neutral value (where it has one)."""

    name: str
    low: float
    high: float
    nominal: float
    unit: str = ""
    log: bool = False

    @classmethod
    def of(cls, name, low, high, nominal, unit="") -> Axis:
        return cls(name, float(low), float(high), float(nominal), unit,
                   bool(low > 0 and high >= 10 * low))

    def _t(self, x):
        return np.log10(x) if self.log else np.asarray(x, float)

    def code(self, x: float) -> float:
        a, b = self._t(self.low), self._t(self.high)
        return float(2 * (self._t(x) - a) / (b - a) - 1) if b > a else 0.0

    def decode(self, z: float) -> float:
        a, b = self._t(self.low), self._t(self.high)
        t = a + (float(np.clip(z, -1, 1)) + 1) / 2 * (b - a)
        return float(10.0**t) if self.log else float(t)


@dataclass
class Coordinates:
    """The coded space of a calibration."""

    axes: list[Axis]

    @classmethod
    def of(cls, space: DesignSpace | None = None, params: Sequence = ()) -> Coordinates:
        """Axes of a design space's variables and of extra parameters (effect
        :class:`~sensfw.params.Parameter` objects)."""
        axes = [] if space is None else [Axis.of(v.name, v.low, v.high, v.nominal, v.unit)
                                         for v in space.variables]
        axes += [Axis.of(p.name, p.min, p.max, p.nominal, p.unit) for p in params]
        return cls(axes)

    @property
    def names(self) -> list[str]:
        return [a.name for a in self.axes]

    def __len__(self) -> int:
        return len(self.axes)

    def code(self, values: Mapping[str, float]) -> np.ndarray:
        return np.array([a.code(values[a.name]) for a in self.axes])

    def decode(self, z: Sequence[float]) -> dict[str, float]:
        return {a.name: a.decode(v) for a, v in zip(self.axes, z, strict=True)}


@dataclass
class Evaluation:
    values: dict[str, float]
    w: np.ndarray | None  # weighted residuals; None: the simulation failed

    @property
    def chi2(self) -> float:
        return float(np.sum(self.w**2)) if self.w is not None else math.inf


@dataclass
class Fit:
    """The result of one calibration."""

    coords: Coordinates
    best: Evaluation
    jacobian: np.ndarray | None  # coded, at (or next to) the best point
    evaluations: list[Evaluation] = field(default_factory=list)
    iterations: int = 0

    @property
    def values(self) -> dict[str, float]:
        return dict(self.best.values)

    @property
    def chi2(self) -> float:
        return self.best.chi2

    @property
    def z(self) -> np.ndarray:
        return self.coords.code(self.best.values)

    def covariance(self) -> np.ndarray | None:
        """Laplace approximation of the coded covariance (module docstring)."""
        J, w = self.jacobian, self.best.w
        if J is None or w is None or len(self.coords) == 0:
            return None
        n, k = J.shape
        s2 = max(1.0, self.chi2 / max(n - k, 1))
        A = J.T @ J
        # a direction the data do not see (a zero column) gets a huge variance, not the
        # zero a pseudo-inverse would give it
        eps = 1e-9 * np.trace(A) / k + 1e-12
        return s2 * np.linalg.inv(A + eps * np.eye(k))

    def summary(self) -> list[dict]:
        """Per axis: value, 95 % interval, coded standard deviation and flags."""
        cov = self.covariance()
        z = self.z
        rows = []
        for i, a in enumerate(self.coords.axes):
            sd = float(np.sqrt(max(cov[i, i], 0.0))) if cov is not None else math.inf
            lo, hi = (a.decode(z[i] - 1.96 * sd), a.decode(z[i] + 1.96 * sd)) \
                if math.isfinite(sd) else (a.low, a.high)
            flags = []
            if z[i] <= -0.98 or z[i] >= 0.98:
                flags.append("on its lower bound" if z[i] < 0 else "on its upper bound")
            if not sd < 0.5:
                flags.append("not identified by these data")
            rows.append({"name": a.name, "unit": a.unit, "value": a.decode(z[i]),
                         "interval": [lo, hi], "coded_sd": sd, "nominal": a.nominal,
                         "bounds": [a.low, a.high], "flags": flags})
        return rows


def _jacobian_points(z: np.ndarray, h: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    steps = np.where(z + h <= 1.0, h, -h)
    return [z + steps[i] * np.eye(len(z))[i] for i in range(len(z))], steps


def calibrate(evaluate: Evaluate, coords: Coordinates, start: Evaluation,
              fixed: Mapping[str, float] | None = None, max_iter: int = 12,
              step: float = 0.05, budget: int | None = None, tol: float = 3e-3,
              log: Callable[[str], None] = lambda s: None) -> Fit:
    """Minimise ``chi2`` over ``coords`` from ``start`` (an evaluated point: its ``values``
    hold every axis, plus any ``fixed`` values passed through unchanged). ``evaluate`` maps
    a list of value dicts to weighted residual vectors (one batch of parallel runs).
    ``budget`` caps the number of points evaluated (one simulation per point and level: a
    calibration on three levels runs three times as many); ``max_iter`` the number of
    Jacobians.

    A Jacobian (``d`` runs) is computed at each new best point; then pairs of damped
    Gauss-Newton steps (two damping values, run together) are tried until one lowers
    ``chi2`` — a failed pair costs two runs, not a new Jacobian — with the damping raised a
    hundredfold after each failed pair (Levenberg 1944, Marquardt 1963). Four failed pairs
    in a row halve the difference step (a coarse difference misleads where chi2 curves
    within it) and start again; at a step below 1.5 % of the range they, or two iterations
    in a row gaining less than ``tol`` (relative) or less than 0.5 in ``chi2`` (together
    under one unit, the change that marks one standard deviation of a parameter's profile
    likelihood), end the search."""
    fixed = dict(fixed or {})
    fit = Fit(coords=coords, best=start, jacobian=None, evaluations=[start])
    if len(coords) == 0 or start.w is None:
        return fit
    used = 0
    d = len(coords)

    def run(zs: list[np.ndarray]) -> list[Evaluation]:
        nonlocal used
        points = [{**fixed, **coords.decode(z)} for z in zs]
        ws = evaluate(points)
        used += len(points)
        out = [Evaluation(p, w) for p, w in zip(points, ws, strict=True)]
        fit.evaluations.extend(out)
        return out

    def affordable(n: int) -> bool:
        return budget is None or used + n <= budget

    lam, slow = 1e-3, 0
    steps = np.full(d, float(step))  # difference step per axis (coded)
    for it in range(max_iter):
        if not affordable(d + 2):
            log(f"  budget of {budget} points reached (each point simulates every level)")
            break
        z, w = coords.code(fit.best.values), fit.best.w
        pts, h = _jacobian_points(z, steps)
        cols = run(pts)
        # an axis whose difference changes the residuals by more than their size has
        # stepped across a narrow valley (a sharp resonance moved by a stiff parameter):
        # difference it again at a quarter of the step, up to twice
        for _ in range(2):
            wide = [i for i, c in enumerate(cols) if c.w is not None and steps[i] > 2e-3
                    and np.linalg.norm(c.w - w) > np.linalg.norm(w)]
            if not wide or not affordable(len(wide) + 2):
                break
            steps[wide] /= 4
            again = run([z + np.where(z[i] + steps[i] <= 1, steps[i], -steps[i]) *
                         np.eye(d)[i] for i in wide])
            h = h.copy()
            for i, c in zip(wide, again, strict=True):
                cols[i] = c
                h[i] = steps[i] if z[i] + steps[i] <= 1 else -steps[i]
        J = np.column_stack([(c.w - w) / hi if c.w is not None else np.zeros_like(w)
                             for c, hi in zip(cols, h, strict=True)])
        fit.jacobian = J
        fit.iterations = it + 1
        A, g = J.T @ J, J.T @ w
        scale = np.maximum(np.diag(A), 1e-12 * max(np.max(np.diag(A)), 1e-300))
        old = fit.best.chi2
        cand = min(cols, key=lambda e: e.chi2)  # a difference point may already be better
        for _ in range(4):
            if not affordable(2):
                break
            trials = []
            for mu in (lam, lam * 10):
                s = -np.linalg.solve(A + mu * np.diag(scale) + 1e-12 * np.eye(d), g)
                norm = np.max(np.abs(s))
                if norm > 1.0:  # at most half the coded range per step
                    s = s / norm
                trials.append(np.clip(z + s, -1, 1))
            tried = run(trials)
            best_trial = min(tried, key=lambda e: e.chi2)
            if best_trial.chi2 < old:
                lam = lam / 3 if best_trial is tried[0] else lam * 3
                cand = min(best_trial, cand, key=lambda e: e.chi2)
                break
            lam *= 100
        if cand.chi2 < old:
            fit.best = cand
            gain = (old - cand.chi2) / max(old, 1e-300)
            log(f"  iteration {it + 1}: chi2 {old:.4g} -> {cand.chi2:.4g}")
            slow = slow + 1 if gain < tol or old - cand.chi2 < 0.5 else 0
            if slow >= 2:
                break
        elif np.max(steps) > 0.015:  # the difference may be too coarse where chi2 curves
            steps = np.maximum(steps / 2, np.minimum(steps, 2e-3))
            lam = 1e-3
            log(f"  iteration {it + 1}: no lower chi2 near {old:.4g}; difference steps "
                f"{np.round(steps, 4).tolist()}")
        else:
            log(f"  iteration {it + 1}: no lower chi2 near {old:.4g}: converged")
            break
    return fit


def roughness(evaluate: Evaluate, coords: Coordinates, fit: Fit, sigma: np.ndarray,
              delta: float = 0.01) -> np.ndarray:
    """The model's own scatter per residual entry (dB) around ``fit``'s optimum.

    Stick-slip makes a contact model's response irregular in its parameters: a change of a
    fraction of a per cent can move band levels by decibels (measured on the quick study at
    the friction velocity 0.65 mm/s), far below any calibration's resolution. The second
    differences ``(r(z + delta e_i) + r(z - delta e_i)) / 2 - r(z)`` along each coded axis
    cancel the smooth trend; for an irregular part of variance ``rho^2`` they have variance
    ``1.5 rho^2``. ``sigma`` (the entries' standard errors) turns the weighted residuals
    back into dB. Costs ``2 d`` runs."""
    d = len(coords)
    if d == 0 or fit.best.w is None:
        return np.zeros(len(sigma))
    z = coords.code(fit.best.values)
    zs = [np.clip(z + s * delta * np.eye(d)[i], -1, 1) for i in range(d) for s in (-1, 1)]
    ws = evaluate([{**fit.best.values, **coords.decode(zz)} for zz in zs])
    r0 = fit.best.w * sigma
    second = []
    for i in range(d):
        a, b = ws[2 * i], ws[2 * i + 1]
        if a is not None and b is not None:
            second.append((a * sigma + b * sigma) / 2 - r0)
    if not second:
        return np.zeros(len(sigma))
    return np.sqrt(np.mean(np.square(second), axis=0) / 1.5)
