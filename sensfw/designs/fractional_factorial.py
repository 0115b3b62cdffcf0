"""Two-level fractional factorial designs, by generators or by a requested resolution.

pyDOE3's ``fracfact_by_res`` is known to return designs of a lower resolution than asked
(pyDOE3 issue #8), so the achieved resolution of every design is computed from its matrix
(the shortest word of the defining relation: a set of columns whose product is constant)
and, when it falls short, generators are searched here until it holds.
"""

from __future__ import annotations

import itertools
import string
from typing import Annotated, Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ..options import Int, PluginOptions, Str
from ..params import DesignSpace
from ..plugins import designs
from ._coded import to_table, two_level_effects
from .base import Design, DesignError, ScreeningResult, responses

LETTERS = string.ascii_lowercase


def defining_words(X: np.ndarray, max_length: int = 6) -> list[tuple[int, ...]]:
    """Words (column index sets, length <= ``max_length``) whose product column is constant:
    the defining relation of a regular two-level design."""
    k = X.shape[1]
    words = []
    for r in range(1, min(max_length, k) + 1):
        for w in itertools.combinations(range(k), r):
            p = np.prod(X[:, w], axis=1)
            if np.all(p == p[0]):
                words.append(w)
    return words


def resolution(X: np.ndarray, max_length: int = 8) -> int:
    """Achieved resolution (length of the shortest defining word); ``max_length + 1`` if no
    word up to that length exists (a full factorial has none)."""
    words = defining_words(X, max_length)
    return min((len(w) for w in words), default=max_length + 1)


def aliases(X: np.ndarray, names: list[str]) -> dict[str, list[str]]:
    """For each main effect, the two-factor interactions it is aliased with (equal or
    opposite columns)."""
    out = {}
    for i, n in enumerate(names):
        al = []
        for j, m in itertools.combinations(range(len(names)), 2):
            if i in (j, m):
                continue
            p = X[:, j] * X[:, m]
            if np.all(p == X[:, i]) or np.all(p == -X[:, i]):
                al.append(f"{names[j]}:{names[m]}")
        out[n] = al
    return out


def search_generators(k: int, res: int) -> str:
    """Generators of a 2^(k-p) design of resolution >= ``res`` with few runs.

    Resolution III and IV have constructions: with ``b`` base factors, any distinct words of
    two or more letters give resolution III (``k <= 2^b - 1``), and words of odd length
    (three or more letters) give resolution IV (``k <= 2^(b-1)``, the even/odd construction).
    Higher resolutions are searched over generator words, longest first. Every result is
    checked from its matrix.
    """
    from pyDOE3 import fracfact

    def words(base, lengths):
        return ["".join(c) for r in sorted(lengths, reverse=True)
                for c in itertools.combinations(base, r)]

    for b in range(1, k + 1):
        p = k - b
        base = LETTERS[:b]
        if p == 0:
            return " ".join(base)
        if res <= 3:
            cand = words(base, range(2, b + 1))
        elif res == 4:
            cand = words(base, range(3, b + 1, 2))
        else:
            cand = None
        if cand is not None:
            if len(cand) >= p:
                gen = " ".join([*base, *cand[:p]])
                if resolution(fracfact(gen), res) >= res:
                    return gen
            continue
        pool = words(base, range(res - 1, b + 1))
        if len(pool) < p:
            continue
        for combo in itertools.islice(itertools.combinations(pool, p), 5000):
            gen = " ".join([*base, *combo])
            if resolution(fracfact(gen), res) >= res:
                return gen
    raise DesignError(f"no 2-level design of resolution {res} found for {k} factors; "
                      "ask for a lower resolution or use definitive_screening")


@designs.register("fractional_factorial")
class FractionalFactorial(Design):
    """2-level fractional factorial at each variable's low/high bound. Options:
    ``generators`` (pyDOE3 ``fracfact`` string, e.g. "a b c ab ac") or ``resolution``
    (3, 4 or 5; default 4: main effects clear of two-factor interactions). The achieved
    resolution is always computed; a design below the requested resolution is replaced by a
    searched one. ``center`` adds centre runs (curvature check). Analysis: main effects
    (mean at high minus mean at low), importance = |effect|; the alias structure is listed
    in the table."""

    name = "fractional_factorial"

    class Options(PluginOptions):
        generators: Str | None = Field(
            None, description="a string of generators like 'a b c ab' or none")
        resolution: Literal[3, 4, 5, 6] = Field(4, description="3, 4, 5 or 6")
        center: Annotated[Int, Field(ge=0)] = Field(0, description="an integer >= 0")

    def matrix(self, k: int) -> tuple[np.ndarray, str, int]:
        """Coded matrix, its generators and its achieved resolution (cached per k)."""
        cache = self.__dict__.setdefault("_matrices", {})
        if k not in cache:
            cache[k] = self._matrix(k)
        X, gen, res = cache[k]
        return X.copy(), gen, res

    def _matrix(self, k: int) -> tuple[np.ndarray, str, int]:
        from pyDOE3 import fracfact, fracfact_by_res

        o = self.options
        if o["generators"]:
            gen = o["generators"]
            X = fracfact(gen)
            if X.shape[1] != k:
                raise DesignError(f"design 'fractional_factorial': generators give "
                                  f"{X.shape[1]} columns for {k} variables")
            return X, gen, resolution(X)
        want = o["resolution"]
        try:
            X = fracfact_by_res(k, want)
            got = resolution(X, want)
        except Exception:
            X, got = None, 0
        if X is None or got < want:  # pyDOE3 issue #8: do not trust it
            gen = search_generators(k, want)
            X = fracfact(gen)
            return X, gen, resolution(X, want + 2)
        return X, "(pyDOE3 fracfact_by_res)", resolution(X, want + 2)

    def n_runs(self, space: DesignSpace) -> int:
        return len(self.matrix(len(space))[0]) + self.options["center"]

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        X, _, _ = self.matrix(len(space))
        if self.options["center"]:
            X = np.vstack([X, np.zeros((self.options["center"], X.shape[1]))])
        return to_table(space, X, "frac")

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        X, gen, res = self.matrix(len(space))
        al = aliases(X, space.names)
        return two_level_effects(space, table, y, [f"generators {gen}, resolution {res}"],
                                 {n: ", ".join(al[n]) for n in space.names})
