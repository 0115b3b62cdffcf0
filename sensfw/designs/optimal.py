"""D- and I-optimal exact designs for Eq. 18 on the grid of a full factorial, optionally
augmenting runs already made (Atkinson, Donev & Tobias 2007, *Optimum Experimental Designs,
with SAS*, Oxford UP: Ch. 10-11 for the criteria, Ch. 12 for exchange algorithms, Sect. 19.2
for augmentation).

The model is the paper's Eq. 18 (intercept, linear terms, pairwise products, squares) in
coded variables (-1 at the low bound, 1 at the high bound). The candidates are the runs of
the ``levels`` full factorial (:class:`~sensfw.designs.full_factorial.FullFactorial`, same
``centre``), so every run of an optimal design on the 3^4 grid is a run of Table 2's design.
A D-optimal design maximises ``det(F^T F)`` (the joint confidence region of the
coefficients), an I-optimal one minimises the prediction variance averaged over the
candidate grid, ``trace((F^T F)^-1 M)`` with ``M`` the grid's moment matrix.

``augment = "oat"`` counts the one-at-a-time runs of the design's variables (the nominal run
and each variable at its min and its max, the others nominal: the runs of the paper's OAT
screen in the space of the variables it selected) as already made: they are rows of the
design (the run store returns them without simulating when the screen ran) and enter the
information matrix, and the exchange chooses the other ``runs`` rows around them.

pyDOE3's ``optimal_design`` has neither fixed runs nor a safeguard against singular designs
(its I-criterion inverts a regularised matrix, which scores rank-deficient 16-20 run designs
on the 3^4 grid well), hence this small exchange: modified Fedorov (Cook & Nachtsheim 1980,
Technometrics 22(3):315-324: each design row in turn is swapped for the candidate that
improves the criterion most), from ``starts`` random starts, the best kept. Equally optimal
designs are common on a grid (different seeds can return different designs with the same
criterion value).
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ..options import Int
from ..params import DesignSpace
from ..plugins import designs
from ._coded import linear_importance
from .base import DesignError, ScreeningResult, responses
from .full_factorial import FullFactorial
from .oat import OAT

CRITERIA = ("D", "I")
#: passes of the exchange over a start's rows at most (each pass that swaps a row improves
#: the criterion; a design that cannot estimate every term gains only round-off and could
#: cycle)
MAX_PASSES = 100


def eq18_columns(Z: np.ndarray) -> np.ndarray:
    """Eq. 18's model matrix of coded runs ``Z`` (intercept, linear, products, squares)."""
    from ..surrogates.eq18 import design_matrix

    Z = np.atleast_2d(np.asarray(Z, float))
    return design_matrix(Z, [f"x{i}" for i in range(Z.shape[1])])[0]


def criterion_value(info: np.ndarray, criterion: str,
                    moments: np.ndarray | None = None) -> np.ndarray:
    """The value to maximise for information matrices ``info`` (``F^T F``, one or a stack):
    ``log det(info)`` (D) or minus the average prediction variance
    ``trace(info^-1 moments)`` (I); ``-inf`` where ``info`` is singular (a term of Eq. 18
    is not estimable)."""
    w = np.linalg.eigvalsh(info)
    singular = w[..., 0] <= 1e-10 * w[..., -1]
    if criterion == "D":
        val = np.sum(np.log(np.abs(w)), axis=-1)
    else:
        safe = np.where(singular[..., None, None], np.eye(info.shape[-1]), info)
        val = -np.trace(np.linalg.solve(safe, np.broadcast_to(moments, info.shape)),
                        axis1=-2, axis2=-1)
    return np.where(singular, -np.inf, val)


def _swap_gains(Minv: np.ndarray, X: np.ndarray, x: np.ndarray, criterion: str,
                moments: np.ndarray) -> np.ndarray:
    """Change of the criterion when the design row ``x`` is swapped for each candidate row
    of ``X``: Fedorov's delta for D (``log`` of the determinant ratio), the Sherman-Morrison-
    Woodbury update of ``trace(info^-1 moments)`` for I (Atkinson et al. 2007, Sect. 12.4);
    ``-inf`` where the swap makes the design singular."""
    V = X @ Minv
    d = np.einsum("np,np->n", V, X)
    dx, dxj = x @ Minv @ x, V @ x
    delta = (1 + d) * (1 - dx) + dxj**2  # det(new info) / det(info)
    ok = delta > 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        if criterion == "D":
            gain = np.log(np.where(ok, delta, 1.0))
        else:
            B = Minv @ moments @ Minv
            W = X @ B
            bjj, bxj, bxx = np.einsum("np,np->n", W, X), W @ x, x @ B @ x
            gain = ((dx - 1) * bjj - 2 * dxj * bxj + (1 + d) * bxx) / -delta
    return np.where(ok, gain, -np.inf)


def exchange(candidates: np.ndarray, n: int, fixed: np.ndarray | None = None,
             criterion: str = "D", starts: int = 10, seed: int | None = 0
             ) -> tuple[np.ndarray, float]:
    """Indices of ``n`` distinct rows of the model matrix ``candidates`` that, with the rows
    ``fixed`` (already made), optimise ``criterion`` (modified Fedorov exchange, best of
    ``starts`` random starts), and the criterion's value. A random start that is singular
    is searched from with a ridge of 1e-6 of the candidates' mean information."""
    if criterion not in CRITERIA:
        raise DesignError(f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}",
                          option="criterion")
    N, p = candidates.shape
    if n > N:
        raise DesignError(f"{n} runs asked from {N} candidates", option="runs")
    base = np.zeros((p, p)) if fixed is None else np.asarray(fixed, float).T @ fixed
    moments = candidates.T @ candidates / N
    ridge = 1e-6 * np.trace(moments) / p * np.eye(p)
    rng = np.random.default_rng(seed)
    best_idx, best = None, -np.inf
    for _ in range(starts):
        idx = list(rng.choice(N, n, replace=False))
        improved, passes = True, 0
        while improved and passes < MAX_PASSES:
            improved, passes = False, passes + 1
            for i in range(n):
                info = base + candidates[idx].T @ candidates[idx] + ridge
                gains = _swap_gains(np.linalg.inv(info), candidates, candidates[idx[i]],
                                    criterion, moments)
                gains[idx] = -np.inf  # no replicates
                k = int(np.argmax(gains))
                if gains[k] > 1e-9:
                    idx[i], improved = k, True
        val = float(criterion_value(base + candidates[idx].T @ candidates[idx], criterion,
                                    moments))
        if val > best:
            best_idx, best = sorted(idx), val
    if best_idx is None or not np.isfinite(best):
        raise DesignError(f"no {n}-run design (with {0 if fixed is None else len(fixed)} runs "
                          "already made) estimates every Eq. 18 term", option="runs")
    return np.asarray(best_idx), best


@designs.register("optimal")
class OptimalDesign(FullFactorial):
    """``runs`` runs of the ``levels`` full factorial (same ``centre``) chosen D- or
    I-optimally (``criterion``) for Eq. 18 (module docstring), best of ``starts`` exchanges
    from random starts (seeded by the study's seed); ``runs`` defaults to the number of
    Eq. 18 coefficients plus 5 (5 residual degrees of freedom for its t-tests).
    ``augment = "oat"``: the OAT runs of the design's variables are rows of the design too
    (first), and the ``runs`` others are chosen around them. Analysis: ``|b_i| + |b_ii|`` of
    a quadratic fit in coded units (as Box-Behnken)."""

    name = "optimal"
    class Options(FullFactorial.Options):
        runs: Annotated[Int, Field(ge=1)] | None = Field(
            None, description="a positive integer (default: Eq. 18's coefficients + 5)")
        criterion: Literal["D", "I"] = Field("D", description="'D' or 'I'")
        augment: Literal["oat"] | None = Field(None, description="'oat' or absent")
        starts: Annotated[Int, Field(ge=1)] = Field(10, description="a positive integer")

    def _fixed(self, space: DesignSpace) -> pd.DataFrame:
        if self.options["augment"] == "oat":
            return OAT().generate(space)
        return pd.DataFrame(columns=space.names, dtype=float)

    def _runs(self, space: DesignSpace) -> int:
        """The runs to choose: ``runs``, or Eq. 18's coefficients + 5 but at most the grid's
        points; a ``runs`` that cannot estimate every Eq. 18 term with the runs already
        made, or that the grid does not hold, is a :class:`DesignError` (``option="runs"``)."""
        k = len(space)
        terms = (k + 1) * (k + 2) // 2
        n_fixed = len(self._fixed(space))
        grid = len(self._candidates(space))  # the grid's points the fixed runs leave
        runs = self.options["runs"] or min(terms + 5, grid)
        if runs + n_fixed < terms:
            raise DesignError(f"design {self.name!r}: {runs} runs"
                              + (f" and {n_fixed} already made" if n_fixed else "")
                              + f" cannot estimate Eq. 18's {terms} terms of {k} variables",
                              option="runs")
        if runs > grid:
            raise DesignError(f"design {self.name!r}: {runs} runs asked, the grid has {grid} "
                              "points" + (" besides the runs already made" if n_fixed else ""),
                              option="runs")
        return runs

    def _candidates(self, space: DesignSpace) -> pd.DataFrame:
        """The grid's points that are not among the fixed runs."""
        grid = super().generate(space)
        done = {tuple(r) for r in self._fixed(space).to_numpy(float)}
        return grid[[tuple(r) not in done for r in grid.to_numpy(float)]]

    def n_runs(self, space: DesignSpace) -> int:
        return self._runs(space) + len(self._fixed(space))

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        fixed = self._fixed(space)
        grid = self._candidates(space)
        k = self._runs(space)
        if k > len(grid):
            raise DesignError(f"design {self.name!r}: {k} runs asked, the grid has "
                              f"{len(grid)} candidates", option="runs")
        F = eq18_columns(space.code(grid).to_numpy())
        F0 = eq18_columns(space.code(fixed).to_numpy()) if len(fixed) else None
        idx, _ = exchange(F, k, F0, self.options["criterion"], self.options["starts"],
                          0 if seed is None else seed)
        chosen = grid.iloc[idx]
        width = len(str(k))
        chosen.index = [f"opt:{i + 1:0{width}d}" for i in range(k)]
        return pd.concat([fixed, chosen])[space.names]

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        imp, tab, notes = linear_importance(space, table, responses(table, y, self.name), True)
        return ScreeningResult(importance=imp, table=tab, notes=notes)
