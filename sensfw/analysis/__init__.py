"""Analyses on top of designs and surrogates: validation, Sobol indices, comparisons."""
