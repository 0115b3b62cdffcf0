"""Polynomial response surface of any degree, optionally sparse (LARS)."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from ..analysis.validation import total_ss
from ..options import Int, Pairs, PluginOptions
from ..plugins import surrogates
from .base import BOUNDS, SurrogateBase, SurrogateError, scaling


@surrogates.register("polynomial")
class Polynomial(SurrogateBase):
    """All monomials up to ``degree`` of the inputs coded to [-1, 1] (``bounds`` or the data
    range), fitted by least squares, or sparsely with ``selection="lars"`` (LassoLarsCV:
    least-angle regression with the penalty chosen by cross-validation, for few runs and
    many terms)."""

    class Options(PluginOptions):
        degree: Annotated[Int, Field(ge=1)] = Field(description="an integer >= 1")
        selection: Literal["lars"] | None = Field(description="'lars' or none")
        bounds: Pairs = Field(description=BOUNDS)
        cv: Annotated[Int, Field(ge=2)] = Field(description="an integer >= 2")

    def __init__(self, degree: int = 2, selection: str | None = None, bounds=None,
                 cv: int = 5):
        self.degree = degree
        self.selection = selection
        self.bounds = bounds
        self.cv = cv

    def fit(self, X, y):
        from sklearn.linear_model import LassoLars, LassoLarsCV, LinearRegression
        from sklearn.preprocessing import PolynomialFeatures

        X, y = self._begin_fit(X, y)
        self.mid_, self.half_ = scaling(self, X, self.bounds)
        self.features_ = PolynomialFeatures(self.degree, include_bias=False)
        A = self.features_.fit_transform((X - self.mid_) / self.half_)
        if self.selection == "lars":
            if len(y) < 3:  # a fold trains on one run: LARS has no path
                raise SurrogateError(f"Polynomial: selection='lars' cross-validates its "
                                     f"penalty and needs at least 3 runs, got {len(y)}")
            if total_ss(y) == 0:  # no path to cross-validate: every coefficient is 0
                self.model_ = LassoLars(alpha=1.0).fit(A, y)
            else:
                self.model_ = LassoLarsCV(cv=min(self.cv, len(y))).fit(A, y)
        else:
            if len(y) <= A.shape[1]:
                raise SurrogateError(f"Polynomial: {len(y)} runs (n_samples = {len(y)}) for "
                                     f"{A.shape[1] + 1} terms; "
                                     "use selection='lars' or a lower degree")
            self.model_ = LinearRegression().fit(A, y)
        self.n_terms_ = int(np.count_nonzero(self.model_.coef_)) + 1
        return self

    def predict(self, X):
        X = self._check_predict(X)
        return self.model_.predict(self.features_.transform((X - self.mid_) / self.half_))
