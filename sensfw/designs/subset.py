"""Fractions of a multi-level full factorial: generalized subset designs (pyDOE3 ``gsd``;
Surowiec et al. 2017, Anal. Chem. 89(12):6491-6497).

A reduction of 3 splits the 3^k factorial into three complementary, balanced fractions of
3^(k-1) runs (for k = 4: 27 of the 81 runs of Table 2's design); in the first of them the
last factor's level (0, 1, 2) is the sum of the others' mod 3. Every run of a
fraction is a run of the full factorial, so a fraction run first costs nothing when the full
factorial follows.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
import pandas as pd
from pydantic import Field, model_validator

from ..options import Int
from ..params import DesignSpace
from ..plugins import designs
from .base import DesignError
from .full_factorial import FullFactorial


@designs.register("subset")
class GeneralizedSubset(FullFactorial):
    """A fraction of the ``levels`` full factorial (:class:`FullFactorial`, same ``levels``
    and ``centre``): ``reduction`` splits it into that many complementary fractions of about
    ``N / reduction`` runs, ``fraction`` (0-based) picks one. Analysis as the full factorial
    (range of the level means: each level appears equally often in a fraction)."""

    name = "subset"
    class Options(FullFactorial.Options):
        reduction: Annotated[Int, Field(ge=2)] = Field(3, description="an integer >= 2")
        fraction: Annotated[Int, Field(ge=0)] = Field(
            0, description="an integer in [0, reduction)")

        @model_validator(mode="after")
        def _fraction_below_reduction(self):
            if not self.fraction < self.reduction:
                raise DesignError("fraction must be an integer in [0, reduction), got "
                                  f"{self.fraction!r}", option="fraction")
            return self

    def _matrix(self, space: DesignSpace) -> np.ndarray:
        """Level indices (0 .. levels-1), one row per run."""
        from pyDOE3 import gsd

        o = self.options
        if len(space) < 2:
            raise DesignError(f"design {self.name!r} needs at least 2 variables, got "
                              f"{len(space)}")
        try:
            parts = gsd(self._levels(space), o["reduction"], n=o["reduction"])
        except (ValueError, AssertionError) as err:  # pyDOE3 asserts its preconditions
            raise DesignError(f"design {self.name!r}: no generalized subset design with "
                              f"reduction {o['reduction']} for levels {self._levels(space)} "
                              f"({err})", option="reduction") from None
        if o["fraction"] >= len(parts):
            raise DesignError(f"design {self.name!r}: only {len(parts)} complementary "
                              "fractions", option="fraction")
        return np.asarray(parts[o["fraction"]], int)

    def n_runs(self, space: DesignSpace) -> int:
        return len(self._matrix(space))

    def generate(self, space: DesignSpace, seed=None) -> pd.DataFrame:
        grids = self.grids(space)
        idx = self._matrix(space)
        rows = np.column_stack([grids[j][idx[:, j]] for j in range(len(grids))])
        width = len(str(len(rows)))
        return pd.DataFrame(rows, columns=space.names,
                            index=[f"gsd:{i + 1:0{width}d}" for i in range(len(rows))])
