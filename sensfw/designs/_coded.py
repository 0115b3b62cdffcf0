"""Shared helpers of designs that work in coded units (-1..1)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..params import DesignSpace
from .base import ScreeningResult, relative


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
    return relative(imp, y, notes), tab, notes


def two_level_effects(space: DesignSpace, table: pd.DataFrame, y: np.ndarray,
                      notes: list[str], aliased: dict[str, str]) -> ScreeningResult:
    """Main effects of a two-level design (mean response at the high level minus mean at the
    low level, over the corner runs), importance = |effect| normalised to the largest; centre
    runs give the curvature check. ``aliased``: what each main effect is aliased with."""
    notes = list(notes)
    Z = np.sign(np.round(space.code(table).to_numpy(), 12))
    ok = np.isfinite(y)
    corner = np.all(Z != 0, axis=1)
    effects = None
    if not ok.all():
        # an unbalanced design: the mean at +1 minus the mean at -1 mixes in the other
        # variables' effects through the missing runs; twice the least-squares slopes of
        # a main-effects model of the runs left do not (on complete data the two agree)
        use = ok & corner
        A = np.column_stack([np.ones(use.sum()), Z[use]])
        if use.sum() >= A.shape[1] and np.linalg.matrix_rank(A) == A.shape[1]:
            coef, *_ = np.linalg.lstsq(A, y[use], rcond=None)
            effects = 2 * coef[1:]
            notes.append(f"{(~ok).sum()} failed runs left out; the effects are twice the "
                         "least-squares slopes of a main-effects model of the runs left "
                         "(the design is no longer orthogonal: aliases may differ)")
        else:
            notes.append(f"{(~ok).sum()} failed runs left out; the runs left cannot "
                         "separate every main effect, so the effects are differences of "
                         "means and biased by the missing runs")
    recs = []
    for i, n in enumerate(space.names):
        hi = ok & corner & (Z[:, i] > 0)
        lo = ok & corner & (Z[:, i] < 0)
        eff = (effects[i] if effects is not None else
               y[hi].mean() - y[lo].mean() if hi.any() and lo.any() else np.nan)
        recs.append({"variable": n, "effect": eff, "aliased_with": aliased.get(n, "")})
    tab = pd.DataFrame(recs).set_index("variable")
    center = ok & ~corner
    if center.any():
        curv = y[center].mean() - y[ok & corner].mean()
        notes.append(f"centre runs minus corner mean: {curv:.4g} (curvature check)")
    imp = relative(tab["effect"].abs(), y, notes)
    return ScreeningResult(importance=imp, table=tab, notes=notes)
