"""Random forest regression (scikit-learn)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field
from sklearn.utils.validation import check_is_fitted

from ..options import Int, PluginOptions
from ..plugins import surrogates
from .base import SEED, RandomState, SurrogateBase


@surrogates.register("random_forest")
class RandomForest(SurrogateBase):
    """A seeded random forest; robust to steps and interactions, poor at extrapolation and
    without calibrated prediction intervals. Its leave-one-out check uses the out-of-bag
    predictions (each run predicted by the trees whose bootstrap sample missed it; Breiman
    2001), the bagging analogue of leave-one-out, instead of n refits."""

    class Options(PluginOptions):
        n_estimators: Annotated[Int, Field(ge=1)] = Field(description="an integer >= 1")
        min_samples_leaf: Annotated[Int, Field(ge=1)] = Field(description="an integer >= 1")
        random_state: RandomState = Field(description=SEED)
    loo_method = "out-of-bag"

    def __init__(self, n_estimators: int = 300, min_samples_leaf: int = 1,
                 random_state: int = 0):
        self.n_estimators = n_estimators
        self.min_samples_leaf = min_samples_leaf
        self.random_state = random_state

    def fit(self, X, y):
        from sklearn.ensemble import RandomForestRegressor

        X, y = self._begin_fit(X, y)
        self.model_ = RandomForestRegressor(n_estimators=self.n_estimators,
                                            min_samples_leaf=self.min_samples_leaf,
                                            oob_score=True,
                                            random_state=self.random_state).fit(X, y)
        return self

    def loo_predict(self):
        """Out-of-bag predictions at the training runs (NaN where a run was in every
        bootstrap sample, possible only for very few trees)."""
        check_is_fitted(self)
        return self.model_.oob_prediction_

    def predict(self, X):
        X = self._check_predict(X)
        return self.model_.predict(X)
