"""How long a resolution-R two-level design takes to find and check: the generator search
of ``fractional_factorial`` per (factors, resolution), the runs it finds, and the
resolution check it rests on, read over GF(2) (``sensfw.designs.fractional_factorial.
resolution``) against the product of every column subset up to the resolution (how it was
read until stop 51: one product column per subset, ``sum C(k, r)`` of them), on the same
matrices in the same run::

    python bench/fractional_search.py [--cases 10:5,11:5,12:5,12:6,19:4,19:5]

The subset check is skipped (``-``) where it would take more than a few seconds: it grows
as ``C(k, R)`` times the rows.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time

import numpy as np

from sensfw.designs import make_design
from sensfw.designs.fractional_factorial import resolution


def by_subsets(X: np.ndarray, max_length: int) -> int:
    """The shortest word from the products of every column subset up to ``max_length``, all
    of them listed first (the check as it was until stop 51, which the generator search
    called for each candidate)."""
    k = X.shape[1]
    words = []
    for r in range(1, min(max_length, k) + 1):
        for w in itertools.combinations(range(k), r):
            p = np.prod(X[:, w], axis=1)
            if np.all(p == p[0]):
                words.append(w)
    return min((len(w) for w in words), default=max_length + 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="8:5,10:5,11:5,12:5,12:6,19:4,19:5,19:6")
    args = ap.parse_args()
    print(f"{'k':>3} {'res':>3} {'runs':>5} {'search s':>9} {'GF(2) check s':>14} "
          f"{'subset check s':>15} {'ratio':>7}")
    for case in args.cases.split(","):
        k, res = (int(x) for x in case.split(":"))
        t0 = time.perf_counter()
        X, _, got = make_design("fractional_factorial", resolution=res).matrix(k)
        search = time.perf_counter() - t0
        t0 = time.perf_counter()
        r_gf2 = resolution(X, res + 1)
        gf2 = time.perf_counter() - t0
        work = sum(math.comb(k, r) for r in range(1, res + 2)) * len(X)
        if work < 6e7:
            t0 = time.perf_counter()
            r_sub = by_subsets(X, res + 1)
            sub = time.perf_counter() - t0
            assert r_sub == r_gf2, (k, res, r_sub, r_gf2)
            cols = f"{sub:15.3f} {sub / gf2:7.0f}"
        else:
            cols = f"{'-':>15} {'-':>7}"
        print(f"{k:3d} {res:3d} {len(X):5d} {search:9.3f} {gf2:14.4f} {cols}"
              f"   (resolution {got})")


if __name__ == "__main__":
    main()
