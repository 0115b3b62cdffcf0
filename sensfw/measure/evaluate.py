"""Hypotheses evaluated against the measurements: a point (base design variables and effect
parameters) -> model runs at every measured level (through the run store) -> comparisons of
every sensor channel the measurement and the model share -> weighted residuals
(:mod:`sensfw.measure.discrepancy`).

Every channel counts: a rig's accelerometers see the structure from different places, and
what one channel cannot tell apart (a heavier crankshaft or a softer bearing) another can.
"""

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


def shared_channels(study: Study, measurements: Sequence[Measurement]) -> list[str]:
    """The study's output first, then every other channel all measurements and the model
    have."""
    sensors = list(study.model.sensors)
    common = [c for c in sensors if all(c in m.signals.channels for m in measurements)]
    return [study.output] + [c for c in common if c != study.output]


class Evaluator:
    """Discrepancy of model variants against ``measurements``; ``space`` holds the base
    design variables a point may set (the rest stay at the study's nominal values);
    ``channels`` (default: :func:`shared_channels`) are compared at every level."""

    def __init__(self, study: Study, measurements: Sequence[Measurement], runner: Runner,
                 space: DesignSpace | None = None, channels: Sequence[str] | None = None):
        self.study, self.meas, self.runner = study, list(measurements), runner
        self.space = space
        self.channels = list(channels) if channels else shared_channels(study, measurements)
        ex = study.excitation
        self.band = (ex.f0, ex.f1)
        self.n_simulations = 0
        self.entries: discrepancy.Entries | None = None
        #: label of the batch -> the reason of its last failed run (the run store's error)
        self.failures: dict[str, str] = {}

    @property
    def n_levels(self) -> int:
        return len(self.meas)

    def variant(self, effect: Mapping | None, values: Mapping[str, float]) -> Variant:
        """The model with ``effect`` (a spec) at the point ``values``."""
        params = {}
        names = set(self.space.names) if self.space is not None else set()
        base = {n: values[n] for n in names if n in values}
        if base:
            params = self.space.to_parameters(base)
        params.update({k: v for k, v in values.items() if k not in names})
        return Variant.of([effect] if effect else [], params)

    def comparisons(self, variants: Sequence[Variant], label: str,
                    levels: Sequence[int] | None = None, detail: bool = True
                    ) -> list[list[LevelComparison] | None]:
        """Per variant, its comparisons for every (level, channel), levels outer (or only
        the ``levels``, indices of the measurements); ``None`` where a run failed.
        ``detail=False``: without the model's resonance fits (residuals only)."""
        idx = list(range(len(self.meas))) if levels is None else list(levels)
        meas = [self.meas[i] for i in idx]
        errors: dict = {}
        sims = simulate(self.study, self.runner, variants, meas, label, errors)
        self.n_simulations += len(sims)
        if errors:
            self.failures[label] = list(errors.values())[-1]
        out = []
        for v in variants:
            comps = []
            for j, m in enumerate(meas):
                sig = sims[(v, j)]
                if sig is None:
                    comps = None
                    break
                comps += [compare_level(m.signals, sig, ch, self.band, m.level, m.file,
                                        detail=detail) for ch in self.channels]
            out.append(comps)
        if self.entries is None and levels is None:
            first = next((c for c in out if c is not None), None)
            if first is not None:
                self.entries = discrepancy.Entries.of(first)
        return out

    def add_scatter(self, extra_db: np.ndarray) -> np.ndarray:
        """Widen every entry's standard error by the model's own scatter (dB, one value per
        entry: ``sigma^2 + extra^2``) and return the factor ``sigma_old / sigma_new`` that
        rescales residuals and Jacobians weighted before."""
        old = np.array([x for part in self.entries.sigma for x in part])
        new = np.sqrt(old**2 + np.asarray(extra_db, float) ** 2)
        sigma, i = [], 0
        for part in self.entries.sigma:
            sigma.append(tuple(new[i:i + len(part)]))
            i += len(part)
        self.entries = discrepancy.Entries(self.entries.bands, self.entries.thd, tuple(sigma))
        return old / new

    def _entries(self, levels: Sequence[int] | None) -> discrepancy.Entries:
        if levels is None:
            return self.entries
        k = len(self.channels)
        return self.entries.select([i * k + c for i in levels for c in range(k)])

    def weighted(self, comps, levels: Sequence[int] | None = None) -> np.ndarray | None:
        return None if comps is None else discrepancy.weighted(comps, self._entries(levels))

    def level_slices(self) -> list[slice]:
        """The entries of each level (all its channels) in the residual vector."""
        per = self.entries.level_slices()
        k = len(self.channels)
        return [slice(per[i * k].start, per[i * k + k - 1].stop) for i in range(self.n_levels)]

    def evaluate(self, effect: Mapping | None, points: Sequence[Mapping[str, float]],
                 label: str, levels: Sequence[int] | None = None
                 ) -> list[np.ndarray | None]:
        """Weighted residual vectors of the model with ``effect`` at ``points``."""
        comps = self.comparisons([self.variant(effect, p) for p in points], label, levels,
                                 detail=False)
        return [self.weighted(c, levels) for c in comps]

    def rms_db(self, comps) -> float | None:
        """RMS dB difference over every entry (all levels and channels)."""
        return None if comps is None else discrepancy.rms_db(comps, self.entries)

    def rms_db_per_level(self, comps) -> list[float] | None:
        if comps is None:
            return None
        k = len(self.channels)
        out = []
        for i in range(self.n_levels):
            part = comps[i * k:(i + 1) * k]
            out.append(discrepancy.rms_db(part, self._entries([i])))
        return out

    def output_comparisons(self, comps) -> list[LevelComparison] | None:
        """The study output's comparison at every level (for plots)."""
        return None if comps is None else comps[::len(self.channels)]
