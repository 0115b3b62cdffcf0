"""Full factorial design (the paper's step 2: 3 levels, 3^4 = 81 runs)."""

from __future__ import annotations

import itertools
from typing import Annotated, Literal

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from ..options import Int, PluginOptions
from ..params import DesignSpace
from ..plugins import designs
from .base import Design, DesignError, ScreeningResult, relative, responses


def level_means(table: pd.DataFrame, y: np.ndarray) -> dict[str, pd.Series] | None:
    """Least-squares level means of an additive (main effects) model ``y ~ 1 + sum_v
    level(v)``: per variable, the mean response at each of its levels with the other
    variables averaged over their levels equally. On a complete grid these are the raw
    level means; on one with runs missing they are not biased by which runs are missing,
    as raw means are. None where the runs cannot estimate every level's effect."""
    n = len(y)
    cols, where = [np.ones(n)], {}
    levels = {v: np.unique(table[v].to_numpy(float)) for v in table.columns}
    for v, lv in levels.items():
        x = table[v].to_numpy(float)
        where[v] = []
        for lvl in lv[1:]:
            where[v].append(len(cols))
            cols.append((x == lvl).astype(float))
    A = np.column_stack(cols)
    if n < A.shape[1] or np.linalg.matrix_rank(A) < A.shape[1]:
        return None
    coef, *_ = np.linalg.lstsq(A, y, rcond=None)
    effects = {v: np.concatenate([[0.0], coef[where[v]]]) for v in levels}
    out = {}
    for v, lv in levels.items():
        rest = sum(float(np.mean(e)) for u, e in effects.items() if u != v)
        out[v] = pd.Series(coef[0] + effects[v] + rest, index=lv)
    return out


@designs.register("full_factorial")
class FullFactorial(Design):
    """Every combination of ``levels`` values per variable between its low and high bound.
    ``levels`` is one integer for all variables or a list, one per variable. ``centre``:
    ``"midpoint"`` (default) spaces the levels evenly (3 levels: min, mid-point, max);
    ``"nominal"`` puts the middle level of an odd number of levels at the variable's nominal
    value and spaces the others evenly on either side (Table 2 prints the clutch stiffness's
    "medium value" 3.16e6 N/mm, which is not the mid-point 3.14e6 N/mm of its limits).

    Analysis: main effects (mean response at each level); importance is the range of the
    level means, relative to the largest. The regression (Eq. 18) is a surrogate.
    """

    name = "full_factorial"

    class Options(PluginOptions):
        levels: Annotated[Int, Field(ge=2)] | Annotated[
            list[Annotated[Int, Field(ge=2)]], Field(min_length=1)] = Field(
            3, description="an integer >= 2 or a list of them (one per variable)")
        centre: Literal["midpoint", "nominal"] = Field(
            "midpoint", description="'midpoint' or 'nominal'")

        @model_validator(mode="after")
        def _nominal_needs_a_middle_level(self):
            items = self.levels if isinstance(self.levels, list) else [self.levels]
            if self.centre == "nominal" and any(n % 2 == 0 for n in items):
                raise DesignError("centre = 'nominal' needs an odd number of levels (a "
                                  f"middle level), got {self.levels!r}", option="centre")
            return self

    def _levels(self, space: DesignSpace) -> list[int]:
        if self.options["centre"] == "nominal":
            on = [v.name for v in space.variables if not v.low < v.nominal < v.high]
            if on:
                raise DesignError(f"design {self.name!r}: centre = 'nominal' needs each "
                                  f"nominal inside its bounds, but {', '.join(on)} has it on "
                                  "a bound: its middle level would repeat an end (use "
                                  "centre = 'midpoint')", option="centre")
        lv = self.options["levels"]
        if isinstance(lv, (list, tuple)):
            if len(lv) != len(space):
                raise DesignError(f"design 'full_factorial': {len(lv)} level counts for "
                                  f"{len(space)} variables")
            return list(lv)
        return [lv] * len(space)

    def n_runs(self, space: DesignSpace) -> int:
        return int(np.prod(self._levels(space)))

    def grids(self, space: DesignSpace) -> list[np.ndarray]:
        """The level values of every variable (physical units)."""
        out = []
        for v, n in zip(space.variables, self._levels(space), strict=True):
            if self.options["centre"] == "nominal":
                half = n // 2 + 1
                out.append(np.concatenate([np.linspace(v.low, v.nominal, half),
                                           np.linspace(v.nominal, v.high, half)[1:]]))
            else:
                out.append(np.linspace(v.low, v.high, n))
        return out

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        rows = list(itertools.product(*self.grids(space)))
        width = len(str(len(rows)))
        return pd.DataFrame(rows, columns=space.names,
                            index=[f"ff:{i + 1:0{width}d}" for i in range(len(rows))])

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        ok = np.isfinite(y)
        means = level_means(table.loc[ok, space.names], y[ok])
        notes = [] if ok.all() else [
            f"{(~ok).sum()} failed runs left out of the main effects, which are least-squares "
            "means of an additive model of the runs left (the raw level means of an "
            "unbalanced grid mix the other variables' effects in)"]
        if means is None:  # the runs left cannot separate the levels: the raw means
            means = {v: pd.Series(y[ok]).groupby(table[v].to_numpy()[ok]).mean()
                     for v in space.names}
            if not ok.all():
                notes[-1] = (f"{(~ok).sum()} failed runs left out; the runs left cannot "
                             "separate every level, so the main effects are raw level means "
                             "and biased by the missing runs")
        recs = []
        for v in space.names:
            m = means[v]
            recs.append({"variable": v, "effect_range": float(m.max() - m.min()),
                         **{f"mean@{lvl:.4g}": x for lvl, x in m.items()}})
        tab = pd.DataFrame(recs).set_index("variable")
        imp = relative(tab["effect_range"], y, notes)
        return ScreeningResult(importance=imp, table=tab, notes=notes)
