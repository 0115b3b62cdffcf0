"""Surrogates (plugin group ``sensfw.surrogates``): scikit-learn regressors of a score."""

from ..options import make, option_problems
from ..plugins import surrogates as _registry
from . import (  # noqa: F401  (register the built-ins)
    auto,
    eq18,
    gaussian_process,
    polynomial,
    random_forest,
)
from .base import Surrogate, SurrogateBase, SurrogateError


def make_surrogate(name: str, **options):
    """Instantiate the surrogate registered as ``name`` with ``options`` checked
    (:func:`sensfw.options.option_problems`); :class:`SurrogateError` names every bad
    option."""
    return make(_registry, name, options, SurrogateError)


__all__ = ["Surrogate", "SurrogateBase", "SurrogateError", "make_surrogate",
           "option_problems"]
