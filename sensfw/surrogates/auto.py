"""The surrogate with the best cross-validated prognosis (the idea of optiSLang's Metamodel
of Optimal Prognosis, Most & Will 2008)."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, Field
from sklearn.utils.validation import check_is_fitted

from ..errors import UnknownPluginError
from ..options import Int, Pairs, PluginOptions, Str, options_model
from ..plugins import surrogates
from .base import BOUNDS, SEED, RandomState, SurrogateBase, SurrogateError

DEFAULT = ("eq18", "polynomial", "gaussian_process", "random_forest")


def _candidates(names: list[str]) -> list[str]:
    for name in names:
        if name == "auto":
            raise SurrogateError("candidates: 'auto' cannot be its own candidate",
                                 option="candidates")
        try:
            surrogates.get(name)
        except UnknownPluginError as err:
            raise SurrogateError(f"candidates: {err}", option="candidates") from None
    return names


@surrogates.register("auto")
class Auto(SurrogateBase):
    """Fits each of ``candidates``, scores each by k-fold Q^2 (``cv`` folds, seeded) and
    keeps the best (``chosen_``, all scores in ``scores_``); predictions, the summary, the
    coefficient tables, leave-one-out and intervals are the chosen surrogate's. Candidates
    that cannot be fitted on the data (e.g. Eq. 18 with too few runs) are skipped."""

    class Options(PluginOptions):
        candidates: Annotated[list[Str], Field(min_length=1), AfterValidator(_candidates)] = \
            Field(description="a list of registered surrogate names other than 'auto'")
        bounds: Pairs = Field(description=BOUNDS)
        cv: Annotated[Int, Field(ge=2)] = Field(description="an integer >= 2")
        random_state: RandomState = Field(description=SEED)

    def __init__(self, candidates=DEFAULT, bounds=None, cv: int = 5, random_state: int = 0):
        self.candidates = candidates
        self.bounds = bounds
        self.cv = cv
        self.random_state = random_state

    @property
    def loo_method(self) -> str | None:
        return self.estimator_.loo_method if hasattr(self, "estimator_") else None

    def fit(self, X, y):
        from sklearn.model_selection import KFold

        from ..analysis.validation import q2_cv
        from . import make_surrogate

        _, y = self._begin_fit(X, y)  # the candidates get X as given (feature names)
        if len(y) < 3:
            raise SurrogateError(f"Auto: {len(y)} run(s) (n_samples = {len(y)}) are too few "
                                 "to cross-validate the candidates")
        self.scores_ = {}
        fitted, why = {}, []
        folds = KFold(n_splits=min(self.cv, len(y)), shuffle=True,
                      random_state=self.random_state)
        for name in self.candidates:
            cls = surrogates.get(name)
            opts = {"bounds": self.bounds} if "bounds" in options_model(cls).model_fields else {}
            est = make_surrogate(name, **opts)
            try:
                self.scores_[name] = q2_cv(est, X, y, folds)
                fitted[name] = est.fit(X, y)
            except SurrogateError as err:
                why.append(str(err))
                continue
        if not fitted:
            raise SurrogateError(f"Auto: no candidate could be fitted ({'; '.join(why)})")
        self.chosen_ = max(fitted, key=lambda n: self.scores_[n])
        self.estimator_ = fitted[self.chosen_]
        self.summary_ = self.estimator_.summary_
        self.coefficient_table_ = self.estimator_.coefficient_table_
        self.coefficient_table_coded_ = self.estimator_.coefficient_table_coded_
        return self

    def predict(self, X):
        self._check_predict(X)
        return self.estimator_.predict(X)

    def loo_predict(self):
        check_is_fitted(self)
        return self.estimator_.loo_predict()

    def predict_interval(self, X, alpha: float = 0.05):
        self._check_predict(X)
        return self.estimator_.predict_interval(X, alpha=alpha)
