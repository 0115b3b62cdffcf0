"""Analytic test problems with known answers, for the test suite and for plugin authors.

* :func:`ishigami` and :func:`ishigami_indices` (Ishigami & Homma 1990; Sobol' & Levitan
  1999 give the variances used below);
* :func:`quadratic` — a polynomial with chosen active main effects, squares and
  interactions;
* the linear 2-DOF oscillator is the model ``two_dof`` (:mod:`sensfw.models.analytic`), whose
  ``frf`` method is exact.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

ISHIGAMI_BOUNDS = [(-math.pi, math.pi)] * 3


def ishigami(X, a: float = 7.0, b: float = 0.1) -> np.ndarray:
    """``sin x1 + a sin^2 x2 + b x3^4 sin x1`` for rows of X (n, 3)."""
    X = np.atleast_2d(np.asarray(X, float))
    return np.sin(X[:, 0]) + a * np.sin(X[:, 1]) ** 2 + b * X[:, 2] ** 4 * np.sin(X[:, 0])


def ishigami_indices(a: float = 7.0, b: float = 0.1) -> dict[str, np.ndarray]:
    """Analytic first-order and total Sobol' indices of :func:`ishigami` on [-pi, pi]^3.

    With ``V1 = (1 + b pi^4 / 5)^2 / 2``, ``V2 = a^2 / 8``, ``V3 = 0`` and the only
    interaction ``V13 = b^2 pi^8 (1/18 - 1/50)``, the total variance is
    ``V = V1 + V2 + V13``; ``S1 = (V1, V2, 0) / V``, ``ST = (V1 + V13, V2, V13) / V``.
    (a = 7, b = 0.1: S1 = 0.3139, 0.4424, 0; ST = 0.5576, 0.4424, 0.2437.)
    """
    pi4 = math.pi**4
    v1 = 0.5 * (1 + b * pi4 / 5) ** 2
    v2 = a * a / 8
    v13 = b * b * pi4 * pi4 * (1 / 18 - 1 / 50)
    v = v1 + v2 + v13
    return {"S1": np.array([v1, v2, 0.0]) / v, "ST": np.array([v1 + v13, v2, v13]) / v}


def quadratic(linear: Mapping[int, float], squares: Mapping[int, float] | None = None,
              interactions: Mapping[tuple[int, int], float] | None = None,
              intercept: float = 0.0):
    """``f(X) = c + sum b_i x_i + sum b_ii x_i^2 + sum b_ij x_i x_j`` (column indices from
    0), returned with its coefficients; inputs in coded units."""
    squares, interactions = dict(squares or {}), dict(interactions or {})

    def f(X):
        X = np.atleast_2d(np.asarray(X, float))
        y = np.full(len(X), float(intercept))
        for i, c in linear.items():
            y += c * X[:, i]
        for i, c in squares.items():
            y += c * X[:, i] ** 2
        for (i, j), c in interactions.items():
            y += c * X[:, i] * X[:, j]
        return y

    return f, {"linear": dict(linear), "squares": squares, "interactions": interactions}
