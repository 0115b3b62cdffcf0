"""Surrogates (plugin group ``sensfw.surrogates``): scikit-learn regressors of a score."""

from ..plugins import surrogates as _registry
from . import (  # noqa: F401  (register the built-ins)
    auto,
    eq18,
    gaussian_process,
    polynomial,
    random_forest,
)
from .base import Surrogate, SurrogateBase, SurrogateError, option_problems


def make_surrogate(name: str, **options):
    """Instantiate the surrogate registered as ``name`` with ``options`` checked
    (:func:`~sensfw.surrogates.base.option_problems`); :class:`SurrogateError` names the
    first bad option."""
    cls = _registry.get(name)
    problems = option_problems(cls, options)
    if problems:
        option, message = problems[0]
        raise SurrogateError(f"surrogate {name!r}: {option + ': ' if option else ''}{message}",
                             option=option)
    return cls(**options)


__all__ = ["Surrogate", "SurrogateBase", "SurrogateError", "make_surrogate",
           "option_problems"]
