"""Measurements: load, check, align, compare with the model, diagnose missing physics."""
