"""Saltelli/Sobol' sampling and variance-based indices (SALib ``sample.sobol`` /
``analyze.sobol``): the reference for other designs' rankings when runs are cheap."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import AfterValidator, Field

from ..errors import AnalysisError
from ..options import Bool, Float, Int, PluginOptions
from ..plugins import designs
from ._coded import to_table
from .base import ROUND_OFF, Design, ScreeningResult, responses


def _power_of_two(n: int) -> int:
    if n & (n - 1):
        raise ValueError("not a power of 2")
    return n


@designs.register("sobol")
class Sobol(Design):
    """``N (k + 2)`` runs (``N (2k + 2)`` with ``second_order``) of a scrambled Sobol'
    sequence in Saltelli's scheme. Analysis: first-order S1 and total ST indices with
    bootstrap confidence intervals; importance = ST. Every run is needed."""

    name = "sobol"

    class Options(PluginOptions):
        N: Annotated[Int, Field(ge=2), AfterValidator(_power_of_two)] = Field(
            64, description="a power of 2 (Sobol' sequence)")
        second_order: Bool = Field(False, description="true or false")
        num_resamples: Annotated[Int, Field(ge=1)] = Field(200, description="an integer >= 1")
        conf_level: Annotated[Float, Field(gt=0, lt=1)] = Field(
            0.95, description="a number in (0, 1)")

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

    def _check_layout(self, Z: np.ndarray) -> None:
        """Saltelli's blocks per base sample: A, AB_1..AB_k (A with column i of B), with
        ``second_order`` also BA_1..BA_k, then B. The estimators read rows by position, so
        a table in another row order gives wrong indices without a word."""
        k = Z.shape[1]
        size = 2 * k + 2 if self.options["second_order"] else k + 2
        blocks = Z.reshape(-1, size, k) if len(Z) % size == 0 else None
        ok = blocks is not None
        if ok:
            A, B = blocks[:, 0], blocks[:, -1]
            for i in range(k):
                AB = A.copy()
                AB[:, i] = B[:, i]
                ok &= np.allclose(blocks[:, 1 + i], AB, atol=1e-9)
                if self.options["second_order"]:
                    BA = B.copy()
                    BA[:, i] = A[:, i]
                    ok &= np.allclose(blocks[:, 1 + k + i], BA, atol=1e-9)
        if not ok:
            raise AnalysisError(f"sobol: the table is not Saltelli's blocks of {size} runs "
                                "(A, AB_i, ..., B) in the order the design generated them")

    def analyze(self, space, table, y) -> ScreeningResult:
        from SALib.analyze import sobol

        y = responses(table, y, self.name)
        if not np.all(np.isfinite(y)):
            raise AnalysisError(f"sobol: {int((~np.isfinite(y)).sum())} failed runs; "
                                "Saltelli's estimators need every run (rerun them or use a "
                                "surrogate: sensfw.analysis.sobol.sobol_indices)")
        self._check_layout(space.code(table).to_numpy())
        res = sobol.analyze(self._problem(space), y, calc_second_order=self.options[
            "second_order"], num_resamples=self.options["num_resamples"],
            conf_level=self.options["conf_level"], seed=0)
        tab = pd.DataFrame({"variable": space.names, "S1": res["S1"], "S1_conf":
                            res["S1_conf"], "ST": res["ST"], "ST_conf": res["ST_conf"]}) \
            .set_index("variable")
        imp = tab["ST"].clip(lower=0).fillna(0.0)
        notes = []
        spread, scale = float(np.ptp(y)), float(np.max(np.abs(y)))
        if spread <= ROUND_OFF * scale:  # indices are ratios of variances: of round-off here
            notes.append(f"no variable changes the response beyond round-off (responses "
                         f"spread over {spread:.3g}, up to {scale:.3g}): every importance is 0")
            imp = imp * 0.0
        return ScreeningResult(importance=imp / imp.max() if imp.max() > 0 else imp,
                               table=tab, notes=notes)
