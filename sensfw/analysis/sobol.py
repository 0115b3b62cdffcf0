"""Sobol' indices of a fitted surrogate (SALib), with bootstrap confidence intervals."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from ..errors import AnalysisError


def sobol_indices(estimator, bounds: Sequence[tuple[float, float]], names: Sequence[str],
                  n: int = 1024, seed: int = 0, num_resamples: int = 200,
                  conf_level: float = 0.95) -> pd.DataFrame:
    """First-order (S1) and total (ST) Sobol' indices of ``estimator.predict`` over the box
    ``bounds`` (Saltelli sampling with ``n`` base samples, a power of 2), with bootstrap
    half-widths ``S1_conf``/``ST_conf`` (Saltelli et al. 2010; SALib)."""
    from SALib.analyze import sobol as analyze
    from SALib.sample import sobol as sample

    b = np.asarray(bounds, dtype=float)
    if b.shape != (len(names), 2) or not np.all(b[:, 0] < b[:, 1]):
        raise AnalysisError(f"sobol_indices: bounds must be {len(names)} pairs (low, high) "
                            f"with low < high, one per name, got {b.tolist()}")
    if n < 2 or n & (n - 1):
        raise AnalysisError(f"sobol_indices: n must be a power of 2 (Sobol' sequence), "
                            f"got {n}")
    problem = {"num_vars": len(names), "names": list(names),
               "bounds": [list(map(float, b)) for b in bounds]}
    X = sample.sample(problem, n, calc_second_order=False, seed=seed)
    y = np.asarray(estimator.predict(pd.DataFrame(X, columns=list(names))), float)
    res = analyze.analyze(problem, y, calc_second_order=False, num_resamples=num_resamples,
                          conf_level=conf_level, seed=seed)
    return pd.DataFrame({"S1": res["S1"], "S1_conf": res["S1_conf"], "ST": res["ST"],
                         "ST_conf": res["ST_conf"]}, index=list(names))
