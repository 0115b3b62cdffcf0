"""Hypotheses against the measurements: a point (base design variables and effect
parameters) -> model runs at every measured level (:func:`sensfw.evaluate.variant_spec`,
through the run store) -> comparisons of every sensor channel the measurement and the
model share -> weighted residual vectors (:mod:`sensfw.measure.discrepancy`).

Every channel counts: a rig's accelerometers see the structure from different places, and
what one channel cannot tell apart (a heavier crankshaft or a softer bearing) another can.

Records of different kinds (sweeps, random excitation, stepped sines, FRFs alone) enter
together, each driving the model as it was driven; each kind's entries are weighted by
``sqrt(n / (K n_k))`` (``n`` entries in all, ``n_k`` of the kind, ``K`` kinds) so that every
kind counts as much as the others whatever its number of bands and channels, while a
correct model still leaves ``chi2 ~ n`` (each kind's expected ``n_k`` becomes ``n / K``).

Every residual vector computed is kept as a :class:`~sensfw.measure.calibration.Trial` of
its model variant (:meth:`Residuals.trials`), so that hypotheses share evidence: the runs
of "parameters only" are every candidate's runs at the candidate's neutral values, and a
run at all levels also answers for any one of them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import SensfwError
from ..evaluate import simulate, variant_spec
from ..params import DesignSpace
from ..runs import Runner
from ..study import Study
from . import discrepancy
from .calibration import Trial
from .checks import recorded_band
from .compare import LevelComparison, compare_level, noise_model
from .io import Measurement

EffectSpecs = Sequence[Mapping[str, str]]


def shared_channels(study: Study, measurements: Sequence[Measurement]) -> list[str]:
    """The study's output first, then every other channel all measurements and the model
    have."""
    sensors = list(study.model.sensors)
    common = [c for c in sensors if all(c in m.signals.channels for m in measurements)]
    return [study.output] + [c for c in common if c != study.output]


def effects_key(effects: EffectSpecs | None) -> tuple:
    return tuple(tuple(sorted(dict(e).items())) for e in effects or ())


class Residuals:
    """Discrepancy of model variants against ``measurements``; ``space`` holds the base
    design variables a point may set (the rest stay at the study's nominal values);
    ``channels`` (default: :func:`shared_channels`) are compared at every level."""

    def __init__(self, study: Study, measurements: Sequence[Measurement], runner: Runner,
                 space: DesignSpace | None = None, channels: Sequence[str] | None = None):
        self.study, self.meas, self.runner = study, list(measurements), runner
        self.space = space
        #: the band errors' noise model (the study's ``[calibration] noise``)
        self.noise = noise_model(study)
        self.channels = list(channels) if channels else shared_channels(study, measurements)
        self.kinds = [m.kind for m in self.meas]
        self.kind_weights: dict[str, float] = {}
        ex = study.excitation
        self.band = (ex.f0, ex.f1)
        #: per record, the band it is compared on: the study's, cut to what a record
        #: sampled below the study's rate holds (:func:`~sensfw.measure.checks.recorded_band`,
        #: as ``compare`` cuts it)
        self.bands = [self.band if m.frf is not None else
                      recorded_band(m, self.band, ex.fs) for m in self.meas]
        for m, b in zip(self.meas, self.bands, strict=True):
            if b[0] >= b[1]:
                raise SensfwError(f"{m.file}: sampled at {m.signals.meta.get('recorded_fs')}"
                                  f" Hz, the record holds no line of the study's band "
                                  f"{self.band[0]:g}-{self.band[1]:g} Hz (up to {b[1]:.4g} Hz)")
        self.n_simulations = 0
        #: the step of the caller's method the next simulations count for (``spent``)
        self.step = "start"
        #: step -> simulations (one per point and level) it asked for, cached or not
        self.spent: dict[str, int] = {}
        self.entries: discrepancy.Entries | None = None
        #: label of the batch -> the reason of its last failed run (the run store's)
        self.failures: dict[str, str] = {}
        #: effects key -> [(levels, Trial)]: every residual vector computed
        self._pool: dict[tuple, list[tuple[tuple[int, ...], Trial]]] = {}

    @property
    def n_levels(self) -> int:
        return len(self.meas)

    def parameters(self, values: Mapping[str, float]) -> dict[str, float]:
        """Model parameter values of a point (design variables expanded to their members)."""
        names = set(self.space.names) if self.space is not None else set()
        base = {n: values[n] for n in names if n in values}
        params = self.space.to_parameters(base) if base else {}
        params.update({k: v for k, v in values.items() if k not in names})
        return params

    def comparisons(self, effects: EffectSpecs | None, points: Sequence[Mapping[str, float]],
                    label: str, levels: Sequence[int] | None = None, detail: bool = True
                    ) -> list[list[LevelComparison] | None]:
        """Per point, the comparisons of the model with ``effects`` for every (level,
        channel), levels outer (or only the ``levels``, indices of the measurements);
        ``None`` where a run failed. ``detail=False``: without the model's resonance fits
        (residuals only)."""
        idx = list(range(self.n_levels)) if levels is None else list(levels)
        specs = [variant_spec(self.study, self.parameters(p), self.meas[i].drive,
                              effects or ()) for p in points for i in idx]
        signals, errors = simulate(self.runner, specs, label)
        self.n_simulations += len(specs)
        self.spent[self.step] = self.spent.get(self.step, 0) + len(specs)
        failed = [e for e in errors if e is not None]
        if failed:
            self.failures[label] = failed[-1]
        out = []
        for k in range(len(points)):
            comps = []
            for j, i in enumerate(idx):
                sig = signals[k * len(idx) + j]
                if sig is None:
                    comps = None
                    break
                m = self.meas[i]
                comps += [compare_level(m.signals, sig, ch, self.bands[i], m.level, m.file,
                                        detail=detail, noise=self.noise)
                          for ch in self.channels]
            out.append(comps)
        if self.entries is None and levels is None:
            first = next((c for c in out if c is not None), None)
            if first is not None:
                self.entries = discrepancy.Entries.of(first, self.noise)
                sizes = [s.stop - s.start for s in self.level_slices()]
                per = {k: sum(n for n, kk in zip(sizes, self.kinds, strict=True) if kk == k)
                       for k in dict.fromkeys(self.kinds)}
                total = sum(per.values())
                self.kind_weights = {k: float(np.sqrt(total / (len(per) * n)))
                                     for k, n in per.items()}
        if self.entries is not None:  # every residual vector is evidence for later
            pool = self._pool.setdefault(effects_key(effects), [])
            pool += [(tuple(idx), Trial(dict(p), self.weighted(c, levels)))
                     for p, c in zip(points, out, strict=True)]
        return out

    def nominal(self, hint: str = "") -> tuple[dict[str, float], list[LevelComparison]]:
        """The space's nominal point and the model's comparisons there (batch ``"nominal
        model"``); a :class:`~sensfw.errors.SensfwError` (ending in ``hint``) where it fails."""
        nominal = self.space.nominal_row()
        (comps,) = self.comparisons(None, [nominal], "nominal model")
        if comps is None:
            why = self.failures.get("nominal model")
            raise SensfwError("the study's model failed at the measured level(s)"
                              + (f": {why}" if why else "") + hint)
        return nominal, comps

    def evaluate(self, effects: EffectSpecs | None, points: Sequence[Mapping[str, float]],
                 label: str, levels: Sequence[int] | None = None
                 ) -> list[np.ndarray | None]:
        """Weighted residual vectors of the model with ``effects`` at ``points`` (kept as
        trials of that variant)."""
        comps = self.comparisons(effects, points, label, levels, detail=False)
        return [self.weighted(c, levels) for c in comps]

    def simulations_of(self, effects: EffectSpecs | None = None) -> int:
        """How many simulations (one per point and level) the model with ``effects`` had,
        failed ones included."""
        return sum(len(lv) for lv, _ in self._pool.get(effects_key(effects), []))

    def trials(self, effects: EffectSpecs | None = None, levels: Sequence[int] | None = None,
               extra: Mapping[str, float] | None = None) -> list[Trial]:
        """Every successful trial of the model with ``effects`` that covers ``levels``
        (default all), its residuals cut to those levels; ``extra`` values are added to each
        trial's point (the neutral values of an effect that H0's trials stand for)."""
        want = tuple(range(self.n_levels)) if levels is None else tuple(levels)
        sizes = [s.stop - s.start for s in self.level_slices()]
        out = []
        for lv, t in self._pool.get(effects_key(effects), []):
            if t.w is None or not set(want) <= set(lv):
                continue
            offsets = np.cumsum([0] + [sizes[i] for i in lv])
            pos = {i: k for k, i in enumerate(lv)}
            w = np.concatenate([t.w[offsets[pos[i]]:offsets[pos[i] + 1]] for i in want])
            out.append(Trial({**t.values, **(extra or {})}, w))
        return out

    def add_scatter(self, extra_db: np.ndarray) -> None:
        """Widen every entry's standard error by the model's own scatter (dB, one value per
        entry: ``sigma^2 + extra^2``) and reweight every trial kept so far."""
        old = np.array([x for part in self.entries.sigma for x in part])
        new = np.sqrt(old**2 + np.asarray(extra_db, float) ** 2)
        sigma, i = [], 0
        for part in self.entries.sigma:
            sigma.append(tuple(new[i:i + len(part)]))
            i += len(part)
        slices = self.level_slices()
        scale = old / new
        # the same entries, and the same noise model (its THD entry reads the model against
        # the record's noise floor), with the widened errors
        self.entries = dataclasses.replace(self.entries, sigma=tuple(sigma))
        for pool in self._pool.values():
            for lv, t in pool:
                if t.w is not None:
                    t.w = t.w * np.concatenate([scale[slices[i]] for i in lv])

    def _entries(self, levels: Sequence[int] | None) -> discrepancy.Entries:
        if levels is None:
            return self.entries
        k = len(self.channels)
        return self.entries.select([i * k + c for i in levels for c in range(k)])

    def weighted(self, comps, levels: Sequence[int] | None = None) -> np.ndarray | None:
        """Residuals divided by their standard errors, each record's by its kind's weight
        (module docstring)."""
        if comps is None:
            return None
        return discrepancy.weighted(comps, self._entries(levels)) * self.entry_weights(levels)

    def entry_weights(self, levels: Sequence[int] | None = None) -> np.ndarray | float:
        """Each entry's kind weight (module docstring); 1 with one kind of record."""
        if len(set(self.kind_weights.values())) <= 1:
            return 1.0
        idx = list(range(self.n_levels)) if levels is None else list(levels)
        sizes = [s.stop - s.start for s in self.level_slices()]
        return np.concatenate([np.full(sizes[i], self.kind_weights[self.kinds[i]])
                               for i in idx])

    def records(self) -> list[dict]:
        """Per record (in the order of the residual vector): file, kind, level."""
        return [{"file": m.file, "kind": k, "level": m.level}
                for m, k in zip(self.meas, self.kinds, strict=True)]

    def level_slices(self) -> list[slice]:
        """The entries of each level (all its channels) in the residual vector."""
        per = self.entries.level_slices()
        k = len(self.channels)
        return [slice(per[i * k].start, per[i * k + k - 1].stop) for i in range(self.n_levels)]

    def chi2_per_level(self, w: np.ndarray) -> list[float]:
        return [float(np.sum(w[s] ** 2)) for s in self.level_slices()]

    def rms_db(self, comps) -> float | None:
        """RMS dB difference over every entry (all levels and channels)."""
        return None if comps is None else discrepancy.rms_db(comps, self.entries)

    def rms_db_per_level(self, comps) -> list[float] | None:
        if comps is None:
            return None
        k = len(self.channels)
        return [discrepancy.rms_db(comps[i * k:(i + 1) * k], self._entries([i]))
                for i in range(self.n_levels)]

    def output_comparisons(self, comps) -> list[LevelComparison] | None:
        """The study output's comparison at every level (for plots)."""
        return None if comps is None else comps[::len(self.channels)]
