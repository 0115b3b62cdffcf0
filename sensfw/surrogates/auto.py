"""The surrogate with the best cross-validated prognosis (the idea of optiSLang's Metamodel
of Optimal Prognosis, Most & Will 2008)."""

from __future__ import annotations

from sklearn.base import BaseEstimator, RegressorMixin

from ..plugins import surrogates
from ._validation import SurrogateError, check_xy

DEFAULT = ("eq18", "polynomial", "gaussian_process", "random_forest")


@surrogates.register("auto")
class Auto(RegressorMixin, BaseEstimator):
    """Fits each of ``candidates``, scores each by k-fold Q^2 (``cv`` folds, seeded) and
    keeps the best (``chosen_``, all scores in ``scores_``); predictions delegate to it.
    Candidates that cannot be fitted on the data (e.g. Eq. 18 with too few runs) are
    skipped."""

    def __init__(self, candidates=DEFAULT, bounds=None, cv: int = 5, random_state: int = 0):
        self.candidates = candidates
        self.bounds = bounds
        self.cv = cv
        self.random_state = random_state

    def fit(self, X, y):
        import inspect

        from sklearn.model_selection import KFold

        from ..analysis.validation import q2_cv
        from . import make_surrogate

        check_xy(self, X, y, fit=True)
        self.scores_ = {}
        fitted = {}
        folds = KFold(n_splits=min(self.cv, len(y)), shuffle=True,
                      random_state=self.random_state)
        for name in self.candidates:
            cls = surrogates.get(name)
            opts = {"bounds": self.bounds} if "bounds" in inspect.signature(cls).parameters \
                else {}
            est = make_surrogate(name, **opts)
            try:
                self.scores_[name] = q2_cv(est, X, y, folds)
                fitted[name] = est.fit(X, y)
            except SurrogateError:
                continue
        if not fitted:
            raise SurrogateError("Auto: no candidate could be fitted")
        self.chosen_ = max(fitted, key=lambda n: self.scores_[n])
        self.estimator_ = fitted[self.chosen_]
        self.summary_ = getattr(self.estimator_, "summary_", None)
        return self

    def predict(self, X):
        return self.estimator_.predict(X)

    def predict_interval(self, X, alpha: float = 0.05):
        if not hasattr(self.estimator_, "predict_interval"):
            raise SurrogateError(f"Auto chose {self.chosen_}, which has no prediction "
                                 "intervals")
        return self.estimator_.predict_interval(X, alpha=alpha)
