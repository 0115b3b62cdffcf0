"""Sequential design by uncertainty sampling: each next run is the candidate where Gaussian-
process surrogates of the responses are least certain (MacKay 1992's active learning;
Gramacy 2020, *Surrogates*, Sect. 6.2).

The uncertainty of a candidate is the sum over the responses of the GP's predictive standard
deviation divided by the spread (standard deviation) of that response's runs so far, so that
responses on different scales count alike. Candidates are a finite set (e.g. the 3^k grid of
the full factorial the sequence replaces); a candidate already run is never proposed again.

A study stage runs one fixed design, and a sequence needs the responses between its runs, so
it is driven from Python: :func:`propose` picks the next candidates from fitted responses,
:func:`run_sequence` alternates runs (through :func:`sensfw.evaluate.evaluate` and the run
store) and proposals (``bench/strategies.py`` uses both).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from .base import DesignError


def uncertainty(table: pd.DataFrame, scores: pd.DataFrame, candidates: pd.DataFrame,
                bounds=None, options: Mapping[str, Any] | None = None) -> pd.Series:
    """Summed relative predictive standard deviation of GP surrogates (one per column of
    ``scores``, fitted to the finished rows of ``table``) at every candidate."""
    from ..surrogates import make_surrogate

    total = np.zeros(len(candidates))
    for label in scores.columns:
        y = scores[label].to_numpy(dtype=float)
        ok = np.isfinite(y)
        if ok.sum() < 3:
            raise DesignError(f"uncertainty sampling: {ok.sum()} finished runs of {label!r}; "
                              "a Gaussian process needs at least 3")
        gp = make_surrogate("gaussian_process", bounds=bounds, **dict(options or {}))
        gp.fit(table.loc[ok], y[ok])
        _, std = gp.predict(candidates[table.columns], return_std=True)
        spread = float(np.std(y[ok])) or 1.0
        total += np.asarray(std) / spread
    return pd.Series(total, index=candidates.index)


def propose(table: pd.DataFrame, scores: pd.DataFrame, candidates: pd.DataFrame, n: int = 1,
            bounds=None, options: Mapping[str, Any] | None = None) -> pd.DataFrame:
    """The ``n`` candidates (rows of ``candidates``) with the largest :func:`uncertainty`,
    leaving out candidates whose values are already a row of ``table``."""
    done = {tuple(np.round(r, 12)) for r in table[candidates.columns].to_numpy(dtype=float)}
    fresh = [lab for lab, r in zip(candidates.index, candidates.to_numpy(dtype=float),
                                   strict=True) if tuple(np.round(r, 12)) not in done]
    if not fresh:
        return candidates.iloc[:0]
    u = uncertainty(table, scores, candidates.loc[fresh], bounds, options)
    return candidates.loc[u.sort_values(ascending=False, kind="stable").index[:n]]


@dataclass
class RunSequence:
    """The runs of a sequence in the order they were added (``table``, ``scores``, run
    ``keys``) and the number of runs after each step (``steps``)."""

    table: pd.DataFrame
    scores: pd.DataFrame
    keys: list[str]
    steps: list[int] = field(default_factory=list)


def run_sequence(study, space, runner, scorers: Mapping[str, Any], start: pd.DataFrame,
                 candidates: pd.DataFrame, budget: int, batch: int = 1,
                 options: Mapping[str, Any] | None = None, reference=None,
                 on_step: Callable[[RunSequence], None] | None = None) -> RunSequence:
    """Run ``start``, then add the ``batch`` most uncertain candidates at a time until
    ``budget`` runs (or no candidate is left). ``on_step`` sees the sequence after each
    step. Runs go through ``runner`` (its run store: runs done before are not recomputed);
    ``reference`` as in :func:`~sensfw.evaluate.evaluate` (scorers that compare)."""
    from ..evaluate import evaluate

    if budget < len(start):
        raise DesignError(f"uncertainty sampling: budget {budget} is below the {len(start)} "
                          "start runs", option="budget")
    bounds = [(v.low, v.high) for v in space.variables]
    ev = evaluate(study, space, start, runner, scorers, reference, label="sequence start")
    seq = RunSequence(ev.table.copy(), ev.scores.copy(), list(ev.keys), [len(ev.table)])
    if on_step is not None:
        on_step(seq)
    while len(seq.table) < budget:
        nxt = propose(seq.table, seq.scores, candidates, min(batch, budget - len(seq.table)),
                      bounds, options)
        if nxt.empty:
            break
        ev = evaluate(study, space, nxt, runner, scorers, ev.reference, label="sequence")
        seq.table = pd.concat([seq.table, ev.table])
        seq.scores = pd.concat([seq.scores, ev.scores])
        seq.keys += ev.keys
        seq.steps.append(len(seq.table))
        if on_step is not None:
            on_step(seq)
    return seq
