"""Simulation models (plugin group ``sensfw.models``): the Exudyn shaft assembly and analytic
test models."""

from . import analytic, bolted_beam, shaft_assembly  # noqa: F401  (register the built-ins)
from .base import Model, Signals, SolverSettings

__all__ = ["Model", "Signals", "SolverSettings"]
