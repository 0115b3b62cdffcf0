"""Simulation models (plugin group ``sensfw.models``)."""

from .base import Model, Signals, SolverSettings

__all__ = ["Model", "Signals", "SolverSettings"]
