"""Measured files against a study's model: loading, levels and simulations at those levels.

Simulations go through the run store (``OUT/runs``) like any study run, so comparisons,
diagnoses and augmentations reuse each other's runs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import MeasurementError, SensfwError
from ..models.base import Signals
from ..runs import Runner, RunSpec
from ..study import Study
from .checks import prepare
from .io import Measurement, load
from .synthetic import model_with_effects


def estimate_level(sig: Signals) -> float:
    """Excitation amplitude (N) from the force: sqrt(2) x its RMS during the sweep."""
    s = sig.sweep()
    return float(np.sqrt(2.0) * np.sqrt(np.mean(s.force**2)))


def load_measurements(study: Study, files: Sequence[str]) -> list[Measurement]:
    """Load, check and align every file; each gets its level (sidecar or estimated)."""
    if not files:
        raise SensfwError("no measurement file given (--measured FILE ...)")
    out = []
    for f in files:
        meas = prepare(load(f), study.excitation, [study.output])
        if meas.level is None:
            meas.level = estimate_level(meas.signals)
            meas.notes.append(f"excitation level estimated from the force: {meas.level:.4g} N")
        if meas.level <= 0:
            raise MeasurementError(meas.file, "the force is zero", "force")
        out.append(meas)
    return sorted(out, key=lambda m: m.level)


@dataclass(frozen=True)
class Variant:
    """The study's model with extra effects and parameter values (hashable)."""

    effects: tuple[tuple[tuple[str, str], ...], ...] = ()
    params: tuple[tuple[str, float], ...] = ()

    @classmethod
    def of(cls, effects=(), params=None) -> Variant:
        v = cls(effects=tuple(tuple(sorted(dict(e).items())) for e in effects))
        return v.with_params(params or {})

    @property
    def effect_specs(self) -> list[dict]:
        return [dict(e) for e in self.effects]

    def with_params(self, values: Mapping[str, float]) -> Variant:
        merged = dict(self.params)
        merged.update({k: float(v) for k, v in values.items()})
        return replace(self, params=tuple(sorted(merged.items())))


def spec_for(study: Study, variant: Variant, level: float) -> RunSpec:
    model = model_with_effects(study, variant.effect_specs)
    params = study.parameters.nominal()
    declared = model.parameters()
    for name in declared:
        params.setdefault(name, declared[name].nominal)
    for k, v in variant.params:
        params[k] = declared[k].check(v)
    ref = study.model_ref()
    if variant.effects:
        ref = {"name": ref["name"], "options": {**ref["options"],
                                                "effects": variant.effect_specs}}
    ex = replace(study.excitation, amplitude=float(f"{level:.4g}"))
    return RunSpec.create(model, params, ex, study.solver, ref)


def simulate(study: Study, runner: Runner, variants: Sequence[Variant],
             levels: Sequence[float], label: str = "model") -> dict:
    """Signals of every (variant, level); failed runs map to None."""
    specs = {(v, lv): spec_for(study, v, lv) for v in variants for lv in levels}
    runner.run(list(specs.values()), label=label)
    out = {}
    for k, s in specs.items():
        res = runner.load(s.key())
        out[k] = res.signals if res is not None and res.ok else None
    return out
