"""Space-filling and response-surface designs from pyDOE3: Latin hypercube, Box-Behnken,
central composite."""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pandas as pd

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
    defaults: ClassVar[dict] = {"samples": None, "criterion": "maximin", "iterations": 20}

    def validate(self):
        o = self.options
        if o["samples"] is not None and (not isinstance(o["samples"], int) or o["samples"] < 2):
            raise DesignError("design 'lhs': samples must be an integer >= 2")
        if o["criterion"] not in (None, "maximin", "centermaximin", "correlation", "lhsmu",
                                  "center"):
            raise DesignError("design 'lhs': criterion must be maximin, centermaximin, "
                              "correlation, lhsmu or center")

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


@designs.register("box_behnken")
class BoxBehnken(Design):
    """Box-Behnken design (3 levels, no corners; needs >= 3 variables) with ``center`` centre
    runs. Analysis: ``|b_i| + |b_ii|`` of a quadratic fit in coded units."""

    name = "box_behnken"
    defaults: ClassVar[dict] = {"center": 1}

    def validate(self):
        if not isinstance(self.options["center"], int) or self.options["center"] < 1:
            raise DesignError("design 'box_behnken': center must be an integer >= 1")

    def _matrix(self, k):
        from pyDOE3 import bbdesign

        if k < 3:
            raise DesignError(f"design 'box_behnken' needs at least 3 variables, got {k}")
        return bbdesign(k, center=self.options["center"])

    def n_runs(self, space):
        return len(self._matrix(len(space)))

    def generate(self, space, seed=None):
        return to_table(space, self._matrix(len(space)), "bbd")

    def analyze(self, space, table, y) -> ScreeningResult:
        imp, tab, notes = linear_importance(space, table, responses(table, y, self.name), True)
        return ScreeningResult(importance=imp, table=tab, notes=notes)


@designs.register("central_composite")
class CentralComposite(Design):
    """Central composite design: 2-level factorial, axial and centre runs (pyDOE3
    ``ccdesign``). ``face``: "ccf" (face-centred, default: every run inside the bounds) or
    "cci" (inscribed); circumscribed designs are refused because their axial runs leave the
    bounds. Analysis as Box-Behnken."""

    name = "central_composite"
    defaults: ClassVar[dict] = {"face": "ccf", "center": [1, 1], "alpha": "orthogonal"}

    def validate(self):
        o = self.options
        if o["face"] not in ("ccf", "cci"):
            raise DesignError("design 'central_composite': face must be 'ccf' or 'cci' (a "
                              "circumscribed design leaves the bounds)")
        if o["alpha"] not in ("orthogonal", "rotatable"):
            raise DesignError("design 'central_composite': alpha must be 'orthogonal' or "
                              "'rotatable'")

    def _matrix(self, k):
        from pyDOE3 import ccdesign

        o = self.options
        X = ccdesign(k, center=tuple(o["center"]), alpha=o["alpha"], face=o["face"])
        if np.max(np.abs(X)) > 1 + 1e-9:
            raise DesignError("design 'central_composite' produced runs outside the bounds")
        return X

    def n_runs(self, space):
        return len(self._matrix(len(space)))

    def generate(self, space, seed=None):
        return to_table(space, self._matrix(len(space)), "ccd")

    def analyze(self, space, table, y) -> ScreeningResult:
        imp, tab, notes = linear_importance(space, table, responses(table, y, self.name), True)
        return ScreeningResult(importance=imp, table=tab, notes=notes)
