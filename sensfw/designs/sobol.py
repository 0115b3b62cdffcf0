"""Saltelli/Sobol' sampling and variance-based indices (SALib ``sample.sobol`` /
``analyze.sobol``): the reference for other designs' rankings when runs are cheap."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pandas as pd

from ..errors import AnalysisError
from ..plugins import designs
from ._coded import to_table
from .base import Design, DesignError, ScreeningResult, responses


@designs.register("sobol")
class Sobol(Design):
    """``N (k + 2)`` runs (``N (2k + 2)`` with ``second_order``) of a scrambled Sobol'
    sequence in Saltelli's scheme. Analysis: first-order S1 and total ST indices with
    bootstrap confidence intervals; importance = ST. Every run is needed."""

    name = "sobol"
    defaults: ClassVar[dict] = {"N": 64, "second_order": False, "num_resamples": 200,
                                "conf_level": 0.95}

    def validate(self):
        n = self.options["N"]
        if not isinstance(n, int) or n < 2 or n & (n - 1):
            raise DesignError("design 'sobol': N must be a power of 2 (Sobol' sequence)")

    def _problem(self, space):
        return {"num_vars": len(space), "names": space.names, "bounds": [[-1.0, 1.0]] *
                len(space)}

    def n_runs(self, space):
        k = len(space)
        return self.options["N"] * (2 * k + 2 if self.options["second_order"] else k + 2)

    def generate(self, space, seed=None):
        from SALib.sample import sobol

        X = sobol.sample(self._problem(space), self.options["N"],
                         calc_second_order=self.options["second_order"],
                         seed=0 if seed is None else seed)
        return to_table(space, X, "sobol")

    def analyze(self, space, table, y) -> ScreeningResult:
        from SALib.analyze import sobol

        y = responses(table, y, self.name)
        if not np.all(np.isfinite(y)):
            raise AnalysisError(f"sobol: {int((~np.isfinite(y)).sum())} failed runs; "
                                "Saltelli's estimators need every run (rerun them or use a "
                                "surrogate: sensfw.analysis.sobol.sobol_indices)")
        res = sobol.analyze(self._problem(space), y, calc_second_order=self.options[
            "second_order"], num_resamples=self.options["num_resamples"],
            conf_level=self.options["conf_level"], seed=0)
        tab = pd.DataFrame({"variable": space.names, "S1": res["S1"], "S1_conf":
                            res["S1_conf"], "ST": res["ST"], "ST_conf": res["ST_conf"]}) \
            .set_index("variable")
        imp = tab["ST"].clip(lower=0)
        return ScreeningResult(importance=imp / imp.max() if imp.max() > 0 else imp,
                               table=tab)
