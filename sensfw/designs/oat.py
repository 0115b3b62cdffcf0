"""One-at-a-time screen (the paper's design space analysis, Sect. 3.1, Fig. 8)."""

from __future__ import annotations

from typing import Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ..errors import AnalysisError
from ..options import PluginOptions, Str
from ..params import DesignSpace
from ..plugins import designs
from .base import Design, ScreeningResult, check_groups, relative, responses


@designs.register("oat")
class OAT(Design):
    """Nominal run plus the min and the max of each design variable, all others nominal
    (grouped parameters move together): ``2k + 1`` runs, the nominal first.

    Analysis: a variable's changes ``s_min``, ``s_max`` are its end runs' ``y`` less the
    nominal run's (for the paper's FRF scalar, Eq. 11, the relative change against the
    nominal reference, the nominal's own ``y`` is 0 and ``s`` is ``y``; for any other scorer,
    a value, an RMS, a THD, this is what makes a variable without effect score 0). Its
    sensitivity combines ``|s_min|`` and ``|s_max|`` (option ``combine``: ``"max"`` — a
    variable matters if either end matters, the default; ``"mean"``; ``"sum"``), then is
    normalised (``normalise``: ``"max"`` — the largest becomes 1, the bars of Fig. 8,
    default; ``"sum"`` — shares of the total). Selection keeps variables above a threshold
    (paper: 10 %).

    ``groups`` (group name -> variables, every variable in one) moves each group's members
    to their min together and to their max together: ``2 G + 1`` runs, the sensitivities
    and the ranking per group (group screening, as Morris's ``groups``). A group's effect
    is not its members' largest: members that act against each other cancel (on Table 1,
    the clutch-driveshaft stiffness alone changes the FRF scalar by 0.11 at its min, the
    component's three members together by 0.025 at most; ``bench/strategies.py``).
    """

    name = "oat"

    class Options(PluginOptions):
        combine: Literal["max", "mean", "sum"] = Field(
            "max", description="'max', 'mean' or 'sum' (of a variable's min and max runs)")
        normalise: Literal["max", "sum"] = Field("max", description="'max' or 'sum'")
        groups: dict[str, list[Str]] | None = Field(
            None, description="a table of group name -> list of variables")

    def _groups(self, space: DesignSpace) -> dict[str, list]:
        """Factor name -> the space's variables it moves (one each without ``groups``)."""
        groups = self.options["groups"]
        if not groups:
            return {v.name: [v] for v in space.variables}
        by_name = {v.name: v for v in space.variables}
        check_groups(self.name, groups, space.names)
        return {g: [by_name[v] for v in vs] for g, vs in groups.items()}

    def n_runs(self, space: DesignSpace) -> int:
        return 2 * len(self._groups(space)) + 1

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        nominal = space.nominal_row()
        rows, labels = [dict(nominal)], ["nominal"]
        for name, members in self._groups(space).items():
            for level in ("min", "max"):
                row = dict(nominal)
                for v in members:
                    row[v.name] = v.low if level == "min" else v.high
                rows.append(row)
                labels.append(f"{name}:{level}")
        return pd.DataFrame(rows, index=labels, columns=space.names)

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        y = responses(table, y, self.name)
        s = pd.Series(y, index=table.index)
        base = s.get("nominal", np.nan)
        if not np.isfinite(base):
            raise AnalysisError("oat: the nominal run has no score (failed or missing); the "
                                "ends' changes are measured from it")
        s = s - base
        recs, notes = [], []
        factor = "group" if self.options["groups"] else "variable"
        for name in self._groups(space):
            lo, hi = s.get(f"{name}:min", np.nan), s.get(f"{name}:max", np.nan)
            ends = [abs(e) for e in (lo, hi) if np.isfinite(e)]
            if not ends:
                raise AnalysisError(f"oat: {factor} {name!r} has neither its min nor its max "
                                    "run; its sensitivity cannot be computed")
            if len(ends) == 1:
                notes.append(f"{name}: only its {'max' if np.isfinite(hi) else 'min'} run "
                             "finished; sensitivity from that end alone")
            comb = {"max": max(ends), "mean": float(np.mean(ends)), "sum": sum(ends)}
            recs.append({"variable": name, "s_min": lo, "s_max": hi,
                         "sensitivity": comb[self.options["combine"]]})
        tab = pd.DataFrame(recs).set_index("variable")
        tab["normalised"] = relative(tab["sensitivity"], y, notes, self.options["normalise"])
        return ScreeningResult(importance=tab["normalised"].copy(), table=tab, notes=notes)
