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


def _nullspace_gf2(D: np.ndarray) -> list[int]:
    """A basis (bit masks over the columns) of the words ``w`` with ``D w = 0`` over GF(2)."""
    rows = [int("".join("1" if v else "0" for v in r[::-1]), 2) for r in D if r.any()]
    k = D.shape[1]
    pivots: dict[int, int] = {}  # pivot column -> reduced row
    for r in rows:
        for c, pr in pivots.items():
            if r >> c & 1:
                r ^= pr
        if r:
            c = r.bit_length() - 1
            for c2 in list(pivots):
                if pivots[c2] >> c & 1:
                    pivots[c2] ^= r
            pivots[c] = r
    free = [c for c in range(k) if c not in pivots]
    basis = []
    for f in free:
        w = 1 << f
        for c, pr in pivots.items():
            if pr >> f & 1:
                w |= 1 << c
        basis.append(w)
    return basis


def _span(basis: list[int]) -> np.ndarray:
    """Every non-zero element of the GF(2) span of ``basis`` (bit masks)."""
    span = np.zeros(1, dtype=object)
    for w in basis:
        span = np.concatenate([span, span ^ w])
    return span[1:]


def defining_words(X: np.ndarray, max_length: int = 6) -> list[tuple[int, ...]]:
    """Words (column index sets, length <= ``max_length``) whose product column is constant:
    the defining relation of a regular two-level design. Computed over GF(2) (a word is
    constant on the runs where it vanishes on every difference of two runs), so its cost
    is ``2^p`` for the ``p`` generated columns, not one product per column subset."""
    X = np.asarray(X)
    bits = X < 0
    basis = _nullspace_gf2(bits[1:] ^ bits[0]) if len(X) > 1 else \
        [1 << c for c in range(X.shape[1])]
    words = [tuple(c for c in range(X.shape[1]) if int(w) >> c & 1) for w in _span(basis)]
    return sorted((w for w in words if len(w) <= max_length), key=lambda w: (len(w), w))


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
        chosen = _greedy_words(base, pool, p, res)
        if chosen is not None:
            gen = " ".join([*base, *chosen])
            if resolution(fracfact(gen), res) >= res:
                return gen
    raise DesignError(f"no 2-level design of resolution {res} found for {k} factors; "
                      "ask for a lower resolution or use definitive_screening")


def _greedy_words(base: str, pool: list[str], p: int, res: int) -> list[str] | None:
    """``p`` generator words from ``pool`` whose defining relation has no word shorter than
    ``res``: greedily, each word added where it keeps that (the relation's words checked as
    bit masks, ``2^p`` at most), starting from each word of ``pool`` in turn (the first
    word decides much: for 8 factors at resolution V, ``abcdef`` first leaves no second
    generator on 6 base factors, ``abcde`` first finds ``abcf``), or None."""
    b = len(base)
    masks = [sum(1 << base.index(ch) for ch in word) for word in pool]
    for start in range(len(pool)):
        group: list[int] = []  # the defining relation so far, every non-zero word
        chosen: list[str] = []
        for i in [*range(start, len(pool)), *range(start)]:
            mask = masks[i] | 1 << (b + len(chosen))
            new = [mask, *(mask ^ g for g in group)]
            if min(bin(w).count("1") for w in new) >= res:
                group += new
                chosen.append(pool[i])
                if len(chosen) == p:
                    return chosen
    return None


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
        resolution: Literal[3, 4, 5, 6] | None = Field(
            None, description="3, 4, 5 or 6 (default 4; with generators, the least they "
                              "must reach)")
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
            try:
                X = fracfact(gen)
            except ValueError as exc:  # pyDOE3: "Generators are not valid."
                raise DesignError(f"design 'fractional_factorial': generators {gen!r}: {exc} "
                                  "(words of letters a-z separated by spaces, e.g. 'a b c "
                                  "ab')", option="generators") from None
            if X.shape[1] != k:
                raise DesignError(f"design 'fractional_factorial': generators give "
                                  f"{X.shape[1]} columns for {k} variables",
                                  option="generators")
            got = resolution(X)
            if o["resolution"] is not None and got < o["resolution"]:
                raise DesignError(f"design 'fractional_factorial': generators {gen!r} give "
                                  f"resolution {got}, below the {o['resolution']} asked",
                                  option="generators")
            return X, gen, got
        want = o["resolution"] or 4
        try:
            X = fracfact_by_res(k, want)
            got = resolution(X, want)
        except Exception:
            X, got = None, 0
        # pyDOE3 issue #8: do not trust it; nor its size where a resolution III design of
        # the fewest runs, 2^p >= k + 1, exists (for k = 7 and 15 it gave 16 and 32 runs
        # where 8 and 16 saturate)
        fewest = 2 ** int(np.ceil(np.log2(k + 1)))
        if X is None or got < want or (want == 3 and len(X) > fewest):
            gen = search_generators(k, want)
            Y = fracfact(gen)
            if X is None or got < want or len(Y) < len(X):
                return Y, gen, resolution(Y, want + 2)
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
