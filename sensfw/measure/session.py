"""Measured files against a study's model: loading, levels and simulations at those levels.

Simulations go through the run store (``OUT/runs``) like any study run, so comparisons,
diagnoses and augmentations reuse each other's runs.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

from ..errors import MeasurementError, SensfwError
from ..runs import Runner, RunSpec
from ..study import Study
from .checks import prepare
from .io import Measurement, load_all
from .synthetic import model_with_effects


def load_measurements(study: Study, files: Sequence[str]) -> list[Measurement]:
    """Load, check and prepare every file (:func:`~sensfw.measure.checks.prepare`: level,
    excitation estimate, drive, alignment), sorted by level."""
    if not files:
        raise SensfwError("no measurement file given (--measured FILE ...)")
    out = []
    for f in files:
        for raw in load_all(f):
            meas = prepare(raw, study)
            if not meas.level > 0:
                raise MeasurementError(meas.file, "the excitation is zero", "force")
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


def spec_for(study: Study, variant: Variant, meas: Measurement) -> RunSpec:
    """The run of the study's model with ``variant`` driven as ``meas`` says."""
    model = model_with_effects(study, variant.effect_specs)
    params = study.parameters.nominal()
    declared = model.parameters()
    for name in declared:
        params.setdefault(name, declared[name].nominal)
    for k, v in variant.params:
        params[k] = (declared[k] if k in declared else study.parameters[k]).check(v)
    ref = study.model_ref()
    if variant.effects:  # the study's own effects, then the variant's (model_with_effects)
        effects = [*ref["options"].get("effects", []), *variant.effect_specs]
        ref = {"name": ref["name"], "options": {**ref["options"], "effects": effects}}
    return RunSpec.create(model, params, meas.drive, study.solver, ref)


def simulate(study: Study, runner: Runner, variants: Sequence[Variant],
             measurements: Sequence[Measurement], label: str = "model",
             errors: dict | None = None) -> dict:
    """Signals of every (variant, index of the measurement); failed runs map to None, and
    their reasons (the run store's) to ``errors[(variant, index)]`` when given."""
    specs = {(v, i): spec_for(study, v, m) for v in variants
             for i, m in enumerate(measurements)}
    runner.run(list(specs.values()), label=label)
    out = {}
    for k, s in specs.items():
        res = runner.load(s.key())
        out[k] = res.signals if res is not None and res.ok else None
        if out[k] is None and errors is not None:
            errors[k] = (res.error if res is not None else None) or "no result stored"
    return out
