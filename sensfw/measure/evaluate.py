"""Hypotheses evaluated against the measurements: a point (base design variables and effect
parameters) -> model runs at every measured level (through the run store) -> comparisons ->
weighted residuals (:mod:`sensfw.measure.discrepancy`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..params import DesignSpace
from ..runs import Runner
from ..study import Study
from . import discrepancy
from .compare import LevelComparison, compare_level
from .io import Measurement
from .session import Variant, simulate


class Evaluator:
    """Discrepancy of model variants against ``measurements``; ``space`` holds the base
    design variables a point may set (the rest stay at the study's nominal values)."""

    def __init__(self, study: Study, measurements: Sequence[Measurement], runner: Runner,
                 space: DesignSpace | None = None):
        self.study, self.meas, self.runner = study, list(measurements), runner
        self.space = space
        ex = study.excitation
        self.band = (ex.f0, ex.f1)
        self.n_simulations = 0
        self.entries: discrepancy.Entries | None = None

    def variant(self, effect: Mapping | None, values: Mapping[str, float]) -> Variant:
        """The model with ``effect`` (a spec) at the point ``values``."""
        params = {}
        if self.space is not None:
            base = {n: values[n] for n in self.space.names if n in values}
            if base:
                params = self.space.to_parameters(base)
        names = set(self.space.names) if self.space is not None else set()
        params.update({k: v for k, v in values.items() if k not in names})
        return Variant.of([effect] if effect else [], params)

    def comparisons(self, variants: Sequence[Variant], label: str,
                    levels: Sequence[int] | None = None
                    ) -> list[list[LevelComparison] | None]:
        """Per variant, its comparison at every measured level (or at ``levels``, indices
        of the measurements); ``None`` where a run failed."""
        idx = list(range(len(self.meas))) if levels is None else list(levels)
        meas = [self.meas[i] for i in idx]
        sims = simulate(self.study, self.runner, variants, meas, label)
        self.n_simulations += len(sims)
        out = []
        for v in variants:
            comps = []
            for j, m in enumerate(meas):
                sig = sims[(v, j)]
                if sig is None:
                    comps = None
                    break
                comps.append(compare_level(m.signals, sig, self.study.output, self.band,
                                           m.level, m.file))
            out.append(comps)
        if self.entries is None and levels is None:
            first = next((c for c in out if c is not None), None)
            if first is not None:
                self.entries = discrepancy.Entries.of(first)
        return out

    def weighted(self, comps, levels: Sequence[int] | None = None) -> np.ndarray | None:
        if comps is None:
            return None
        entries = self.entries
        if levels is not None:
            entries = discrepancy.Entries(tuple(entries.bands[i] for i in levels),
                                          tuple(entries.thd[i] for i in levels))
        return discrepancy.weighted(comps, entries)

    def evaluate(self, effect: Mapping | None, points: Sequence[Mapping[str, float]],
                 label: str, levels: Sequence[int] | None = None
                 ) -> list[np.ndarray | None]:
        """Weighted residual vectors of the model with ``effect`` at ``points``."""
        comps = self.comparisons([self.variant(effect, p) for p in points], label, levels)
        return [self.weighted(c, levels) for c in comps]

    def rms_db(self, comps) -> float | None:
        return None if comps is None else discrepancy.rms_db(comps, self.entries)

    def rms_db_per_level(self, comps) -> list[float] | None:
        if comps is None:
            return None
        out = []
        for i, c in enumerate(comps):
            entries = discrepancy.Entries((self.entries.bands[i],), (self.entries.thd[i],))
            out.append(discrepancy.rms_db([c], entries))
        return out
