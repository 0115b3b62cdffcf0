"""Surrogates (plugin group ``sensfw.surrogates``): scikit-learn regressors of a score."""

from ..plugins import surrogates as _registry
from . import (  # noqa: F401  (register the built-ins)
    auto,
    eq18,
    gaussian_process,
    polynomial,
    random_forest,
)
from ._validation import SurrogateError


def make_surrogate(name: str, **options):
    """Instantiate the surrogate registered as ``name``."""
    try:
        return _registry.get(name)(**options)
    except TypeError as err:
        raise SurrogateError(f"surrogate {name!r}: {err}") from None


__all__ = ["SurrogateError", "make_surrogate"]
