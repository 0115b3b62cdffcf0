"""Full factorial design (the paper's step 2: 3 levels, 3^4 = 81 runs)."""

from __future__ import annotations

import itertools
from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field

from ..options import Int, PluginOptions
from ..params import DesignSpace
from ..plugins import designs
from .base import Design, DesignError, ScreeningResult, responses


@designs.register("full_factorial")
class FullFactorial(Design):
    """Every combination of ``levels`` evenly spaced values per variable between its low and
    high bound (3 levels: min, mid-point, max; Table 2's "medium value" is the mid-point).
    ``levels`` is one integer for all variables or a list, one per variable.

    Analysis: main effects (mean response at each level); importance is the range of the
    level means, relative to the largest. The regression (Eq. 18) is a surrogate.
    """

    name = "full_factorial"

    class Options(PluginOptions):
        levels: Annotated[Int, Field(ge=2)] | Annotated[
            list[Annotated[Int, Field(ge=2)]], Field(min_length=1)] = Field(
            3, description="an integer >= 2 or a list of them (one per variable)")

    def _levels(self, space: DesignSpace) -> list[int]:
        lv = self.options["levels"]
        if isinstance(lv, (list, tuple)):
            if len(lv) != len(space):
                raise DesignError(f"design 'full_factorial': {len(lv)} level counts for "
                                  f"{len(space)} variables")
            return list(lv)
        return [lv] * len(space)

    def n_runs(self, space: DesignSpace) -> int:
        return int(np.prod(self._levels(space)))

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        grids = [np.linspace(v.low, v.high, n) for v, n in zip(space.variables,
                                                               self._levels(space), strict=True)]
        rows = list(itertools.product(*grids))
        width = len(str(len(rows)))
        return pd.DataFrame(rows, columns=space.names,
                            index=[f"ff:{i + 1:0{width}d}" for i in range(len(rows))])

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        ok = np.isfinite(y)
        recs = []
        for v in space.variables:
            means = pd.Series(y[ok]).groupby(table[v.name].to_numpy()[ok]).mean()
            recs.append({"variable": v.name, "effect_range": float(means.max() - means.min()),
                         **{f"mean@{lvl:.4g}": m for lvl, m in means.items()}})
        tab = pd.DataFrame(recs).set_index("variable")
        top = tab["effect_range"].max()
        imp = tab["effect_range"] / top if top > 0 else tab["effect_range"] * 0
        notes = [] if ok.all() else [f"{(~ok).sum()} failed runs left out of the main effects"]
        return ScreeningResult(importance=imp, table=tab, notes=notes)
