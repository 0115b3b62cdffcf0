"""Random forest regression (scikit-learn)."""

from __future__ import annotations

from sklearn.base import BaseEstimator, RegressorMixin

from ..plugins import surrogates
from ._validation import check_xy


@surrogates.register("random_forest")
class RandomForest(RegressorMixin, BaseEstimator):
    """A seeded random forest; robust to steps and interactions, poor at extrapolation and
    without calibrated prediction intervals."""

    def __init__(self, n_estimators: int = 300, min_samples_leaf: int = 1,
                 random_state: int = 0):
        self.n_estimators = n_estimators
        self.min_samples_leaf = min_samples_leaf
        self.random_state = random_state

    def fit(self, X, y):
        from sklearn.ensemble import RandomForestRegressor

        X, y = check_xy(self, X, y, fit=True)
        self.model_ = RandomForestRegressor(n_estimators=self.n_estimators,
                                            min_samples_leaf=self.min_samples_leaf,
                                            random_state=self.random_state).fit(X, y)
        return self

    def predict(self, X):
        return self.model_.predict(check_xy(self, X))
