"""Outcome scorers (plugin group ``sensfw.scorers``): signals -> numbers."""

from ..plugins import scorers as _registry
from . import basic, frf_scalar, orders  # noqa: F401  (register the built-ins)
from .base import Scorer, ScorerError


def make_scorer(name: str, **options) -> Scorer:
    """Instantiate the scorer registered as ``name`` (options validated)."""
    return _registry.get(name)(**options)


__all__ = ["Scorer", "ScorerError", "make_scorer"]
