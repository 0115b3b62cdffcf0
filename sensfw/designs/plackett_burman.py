"""Plackett-Burman screening designs: two levels, the fewest runs that estimate every main
effect (a multiple of four above the number of variables; pyDOE3's ``pbdesign``, and where
it has no Hadamard matrix of that order, 28, 36 and 44 runs among them, Paley's
constructions from the conference matrices of :mod:`.definitive_screening`: Paley, R. E.
A. C. (1933), On orthogonal matrices, J. Math. Phys. 12, 311-320).

Plackett, R. L., Burman, J. P. (1946), The design of optimum multifactorial experiments,
Biometrika 33(4), 305-325. Where the run count is a power of two the design is a regular
resolution-III fraction (a main effect fully aliased with some two-factor interactions);
otherwise a main effect is partially aliased with many interactions: the 12-run design's
interaction columns correlate with a main-effect column by ±1/3, the 20-run design's by ±0.2
or ±0.6, so every interaction leaks into several main effects. The analysis states the
largest such correlation.
"""

from __future__ import annotations

import itertools
from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field

from ..options import Int, PluginOptions
from ..params import DesignSpace
from ..plugins import designs
from ._coded import to_table, two_level_effects
from .base import Design, DesignError, ScreeningResult, responses
from .definitive_screening import _is_prime, conference_matrix


def hadamard(n: int) -> np.ndarray | None:
    """A Hadamard matrix of order ``n`` (``H^T H = n I``) by Paley's constructions (I: ``I +
    C`` with ``C`` the skew conference matrix of order ``n = q + 1``, q = 3 mod 4; II:
    ``[[C + I, C - I], [C - I, -C - I]]`` with ``C`` the symmetric one of order ``n / 2 = q +
    1``, q = 1 mod 4; q prime) or Sylvester's doubling of one of half the order; None where
    none of them gives one (52, 92, 100, ...)."""
    if n in (1, 2):
        return np.array([[1]]) if n == 1 else np.array([[1, 1], [1, -1]])
    if n % 4:
        return None
    q = n - 1
    if _is_prime(q) and q % 4 == 3:
        return np.eye(n, dtype=int) + conference_matrix(n)
    q = n // 2 - 1
    if _is_prime(q) and q % 4 == 1:
        C, eye = conference_matrix(q + 1), np.eye(q + 1, dtype=int)
        return np.block([[C + eye, C - eye], [C - eye, -C - eye]])
    half = hadamard(n // 2)
    return None if half is None else np.block([[half, half], [half, -half]])


def partial_aliasing(X: np.ndarray) -> float:
    """Largest |correlation| between a main-effect column and a two-factor interaction
    column of variables other than its own (0 for a resolution-IV design, 1 for a full
    alias as in a regular resolution-III fraction)."""
    n, k = X.shape
    worst = 0.0
    for j, m in itertools.combinations(range(k), 2):
        c = np.abs(X.T @ (X[:, j] * X[:, m])) / n
        c[[j, m]] = 0.0
        worst = max(worst, float(c.max()))
    return worst


def alias_table(X: np.ndarray, names: list[str]) -> dict[str, str]:
    """For each main effect, the two-factor interactions of other variables it is aliased
    with: named where fully (equal or opposite columns: a regular 8-run design), else how
    many it correlates with and by how much at most (the 12- and 20-run designs spread each
    interaction over many main effects)."""
    n, k = X.shape
    out = {}
    for i, name in enumerate(names):
        full, part = [], []
        for j, m in itertools.combinations(range(k), 2):
            if i in (j, m):
                continue
            c = float(X[:, i] @ (X[:, j] * X[:, m])) / n
            if abs(abs(c) - 1) < 1e-12:
                full.append(f"{'-' if c < 0 else ''}{names[j]}:{names[m]}")
            elif abs(c) > 1e-12:
                part.append(abs(c))
        text = ", ".join(full)
        if part:
            text += ("; " if text else "") + (f"partly with {len(part)} interaction(s), "
                                              f"|r| <= {max(part):.2f}")
        out[name] = text
    return out


@designs.register("plackett_burman")
class PlackettBurman(Design):
    """2-level Plackett-Burman design at each variable's low/high bound: ``4 ceil((k + 1) /
    4)`` runs for ``k`` variables (20 for 19), plus ``center`` centre runs. Analysis: main
    effects (mean at high minus mean at low), importance = |effect|; the notes give the
    largest partial aliasing with a two-factor interaction."""

    name = "plackett_burman"

    class Options(PluginOptions):
        center: Annotated[Int, Field(ge=0)] = Field(0, description="an integer >= 0")

    def matrix(self, k: int) -> np.ndarray:
        from pyDOE3 import pbdesign

        n = 4 * (k // 4 + 1)
        try:
            return np.asarray(pbdesign(k), float)
        except AssertionError:  # pyDOE3 has no Hadamard matrix of order n (28, 36, 44, ...)
            H = hadamard(n)
        if H is None:
            raise DesignError(f"design {self.name!r}: no Hadamard matrix of order {n} (the "
                              f"{n} runs of {k} variables) is built here; use "
                              "fractional_factorial or definitive_screening")
        H = H * H[:, :1]  # first column all +1: every other column is balanced
        return np.asarray(H[:, 1:k + 1], float)

    def n_runs(self, space: DesignSpace) -> int:
        return len(self.matrix(len(space))) + self.options["center"]

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        X = self.matrix(len(space))
        if self.options["center"]:
            X = np.vstack([X, np.zeros((self.options["center"], X.shape[1]))])
        return to_table(space, X, "pb")

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        X = self.matrix(len(space))
        note = (f"Plackett-Burman, {len(X)} runs; a main effect correlates with a two-factor "
                f"interaction by up to {partial_aliasing(X):.2f}")
        return two_level_effects(space, table, y, [note], alias_table(X, space.names))
