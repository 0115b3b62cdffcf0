"""Designs of experiments (plugin group ``sensfw.designs``): run tables and their analyses."""

from ..plugins import designs as _registry
from . import (  # noqa: F401  (register the built-ins)
    definitive_screening,
    fractional_factorial,
    full_factorial,
    morris,
    oat,
    optimal,
    plackett_burman,
    response_surface,
    sobol,
    subset,
)
from .base import Design, DesignError, ScreeningResult


def make_design(name: str, **options) -> Design:
    """Instantiate the design registered as ``name`` (options validated)."""
    return _registry.get(name)(**options)


__all__ = ["Design", "DesignError", "ScreeningResult", "make_design"]
