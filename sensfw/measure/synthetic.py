"""Synthetic measurements: the model (optionally with a hidden effect and base parameters
off their nominal values) as a rig would record it.

A rig's records are never the study's clean signals: :func:`synthesize` adds what
:mod:`sensfw.measure.checks` must cope with — sensor noise on every channel, a DC offset on
the force, an amplitude that drifts slowly (the shaker-structure interaction near
resonances; the model is driven by the drifting force, so the response is consistent with
it), a pre-trigger delay, another kind of excitation (``linear_sweep``, ``random``,
``stepped_sine``) and an amplifier voltage recorded instead of the force (``gain`` N/V).
This is how tests and demos make data whose answer is known (``sensfw simulate``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SensfwError
from ..evaluate import model_with_effects
from ..excitation import Excitation, SampledForce, make_excitation
from ..models.base import Signals
from ..study import Study


def parse_effect(text: str) -> tuple[dict, dict[str, float]]:
    """``NAME[@PLACE][:KEY=VALUE,...]`` -> (effect spec, parameter values): a key that is
    one of the effect's options (``micro_slip:elements=6``, as ``augment --option`` takes
    them) goes into the spec, the others are its parameters' values."""
    head, _, tail = text.partition(":")
    name, _, attach = head.partition("@")
    spec = {"name": name.strip()}
    if attach:
        spec["attach"] = attach.strip()
    items = [s.strip() for s in tail.split(",") if s.strip()]
    options = _option_names(spec["name"])
    opts = [i for i in items if i.partition("=")[0].strip() in options]
    for item in opts:
        key, _, val = item.partition("=")
        spec[key.strip()] = _literal(val.strip())
    rest = [i for i in items if i not in opts]
    return spec, parse_assignments(rest, f"effect {text!r}")


def _option_names(effect: str) -> set[str]:
    """The options an effect declares besides ``attach`` (none for an unknown name: the
    model's check names it)."""
    from ..options import options_model
    from ..plugins import effects

    try:
        cls = effects.get(effect)
    except Exception:  # an unknown effect: reported where the model resolves it
        return set()
    return set(options_model(cls).model_fields) - {"attach"}


def _literal(text: str):
    """An option's value as written: an integer, a number, or a string."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def parse_assignments(items: Iterable[str], where: str) -> dict[str, float]:
    """``["NAME=VALUE", ...]`` -> ``{NAME: VALUE}``; a clear error naming ``where`` (the
    option or effect the items came from) for an item without ``=`` or with no number."""
    values = {}
    for item in items:
        key, sep, val = item.partition("=")
        if not sep:
            raise SensfwError(f"{where}: expected NAME=VALUE, got {item!r}")
        try:
            values[key.strip()] = float(val)
        except ValueError:
            raise SensfwError(f"{where}: {key.strip()} = {val!r} is not a number") from None
    return values


@dataclass(frozen=True)
class Rig:
    """How the rig records: ``noise`` (std as a fraction of each channel's RMS), ``offset``
    (DC on the force, fraction of the level), ``drift`` (relative amplitude of a slow
    sinusoidal modulation of the applied force), ``delay`` (s of pre-trigger silence),
    ``gain`` (N/V: the excitation channel holds the amplifier voltage, force / gain)."""

    noise: float = 0.0
    offset: float = 0.0
    drift: float = 0.0
    delay: float = 0.0
    gain: float | None = None
    seed: int | None = 0

    def __post_init__(self) -> None:
        for name in ("noise", "drift", "delay"):
            if not getattr(self, name) >= 0:
                raise SensfwError(f"rig {name} must be >= 0, got {getattr(self, name)!r}")
        if not self.drift < 1:
            raise SensfwError(f"rig drift must be below 1 (a fraction of the level), got "
                              f"{self.drift!r}: at 1 or more the excitation's envelope "
                              "passes through zero and inverts")
        if self.gain is not None and not self.gain > 0:
            raise SensfwError(f"rig gain (N/V) must be positive, got {self.gain!r}")


def excitation_of(study: Study, kind: str | None, amplitude: float | None) -> Excitation:
    """The study's excitation, or another ``kind`` over the same band, duration, rate and
    tail, at ``amplitude``."""
    ex = study.excitation
    if kind is not None and kind != ex.kind:
        spec = {"kind": kind, "f0": ex.f0, "f1": ex.f1, "duration": ex.duration, "fs": ex.fs,
                "amplitude": ex.amplitude, "tail": ex.tail}
        ex = make_excitation(spec)
    if amplitude is not None:
        ex = ex.with_amplitude(float(amplitude))
    return ex


def _drifting(ex: Excitation, drift: float, rng) -> Excitation:
    """The force with a slow amplitude modulation ``1 + drift sin(...)`` (about 1.3 cycles
    over the sweep, random phase) as a sampled excitation."""
    t = ex.time()
    phase = rng.uniform(0, 2 * math.pi)
    mod = 1.0 + drift * np.sin(2 * math.pi * t / (ex.duration / 1.3) + phase)
    sweep = None
    if ex.f_inst(t) is not None and ex.kind in ("log_chirp", "linear_sweep"):
        sweep = {"kind": ex.kind, "f0": ex.f0, "f1": ex.f1, "t_start": 0.0,
                 "t_end": ex.duration}
    return SampledForce(ex.force(t) * mod, ex.fs, amplitude=ex.amplitude, sweep=sweep)


def record(sig: Signals, rig: Rig, level: float, rng) -> Signals:
    """What the rig records of a simulated run (see :class:`Rig`); ``level`` is the
    excitation level in the recorded channel's unit."""
    force = sig.force / rig.gain if rig.gain else sig.force
    channels = dict(sig.channels)
    units = {**sig.units, "force": "V" if rig.gain else "N"}
    n0 = round(rig.delay * sig.fs)
    if n0:
        force = np.concatenate([np.zeros(n0), force])
        channels = {k: np.concatenate([np.zeros(n0), v]) for k, v in channels.items()}

    def noisy(x):
        rms = float(np.sqrt(np.mean(x**2)))
        return x + rig.noise * rms * rng.standard_normal(len(x)) if rig.noise else x

    force = noisy(force) + rig.offset * level
    channels = {k: noisy(v) for k, v in channels.items()}
    n = len(force)
    return Signals(t=np.arange(n) / sig.fs, force=force, channels=channels, fs=sig.fs,
                   units=units, meta=dict(sig.meta))


def synthesize(study: Study, sets: Mapping[str, float] | None = None,
               effects: Sequence[str] = (), noise: float = 0.0, seed: int | None = 0,
               amplitude: float | None = None, excitation: str | None = None,
               rig: Rig | None = None) -> tuple[Signals, dict]:
    """Simulate one configuration of ``study``'s model as a rig records it.

    ``effects`` are ``NAME[@PLACE][:PARAM=VALUE,...]`` strings; ``sets`` overrides parameter
    values (checked against bounds); ``excitation`` another kind than the study's;
    ``rig`` the recording (``noise`` and ``seed`` are shortcuts for it). Returns the
    signals and what was simulated.
    """
    rig = rig or Rig(noise=noise, seed=seed)
    rng = np.random.default_rng(rig.seed)
    specs, values = [], dict(sets or {})
    for text in effects:
        spec, vals = parse_effect(text)
        specs.append(spec)
        values.update(vals)
    model = model_with_effects(study, specs)
    params = study.parameters.nominal()
    gain = values.pop("excitation_gain", params.pop("excitation_gain", None))
    declared = model.parameters()
    for p in declared:
        if p not in params:
            params[p] = declared[p].nominal
    for k, v in values.items():
        params[k] = declared[k].check(v)
    ex = excitation_of(study, excitation, amplitude)
    level = ex.amplitude  # in the recorded channel's unit
    if ex.unit != "N":  # a voltage study: the rig records the voltage, the shaker's gain
        if rig.gain is not None:
            raise SensfwError(f"the study drives a voltage ({ex.unit}): the shaker's gain is "
                              "its parameter excitation_gain; set it with --set "
                              "excitation_gain=..., not --channel-gain")
        gain = study.parameters["excitation_gain"].check(gain) if gain is not None else None
        rig = replace(rig, gain=gain or study.parameters["excitation_gain"].nominal)
        ex = ex.scaled(rig.gain)
    elif rig.gain:  # a force study whose rig records the voltage
        level = ex.amplitude / rig.gain
    drive = _drifting(ex, rig.drift, rng) if rig.drift else ex
    sig = model.simulate(params, drive, study.solver)
    if len(sig.t) < 2:
        raise SensfwError(f"model {study.spec.model.name!r} gives one value per run, not a "
                          "time response (a function model): there is nothing a rig would "
                          "record")
    sig = record(sig, rig, level, rng)
    info = {"effects": specs, "parameters": values, "amplitude": level,
            "unit": sig.units["force"], "excitation": ex.kind,
            "noise": rig.noise, "seed": rig.seed, "rig": dict(rig.__dict__)}
    return sig, info


def add_noise(sig: Signals, fraction: float, seed: int | None) -> Signals:
    """White Gaussian noise on force and channels, std = ``fraction`` x each signal's RMS."""
    rng = np.random.default_rng(seed)

    def noisy(x):
        rms = float(np.sqrt(np.mean(x**2)))
        return x + fraction * rms * rng.standard_normal(len(x))

    return replace(sig, force=noisy(sig.force),
                   channels={k: noisy(v) for k, v in sig.channels.items()})
