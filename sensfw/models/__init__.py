"""Simulation models (plugin group ``sensfw.models``)."""

from .base import Model, Signals, SolverSettings

__all__ = ["Model", "Signals", "SolverSettings"]

from . import shaft_assembly  # noqa: F401  (registers the built-in model)
