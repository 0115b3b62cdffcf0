"""What a calibration produces: its trials (points with their weighted residual vectors),
the best of them, the Jacobian there, and from it intervals, correlations and flags.

At the optimum the Laplace approximation gives the coded covariance ``s^2 (J^T J)^-1``
(``s^2 = max(1, chi2 / (n - k))``: inflated where the model does not fit to the noise) and
from it 95 % intervals in physical units and identifiability flags: a parameter whose
interval spans more than half its range is not identified by the data; a parameter within
2 % of a bound is reported as on it.

That interval is local: it sees the basin the search ended in. Every point the calibration
ran whose chi2 lies within ``3.84 s^2`` of the best (the likelihood ratio's 95 % bound for
one parameter, chi-square with 1 degree of freedom, on the same scale ``s^2``) lies inside
the 95 % profile-likelihood region, so each of its coordinates belongs in that
parameter's interval; the interval reported is the hull of the local one and those points,
flagged where they widen it (a second basin, or a long valley the local curvature
understates).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .coordinates import Coordinates


@dataclass
class Trial:
    """A point (physical values of every calibrated axis, plus any fixed values) and its
    weighted residual vector; ``w is None``: the simulation failed."""

    values: dict[str, float]
    w: np.ndarray | None

    @property
    def chi2(self) -> float:
        return float(np.sum(self.w**2)) if self.w is not None else math.inf


@dataclass
class Fit:
    """The result of one calibration (:func:`sensfw.measure.calibration.calibrate`)."""

    coords: Coordinates
    best: Trial
    jacobian: np.ndarray | None  # d w / d z (coded) at the best point
    trials: list[Trial] = field(default_factory=list)  # every point this calibration ran
    info: dict = field(default_factory=dict)  # phases, surrogate quality, refinement

    @property
    def values(self) -> dict[str, float]:
        return dict(self.best.values)

    @property
    def chi2(self) -> float:
        return self.best.chi2

    @property
    def z(self) -> np.ndarray:
        return self.coords.code(self.best.values)

    @property
    def n_points(self) -> int:
        return len(self.trials)

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

    def correlation(self) -> np.ndarray | None:
        cov = self.covariance()
        if cov is None:
            return None
        sd = np.sqrt(np.maximum(np.diag(cov), 1e-300))
        return cov / np.outer(sd, sd)

    def trades(self, threshold: float = 0.9) -> list[dict]:
        """Pairs of calibrated quantities the data trade against each other: the
        correlation of their estimates beyond ``threshold`` in magnitude (a heavier shaft
        against a stiffer bearing: the data see only their ratio)."""
        corr = self.correlation()
        if corr is None:
            return []
        names = self.coords.names
        out = []
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if abs(corr[i, j]) >= threshold:
                    out.append({"a": names[i], "b": names[j],
                                "correlation": float(corr[i, j])})
        return sorted(out, key=lambda t: -abs(t["correlation"]))

    def uncertainty(self, records: list[dict] | None = None) -> dict | None:
        """What the calibration found, for the calibrated study (``[calibration.result]``,
        :mod:`sensfw.measure.prediction`): the axes, their coding, the calibrated point and
        its covariance (coded), and the ``records`` it saw (with the calibrated model's
        misfit on each, where given: :func:`sensfw.measure.prediction.fitted_records`); None
        without a covariance."""
        cov = self.covariance()
        if cov is None:
            return None
        return {"parameters": self.coords.names,
                "scales": [a.scale for a in self.coords.axes],
                "coded": [float(x) for x in self.z], "covariance": cov.tolist(),
                "records": [{"kind": r["kind"], "level": float(r["level"]),
                             **{k: float(r[k]) for k in ("resonance_shift_hz", "error_db")
                                if r.get(k) is not None and math.isfinite(r[k])}}
                            for r in records or []]}

    def as_good(self) -> np.ndarray:
        """Coded points of the trials whose chi2 is within ``3.84 s^2`` of the best
        (module docstring): inside the 95 % profile-likelihood region; shape (m, k)."""
        k = len(self.coords)
        w = self.best.w
        if w is None or k == 0:
            return np.zeros((0, k))
        s2 = max(1.0, self.chi2 / max(len(w) - k, 1))
        bound = self.chi2 + 3.84 * s2
        names = set(self.coords.names)
        pts = [self.coords.code(t.values) for t in [self.best, *self.trials]
               if t.w is not None and names <= set(t.values) and t.chi2 <= bound]
        return np.array(pts, float).reshape(-1, k)

    def summary(self) -> list[dict]:
        """Per axis: value, 95 % interval (the Laplace interval widened to the trials that
        fit as well, module docstring), coded standard deviation and flags."""
        cov = self.covariance()
        z = self.z
        good = self.as_good()
        rows = []
        for i, a in enumerate(self.coords.axes):
            sd = float(np.sqrt(max(cov[i, i], 0.0))) if cov is not None else math.inf
            zlo, zhi = (z[i] - 1.96 * sd, z[i] + 1.96 * sd) if math.isfinite(sd) \
                else (-1.0, 1.0)
            flags = []
            widened = bool(len(good)) and (good[:, i].min() < zlo or good[:, i].max() > zhi)
            if widened:
                zlo, zhi = min(zlo, good[:, i].min()), max(zhi, good[:, i].max())
                flags.append("interval widened to runs that fit as well (chi2 within "
                             "the 95 % likelihood-ratio bound of the best)")
            zlo, zhi = max(zlo, -1.0), min(zhi, 1.0)
            lo, hi = a.decode(zlo), a.decode(zhi)
            if z[i] <= -0.98 or z[i] >= 0.98:
                flags.append("on its lower bound" if z[i] < 0 else "on its upper bound")
            # the Laplace rule (sd 0.5: the interval spans the range), or runs as good
            # across nearly all of it
            if not sd < 0.5 or (widened and zhi - zlo >= 1.96):
                flags.append("not identified by these data")
            rows.append({"name": a.name, "unit": a.unit, "value": a.decode(z[i]),
                         "interval": [lo, hi], "coded_sd": sd, "nominal": a.nominal,
                         "bounds": [a.low, a.high], "flags": flags})
        return rows
