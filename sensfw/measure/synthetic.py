"""Synthetic measurements: the model (optionally with a hidden effect) plus sensor noise.

This is how tests and demos make data whose answer is known (``sensfw simulate``).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np

from ..errors import SensfwError
from ..models.base import Model, Signals
from ..study import Study


def model_with_effects(study: Study, effects: Sequence[Mapping]) -> Model:
    """The study's model with extra effects (``[{"name": ..., "attach": ...}, ...]``)."""
    from ..plugins import models

    cls = models.get(study.spec.model.name)
    options = dict(study.spec.model.options)
    if effects:
        if "effects" not in inspect.signature(cls).parameters:
            raise SensfwError(f"model {study.spec.model.name!r} does not take effects")
        options["effects"] = [*options.get("effects", []), *effects]
    return cls(**options)


def parse_effect(text: str) -> tuple[dict, dict[str, float]]:
    """``NAME[@ATTACH][:PARAM=VALUE,...]`` -> (effect spec, parameter values)."""
    head, _, tail = text.partition(":")
    name, _, attach = head.partition("@")
    spec = {"name": name.strip()}
    if attach:
        spec["attach"] = attach.strip()
    values = {}
    for item in filter(None, (s.strip() for s in tail.split(","))):
        key, sep, val = item.partition("=")
        if not sep:
            raise SensfwError(f"effect {text!r}: expected PARAM=VALUE, got {item!r}")
        try:
            values[key.strip()] = float(val)
        except ValueError:
            raise SensfwError(f"effect {text!r}: {key.strip()} = {val!r} is not a number") \
                from None
    return spec, values


def add_noise(sig: Signals, fraction: float, seed: int | None) -> Signals:
    """White Gaussian noise on force and channels, std = ``fraction`` x each signal's RMS."""
    rng = np.random.default_rng(seed)

    def noisy(x):
        rms = float(np.sqrt(np.mean(x**2)))
        return x + fraction * rms * rng.standard_normal(len(x))

    return replace(sig, force=noisy(sig.force),
                   channels={k: noisy(v) for k, v in sig.channels.items()})


def synthesize(study: Study, sets: Mapping[str, float] | None = None,
               effects: Sequence[str] = (), noise: float = 0.0, seed: int | None = 0,
               amplitude: float | None = None) -> tuple[Signals, dict]:
    """Simulate one configuration of ``study``'s model as a measurement.

    ``effects`` are ``NAME[@ATTACH][:PARAM=VALUE,...]`` strings; ``sets`` overrides parameter
    values (checked against bounds). Returns the signals and what was simulated.
    """
    specs, values = [], dict(sets or {})
    for text in effects:
        spec, vals = parse_effect(text)
        specs.append(spec)
        values.update(vals)
    model = model_with_effects(study, specs)
    params = study.parameters.nominal()
    declared = model.parameters()
    for p in declared:
        if p not in params:
            params[p] = declared[p].nominal
    for k, v in values.items():
        params[k] = declared[k].check(v)
    ex = study.excitation if amplitude is None else replace(study.excitation,
                                                            amplitude=float(amplitude))
    sig = model.simulate(params, ex, study.solver)
    if noise:
        sig = add_noise(sig, noise, seed)
    return sig, {"effects": specs, "parameters": values, "amplitude": ex.amplitude,
                 "noise": noise, "seed": seed}
