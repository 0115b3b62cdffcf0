"""Shared helpers of designs that work in coded units (-1..1)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..params import DesignSpace


def to_table(space: DesignSpace, coded: np.ndarray, prefix: str) -> pd.DataFrame:
    """Physical run table from a coded matrix (clipped to [-1, 1]). Coded -1, 0 and 1 become
    exactly the low bound, the mid-point and the high bound as the full factorial's levels
    (``mid + c * half`` can miss a bound by a rounding error, which leaves the bounds and
    makes a run at a bound a different run, with its own key in the run store, from the full
    factorial's run there)."""
    coded = np.clip(np.asarray(coded, float), -1.0, 1.0)
    frame = space.decode(coded)
    for j, v in enumerate(space.variables):
        for c, exact in ((-1.0, v.low), (0.0, v.low + (v.high - v.low) / 2), (1.0, v.high)):
            frame.iloc[coded[:, j] == c, j] = exact
    width = len(str(len(frame)))
    frame.index = [f"{prefix}:{i + 1:0{width}d}" for i in range(len(frame))]
    return frame[space.names]


def linear_importance(space: DesignSpace, table: pd.DataFrame, y: np.ndarray,
                      quadratic: bool = False) -> tuple[pd.Series, pd.DataFrame, list[str]]:
    """Importance from a least-squares fit in coded units: ``|b_i|`` of a main-effect model,
    or ``|b_i| + |b_ii|`` when ``quadratic`` (response-surface designs)."""
    ok = np.isfinite(y)
    Z = space.code(table).to_numpy()[ok]
    cols = [np.ones(ok.sum()), *Z.T]
    if quadratic:
        cols += [z**2 for z in Z.T]
    A = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(A, y[ok], rcond=None)
    k = len(space)
    lin = coef[1:k + 1]
    quad = coef[k + 1:] if quadratic else np.zeros(k)
    tab = pd.DataFrame({"variable": space.names, "linear": lin, "quadratic": quad}) \
        .set_index("variable")
    if not quadratic:
        tab = tab.drop(columns="quadratic")
    imp = pd.Series(np.abs(lin) + np.abs(quad), index=space.names)
    notes = [] if ok.all() else [f"{(~ok).sum()} failed runs left out of the fit"]
    return imp / imp.max() if imp.max() > 0 else imp, tab, notes
