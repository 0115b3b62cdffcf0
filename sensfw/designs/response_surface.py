"""Space-filling and response-surface designs from pyDOE3: Latin hypercube, Box-Behnken,
central composite."""

from __future__ import annotations

from abc import abstractmethod
from typing import Annotated, ClassVar, Literal

import numpy as np
import pandas as pd
from pydantic import Field

from ..options import Int, PluginOptions
from ..params import DesignSpace
from ..plugins import designs
from ._coded import linear_importance, to_table
from .base import Design, DesignError, ScreeningResult, responses


@designs.register("lhs")
class LatinHypercube(Design):
    """Latin hypercube of ``samples`` runs (default 10 per variable), optimised by
    ``criterion`` ("maximin" default, "centermaximin", "correlation", "lhsmu"; pyDOE3), seeded.
    Analysis: importance = |coefficient| of a main-effect least-squares fit in coded units."""

    name = "lhs"

    class Options(PluginOptions):
        samples: Annotated[Int, Field(ge=2)] | None = Field(
            None, description="an integer >= 2 or none (10 per variable)")
        criterion: Literal["maximin", "centermaximin", "correlation", "lhsmu", "center"] | \
            None = Field("maximin", description="maximin, centermaximin, correlation, lhsmu, "
                                                "center or none")
        iterations: Annotated[Int, Field(ge=1)] = Field(20, description="an integer >= 1")

    def n_runs(self, space: DesignSpace) -> int:
        return self.options["samples"] or 10 * len(space)

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        from pyDOE3 import lhs

        o = self.options
        U = lhs(len(space), samples=self.n_runs(space), criterion=o["criterion"],
                iterations=o["iterations"], seed=0 if seed is None else seed)
        return to_table(space, 2 * U - 1, "lhs")

    def analyze(self, space, table, y) -> ScreeningResult:
        imp, tab, notes = linear_importance(space, table, responses(table, y, self.name))
        return ScreeningResult(importance=imp, table=tab, notes=notes)


class _QuadraticDesign(Design):
    """A response-surface design: the pyDOE3 matrix of :meth:`_matrix` in coded units, its
    runs labelled ``label``. Analysis: ``|b_i| + |b_ii|`` of a quadratic fit in coded
    units."""

    label: ClassVar[str]

    @abstractmethod
    def _matrix(self, k: int) -> np.ndarray:
        """The coded design matrix for ``k`` variables."""

    def n_runs(self, space: DesignSpace) -> int:
        return len(self._matrix(len(space)))

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        return to_table(space, self._matrix(len(space)), self.label)

    def analyze(self, space, table, y) -> ScreeningResult:
        imp, tab, notes = linear_importance(space, table, responses(table, y, self.name), True)
        return ScreeningResult(importance=imp, table=tab, notes=notes)


@designs.register("box_behnken")
class BoxBehnken(_QuadraticDesign):
    """Box-Behnken design (3 levels, no corners; needs >= 3 variables) with ``center`` centre
    runs. Analysis: ``|b_i| + |b_ii|`` of a quadratic fit in coded units."""

    name = "box_behnken"
    label = "bbd"

    class Options(PluginOptions):
        center: Annotated[Int, Field(ge=1)] = Field(1, description="an integer >= 1")

    def _matrix(self, k):
        from pyDOE3 import bbdesign

        if k < 3:
            raise DesignError(f"design 'box_behnken' needs at least 3 variables, got {k}")
        return bbdesign(k, center=self.options["center"])


@designs.register("central_composite")
class CentralComposite(_QuadraticDesign):
    """Central composite design: 2-level factorial, axial and centre runs (pyDOE3
    ``ccdesign``). ``face``: "ccf" (face-centred, default: every run inside the bounds) or
    "cci" (inscribed); circumscribed designs are refused because their axial runs leave the
    bounds. Analysis as Box-Behnken."""

    name = "central_composite"
    label = "ccd"

    class Options(PluginOptions):
        face: Literal["ccf", "cci"] = Field(
            "ccf", description="'ccf' or 'cci' (a circumscribed design leaves the bounds)")
        center: tuple[Annotated[Int, Field(ge=0)], Annotated[Int, Field(ge=0)]] = Field(
            (1, 1), description="two integers >= 0 (centre runs of the factorial and axial "
                                "parts)")
        alpha: Literal["orthogonal", "rotatable"] = Field(
            "orthogonal", description="'orthogonal' or 'rotatable'")

    def _matrix(self, k):
        from pyDOE3 import ccdesign

        if k < 2:
            raise DesignError(f"design 'central_composite' needs at least 2 variables, got {k}")
        o = self.options
        X = ccdesign(k, center=tuple(o["center"]), alpha=o["alpha"], face=o["face"])
        if np.max(np.abs(X)) > 1 + 1e-9:
            raise DesignError("design 'central_composite' produced runs outside the bounds")
        return X
