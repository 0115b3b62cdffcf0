"""One-at-a-time screen (the paper's design space analysis, Sect. 3.1, Fig. 8)."""

from __future__ import annotations

from typing import Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ..errors import AnalysisError
from ..options import PluginOptions
from ..params import DesignSpace
from ..plugins import designs
from .base import Design, ScreeningResult, responses


@designs.register("oat")
class OAT(Design):
    """Nominal run plus the min and the max of each design variable, all others nominal
    (grouped parameters move together): ``2k + 1`` runs, the nominal first.

    Analysis: ``y`` is each run's relative change of the FRF scalar against the nominal
    reference (Eq. 11; the nominal row's own ``y`` is ignored). A variable's sensitivity
    combines ``|s_min|`` and ``|s_max|`` (option ``combine``: ``"max"`` — a variable matters if
    either end matters, the default; ``"mean"``; ``"sum"``), then is normalised (``normalise``:
    ``"max"`` — the largest becomes 1, the bars of Fig. 8, default; ``"sum"`` — shares of the
    total). Selection keeps variables above a threshold (paper: 10 %).
    """

    name = "oat"

    class Options(PluginOptions):
        combine: Literal["max", "mean", "sum"] = Field(
            "max", description="'max', 'mean' or 'sum' (of a variable's min and max runs)")
        normalise: Literal["max", "sum"] = Field("max", description="'max' or 'sum'")

    def n_runs(self, space: DesignSpace) -> int:
        return 2 * len(space) + 1

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        nominal = space.nominal_row()
        rows, labels = [dict(nominal)], ["nominal"]
        for v in space.variables:
            for level, value in (("min", v.low), ("max", v.high)):
                row = dict(nominal)
                row[v.name] = value
                rows.append(row)
                labels.append(f"{v.name}:{level}")
        return pd.DataFrame(rows, index=labels, columns=space.names)

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        s = pd.Series(y, index=table.index)
        recs, notes = [], []
        for v in space.variables:
            lo, hi = s.get(f"{v.name}:min", np.nan), s.get(f"{v.name}:max", np.nan)
            ends = [abs(e) for e in (lo, hi) if np.isfinite(e)]
            if not ends:
                raise AnalysisError(f"oat: variable {v.name!r} has neither its min nor its max "
                                    "run; its sensitivity cannot be computed")
            if len(ends) == 1:
                notes.append(f"{v.name}: only its {'max' if np.isfinite(hi) else 'min'} run "
                             "finished; sensitivity from that end alone")
            comb = {"max": max(ends), "mean": float(np.mean(ends)), "sum": sum(ends)}
            recs.append({"variable": v.name, "s_min": lo, "s_max": hi,
                         "sensitivity": comb[self.options["combine"]]})
        tab = pd.DataFrame(recs).set_index("variable")
        total = tab["sensitivity"].max() if self.options["normalise"] == "max" \
            else tab["sensitivity"].sum()
        tab["normalised"] = tab["sensitivity"] / total if total > 0 else 0.0
        return ScreeningResult(importance=tab["normalised"].copy(), table=tab, notes=notes)
