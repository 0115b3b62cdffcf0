"""Morris elementary effects (SALib ``sample.morris`` / ``analyze.morris``)."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from ..errors import AnalysisError
from ..options import Bool, Float, Int, PluginOptions, Str
from ..params import DesignSpace
from ..plugins import designs
from ._coded import to_table
from .base import Design, DesignError, ScreeningResult, check_groups, relative, responses


@designs.register("morris")
class Morris(Design):
    """Trajectories of one-at-a-time steps on a grid of ``levels`` (Morris 1991; Campolongo
    et al. 2007's mu*). ``trajectories`` N; ``optimal_trajectories`` picks that many of the
    N with the largest spread (Campolongo's optimisation, ``local_optimization`` for speed);
    ``groups`` maps a group name to variables moved together (r (G+1) runs). Analysis: mu,
    mu*, sigma and the bootstrap confidence interval of mu*; importance = mu*."""

    name = "morris"

    class Options(PluginOptions):
        trajectories: Annotated[Int, Field(ge=2)] = Field(10, description="an integer >= 2")
        levels: Annotated[Int, Field(ge=2, multiple_of=2)] = Field(
            4, description="an even integer >= 2")
        optimal_trajectories: Int | None = Field(
            None, description="an integer in [2, trajectories) or none")
        local_optimization: Bool = Field(True, description="true or false")
        groups: dict[str, list[Str]] | None = Field(
            None, description="a table of group name -> list of variables")
        num_resamples: Annotated[Int, Field(ge=1)] = Field(200, description="an integer >= 1")
        conf_level: Annotated[Float, Field(gt=0, lt=1)] = Field(
            0.95, description="a number in (0, 1)")

        @model_validator(mode="after")
        def _optimal_below_trajectories(self):
            opt = self.optimal_trajectories
            if opt is not None and not 2 <= opt < self.trajectories:
                raise DesignError("optimal_trajectories must be an integer in [2, "
                                  f"trajectories) = [2, {self.trajectories}), got {opt}",
                                  option="optimal_trajectories")
            return self

    def _problem(self, space: DesignSpace) -> dict:
        prob = {"num_vars": len(space), "names": space.names, "bounds": [[-1.0, 1.0]] *
                len(space)}
        groups = self.options["groups"]
        if groups:
            member = check_groups(self.name, groups, space.names)
            prob["groups"] = [member[v] for v in space.names]
        return prob

    def _n_groups(self, space):
        g = self.options["groups"]
        if g:  # checked when counted, so a study's validation reports it
            check_groups(self.name, g, space.names)
        return len(g) if g else len(space)

    def n_runs(self, space: DesignSpace) -> int:
        r = self.options["optimal_trajectories"] or self.options["trajectories"]
        return r * (self._n_groups(space) + 1)

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        from SALib.sample import morris

        o = self.options
        X = morris.sample(self._problem(space), N=o["trajectories"], num_levels=o["levels"],
                          optimal_trajectories=o["optimal_trajectories"],
                          local_optimization=o["local_optimization"], seed=seed)
        return to_table(space, X, "morris")

    def _check_trajectories(self, space: DesignSpace, Z: np.ndarray, step: int) -> None:
        """Each trajectory's consecutive runs move one variable (one group), every one once:
        elementary effects are differences of consecutive rows, so a table in another row
        order gives wrong ones without a word."""
        groups = self.options["groups"]
        member = check_groups(self.name, groups, space.names) if groups else {}
        group = np.array([member.get(v, v) for v in space.names])
        for t, traj in enumerate(Z.reshape(-1, step, Z.shape[1])):
            moved = [set(group[np.abs(d) > 1e-9]) for d in np.diff(traj, axis=0)]
            if any(len(m) != 1 for m in moved) or len(set().union(*moved)) != step - 1:
                raise AnalysisError(
                    f"morris: trajectory {t + 1} (runs {t * step + 1}-{(t + 1) * step}) is not "
                    "one-at-a-time steps of every variable once: the table is not in the "
                    "order the design generated it")

    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        from SALib.analyze import morris

        y = responses(table, y, self.name)
        step = self._n_groups(space) + 1
        if len(y) % step:
            raise AnalysisError("morris: the table is not made of whole trajectories")
        traj = y.reshape(-1, step)
        keep = np.all(np.isfinite(traj), axis=1)
        notes = []
        if not keep.all():
            notes.append(f"{(~keep).sum()} of {len(keep)} trajectories had a failed run and "
                         "were left out")
        if keep.sum() < 2:
            raise AnalysisError("morris: fewer than 2 complete trajectories; elementary effects "
                                "need at least 2")
        self._check_trajectories(space, space.code(table).to_numpy(), step)
        rows = np.repeat(keep, step)
        Z = space.code(table).to_numpy()[rows]
        res = morris.analyze(self._problem(space), Z, y[rows], num_resamples=
                             self.options["num_resamples"], conf_level=self.options[
                                 "conf_level"], num_levels=self.options["levels"], seed=0)
        names = list(res["names"])
        tab = pd.DataFrame({"variable": names, "mu": res["mu"], "mu_star": res["mu_star"],
                            "sigma": res["sigma"], "mu_star_conf": res["mu_star_conf"]}) \
            .set_index("variable")
        imp = relative(tab["mu_star"], y[rows], notes)
        return ScreeningResult(importance=imp, table=tab, notes=notes)
