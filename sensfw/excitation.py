"""Excitation signals: the paper's logarithmic chirp, and what test rigs also run.

The paper (Sect. 2.3) excites with an exponential sweep. Eq. 7 as printed,
``A0 cos(2 pi f0 t (f1/f0)^(t/T))``, does not end at ``f1``: its instantaneous frequency
``d(phase)/dt / 2pi = f0 (f1/f0)^(t/T) (1 + t ln(f1/f0)/T)`` reaches ``f1 (1 + ln(f1/f0))``
at ``t = T``. We use the standard exponential sweep (Farina 2000)

    phase(t) = 2 pi f0 T / ln(f1/f0) * ((f1/f0)^(t/T) - 1),

whose instantaneous frequency is ``f0 exp(k t)`` with ``k = ln(f1/f0)/T``, exactly the
``rpm(t)/60`` of Eq. 17 that the order analysis needs.

Rigs also run linear sweeps, stepped sines and band-limited random noise, and a measured force
(or amplifier voltage) record can drive a model directly: :class:`Chirp`,
:class:`LinearSweep`, :class:`SteppedSine`, :class:`RandomForce`, :class:`SampledForce`.
Every excitation gives its samples (:meth:`Excitation.force`), its instantaneous frequency
where it has one (``None`` for random noise), and either a closed-form expression of time
that a model evaluates inside its solver (:meth:`Excitation.force_expression`) or, for
sampled signals, ``None`` (the model then feeds the samples step by step:
:mod:`sensfw.models.drive`). :func:`make_excitation` rebuilds one from its
:meth:`~Excitation.to_dict`. (Over 400 lines: the five kinds share one interface and one
rule for what enters a run's hash, and are read together.)
"""

from __future__ import annotations

import hashlib
import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any, ClassVar

import numpy as np

from .errors import SignalError


def _check_sweep(f0: float, f1: float, duration: float, fs: float, tail: float = 0.0,
                 kind: str = "chirp") -> None:
    if not (f0 > 0 and f1 > f0):
        raise SignalError(f"chirp needs 0 < f0 < f1, got f0={f0}, f1={f1}")
    if not duration > 0:
        raise SignalError(f"chirp duration must be > 0, got {duration}")
    if not fs > 2 * f1:
        raise SignalError(f"sample rate fs={fs} Hz must exceed 2*f1={2 * f1} Hz (Nyquist)")
    if not tail >= 0:
        raise SignalError(f"{kind} tail must be >= 0, got {tail}")
    if round(duration * fs) < 2:
        raise SignalError(f"{kind} duration {duration:g} s holds {round(duration * fs)} "
                          f"sample(s) at fs={fs:g} Hz: it needs at least two")


def chirp_phase(t: np.ndarray, f0: float, f1: float, duration: float) -> np.ndarray:
    """Phase (rad) of the exponential sweep at times ``t`` (see module docstring)."""
    k = np.log(f1 / f0) / duration
    return 2.0 * np.pi * f0 / k * np.expm1(k * np.asarray(t, dtype=float))


def chirp_frequency(t: np.ndarray, f0: float, f1: float, duration: float) -> np.ndarray:
    """Instantaneous frequency ``f0 exp(k t)`` in Hz (Eq. 17 divided by 60)."""
    k = np.log(f1 / f0) / duration
    return f0 * np.exp(k * np.asarray(t, dtype=float))


def log_chirp(
    f0: float, f1: float, duration: float, fs: float, amplitude: float = 1.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exponential sine sweep from ``f0`` to ``f1`` Hz in ``duration`` s, sampled at ``fs``.

    Returns
    -------
    t : ndarray
        Sample times ``n / fs`` for ``n = 0 .. round(duration*fs) - 1``.
    force : ndarray
        ``amplitude * sin(phase(t))`` (sine, so the force starts at zero without a step).
    f_inst : ndarray
        Instantaneous (rotation) frequency ``f0 exp(k t)`` per sample, in Hz; the
        ``rpm(t)/60`` of Eq. 17 used to convert frequency to order (Eq. 14).
    """
    _check_sweep(f0, f1, duration, fs)
    n = round(duration * fs)
    t = np.arange(n) / fs
    return t, amplitude * np.sin(chirp_phase(t, f0, f1, duration)), chirp_frequency(
        t, f0, f1, duration
    )


class Excitation(ABC):
    """An excitation record: ``duration`` s of signal, then ``tail`` s of silence, at ``fs``.

    ``amplitude`` is the level (N, or V for a voltage): the peak of a sine, ``sqrt(2)`` x
    the RMS of noise. ``unit`` is ``"N"`` for a force; a voltage (``"V"``) drives a model
    through a gain (:func:`sensfw.models.drive.split_gain`).
    """

    kind: ClassVar[str] = "excitation"
    #: whether :meth:`force_expression` gives the signal in closed form
    closed_form: ClassVar[bool] = False
    fs: float
    amplitude: float
    duration: float
    tail: float

    @property
    def n_samples(self) -> int:
        return round((self.duration + self.tail) * self.fs)

    @property
    def unit(self) -> str:
        """``"N"`` for a force; ``"V"`` for a voltage that drives through a gain."""
        return getattr(self, "signal_unit", "N")

    def scaled(self, gain: float) -> Excitation:
        """The force of this signal through a gain (N per unit of the signal)."""
        return replace(self, amplitude=self.amplitude * float(gain), signal_unit="N")

    @property
    def sweep_end(self) -> float:
        """Time (s) at which the signal ends (a silent tail may follow)."""
        return self.duration

    def time(self) -> np.ndarray:
        return np.arange(self.n_samples) / self.fs

    @abstractmethod
    def force(self, t: np.ndarray | None = None) -> np.ndarray:
        """The signal at times ``t`` (default: every sample), zero in the tail."""

    def f_inst(self, t: np.ndarray | None = None) -> np.ndarray | None:
        """Instantaneous frequency (Hz) of a sweep or stepped sine; ``None`` otherwise."""
        return None

    def force_expression(self, ops, t):
        """The signal as an expression of time for a model's solver, or ``None`` when it
        only exists as samples."""
        return None

    def with_amplitude(self, amplitude: float) -> Excitation:
        return replace(self, amplitude=float(amplitude))

    def to_dict(self) -> dict[str, Any]:
        out = {"kind": self.kind, **asdict(self)}
        if out.get("signal_unit") == "N":
            del out["signal_unit"]  # a force, the default
        return out

    def identity(self) -> dict[str, Any]:
        """What identifies the excitation in a run's hash (:meth:`to_dict` by default)."""
        return self.to_dict()


@dataclass(frozen=True)
class Sweep(Excitation):
    """A sine sweep from ``f0`` to ``f1`` in ``duration`` s, then ``tail`` s of silence:
    ``amplitude sin(phase(t))``. Subclasses give the phase (numpy, and as an expression of
    time for a model's solver) and the instantaneous frequency."""

    closed_form: ClassVar[bool] = True
    f0: float = 50.0
    f1: float = 5000.0
    duration: float = 1.0
    fs: float = 20000.0
    amplitude: float = 1.0
    tail: float = 0.0
    signal_unit: str = "N"

    def __post_init__(self) -> None:
        _check_sweep(self.f0, self.f1, self.duration, self.fs, self.tail, self.kind)

    @abstractmethod
    def phase(self, t: np.ndarray) -> np.ndarray:
        """Phase (rad) at times ``t`` during the sweep."""

    @abstractmethod
    def phase_expression(self, ops, t):
        """The phase as an expression of time ``t`` (``ops``:
        :func:`sensfw.models.contact.symbolic_ops` for Exudyn, or numpy)."""

    @abstractmethod
    def frequency(self, t: np.ndarray) -> np.ndarray:
        """Instantaneous frequency (Hz) at times ``t`` during the sweep."""

    def force(self, t: np.ndarray | None = None) -> np.ndarray:
        t = self.time() if t is None else np.asarray(t, dtype=float)
        return np.where(t < self.duration, self.amplitude * np.sin(self.phase(t)), 0.0)

    def force_expression(self, ops, t):
        """The force as an expression of time ``t`` for a model's load function, zero after
        the sweep."""
        return ops.where(t < self.duration, self.amplitude * ops.sin(self.phase_expression(ops, t)),
                         0.0)

    def f_inst(self, t: np.ndarray | None = None) -> np.ndarray:
        """Instantaneous frequency; held at ``f1`` during the tail."""
        t = self.time() if t is None else np.asarray(t, dtype=float)
        return self.frequency(np.minimum(t, self.duration))


@dataclass(frozen=True)
class Chirp(Sweep):
    """The excitation of a study: a log chirp (the exponential sweep of the module docstring),
    optionally followed by a silent tail.

    ``tail`` seconds of zero force after the sweep let the last resonances ring down inside
    the record, so that FRF and order analysis see the whole response.
    """

    kind: ClassVar[str] = "log_chirp"

    @property
    def k(self) -> float:
        """Sweep rate ``ln(f1/f0)/T`` of Eq. 17, 1/s."""
        return float(np.log(self.f1 / self.f0) / self.duration)

    def phase(self, t):
        return chirp_phase(t, self.f0, self.f1, self.duration)

    def phase_expression(self, ops, t):
        k = self.k
        return (2.0 * math.pi * self.f0 / k) * (ops.exp(k * t) - 1.0)

    def frequency(self, t):
        return chirp_frequency(t, self.f0, self.f1, self.duration)

    def to_dict(self) -> dict[str, float]:
        out = asdict(self)  # no "kind": the paper's chirp keeps the run hashes it had
        if out["signal_unit"] == "N":
            del out["signal_unit"]
        return out


@dataclass(frozen=True)
class LinearSweep(Sweep):
    """Linear sine sweep: ``phase = 2 pi (f0 t + (f1 - f0) t^2 / (2 T))``, frequency
    ``f0 + (f1 - f0) t / T``."""

    kind: ClassVar[str] = "linear_sweep"

    def phase(self, t):
        rate = (self.f1 - self.f0) / self.duration
        return 2.0 * math.pi * (self.f0 * t + 0.5 * rate * t * t)

    def phase_expression(self, ops, t):
        return self.phase(t)

    def frequency(self, t):
        return self.f0 + (self.f1 - self.f0) * t / self.duration


@dataclass(frozen=True)
class SteppedSine(Excitation):
    """Stepped sine: ``steps`` frequencies from ``f0`` to ``f1`` (log spaced), or the given
    ``lines`` (Hz, e.g. an FRF record's; ``f0``, ``f1`` and ``steps`` then follow from
    them: :meth:`at`), each held for ``duration / steps`` s with a continuous phase (no
    force jumps), driven upwards or downwards (``direction``). The response at each step's
    frequency, in steady state: :func:`sensfw.signal.stepped.stepped_frf`."""

    kind: ClassVar[str] = "stepped_sine"
    f0: float = 50.0
    f1: float = 5000.0
    steps: int = 20
    duration: float = 1.0
    fs: float = 20000.0
    amplitude: float = 1.0
    tail: float = 0.0
    signal_unit: str = "N"
    lines: tuple[float, ...] = ()
    direction: str = "up"

    def __post_init__(self) -> None:
        _check_sweep(self.f0, self.f1, self.duration, self.fs, self.tail, self.kind)
        if self.steps < 1:
            raise SignalError(f"stepped sine needs at least one step, got {self.steps}")
        if self.duration / self.steps < 2 / self.fs:
            raise SignalError(f"stepped sine of {self.steps} steps in {self.duration:g} s "
                              f"dwells {self.duration / self.steps:.3g} s per step, less than "
                              f"two samples at fs={self.fs:g} Hz")
        if self.direction not in ("up", "down"):
            raise SignalError(f"stepped sine direction must be 'up' or 'down', got "
                              f"{self.direction!r}")
        if self.lines:
            lines = tuple(sorted(float(x) for x in self.lines))
            if len(lines) != self.steps or lines[0] != self.f0 or lines[-1] != self.f1:
                raise SignalError("stepped sine lines: give them with SteppedSine.at() (f0, "
                                  "f1 and steps follow from the lines)")
            object.__setattr__(self, "lines", lines)

    @classmethod
    def at(cls, lines, dwell: float, fs: float, amplitude: float = 1.0,
           direction: str = "up", tail: float = 0.0, signal_unit: str = "N") -> SteppedSine:
        """A stepped sine on the frequencies ``lines`` (Hz, any order; driven in
        ``direction``), ``dwell`` s per step."""
        f = sorted(float(x) for x in lines)
        if len(f) < 2 or len(set(f)) != len(f) or f[0] <= 0:
            raise SignalError("a stepped sine needs two or more distinct positive "
                              "frequencies")
        return cls(f0=f[0], f1=f[-1], steps=len(f), duration=dwell * len(f), fs=fs,
                   amplitude=amplitude, tail=tail, signal_unit=signal_unit, lines=tuple(f),
                   direction=direction)

    @property
    def dwell(self) -> float:
        """Seconds per step."""
        return self.duration / self.steps

    def frequencies(self) -> np.ndarray:
        """The step frequencies in the order they are driven."""
        f = np.array(self.lines) if self.lines else np.geomspace(self.f0, self.f1, self.steps)
        return f if self.direction == "up" else f[::-1]

    def f_inst(self, t: np.ndarray | None = None) -> np.ndarray:
        t = self.time() if t is None else np.asarray(t, dtype=float)
        i = np.clip((t / self.duration * self.steps).astype(int), 0, self.steps - 1)
        return self.frequencies()[i]

    def force(self, t: np.ndarray | None = None) -> np.ndarray:
        t = self.time() if t is None else np.asarray(t, dtype=float)
        dwell = self.dwell
        f = self.frequencies()
        start_phase = np.concatenate([[0.0], np.cumsum(2 * np.pi * f * dwell)])[:-1]
        i = np.clip((t / dwell).astype(int), 0, self.steps - 1)
        phase = start_phase[i] + 2 * np.pi * f[i] * (t - i * dwell)
        return np.where(t < self.duration, self.amplitude * np.sin(phase), 0.0)

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        if not self.lines:  # runs of the log-spaced steps keep their hashes
            del out["lines"]
        else:
            out["lines"] = list(self.lines)
        if self.direction == "up":
            del out["direction"]
        return out


@dataclass(frozen=True)
class RandomForce(Excitation):
    """Band-limited Gaussian noise with a flat spectrum in ``[f0, f1]`` (seeded; the same
    seed gives the same record). ``amplitude`` is ``sqrt(2)`` x its RMS (the level of a sine
    of the same RMS)."""

    kind: ClassVar[str] = "random"
    f0: float = 50.0
    f1: float = 5000.0
    duration: float = 1.0
    fs: float = 20000.0
    amplitude: float = 1.0
    tail: float = 0.0
    signal_unit: str = "N"
    seed: int = 0

    def __post_init__(self) -> None:
        _check_sweep(self.f0, self.f1, self.duration, self.fs, self.tail, self.kind)
        n = round(self.duration * self.fs)
        f = np.fft.rfftfreq(n, 1 / self.fs)
        if not np.any((f >= self.f0) & (f <= self.f1)):
            raise SignalError(f"random band [{self.f0:g}, {self.f1:g}] Hz holds no frequency "
                              f"line of a {self.duration:g} s record (lines "
                              f"{self.fs / n:.4g} Hz apart): widen the band or lengthen the "
                              "record")

    def _record(self) -> np.ndarray:
        n = round(self.duration * self.fs)
        rng = np.random.default_rng(self.seed)
        spec = rng.standard_normal(n // 2 + 1) + 1j * rng.standard_normal(n // 2 + 1)
        f = np.fft.rfftfreq(n, 1 / self.fs)
        spec[(f < self.f0) | (f > self.f1)] = 0.0
        x = np.fft.irfft(spec, n)
        return x * (self.amplitude / math.sqrt(2) / np.sqrt(np.mean(x * x)))

    def force(self, t: np.ndarray | None = None) -> np.ndarray:
        rec = np.concatenate([self._record(), np.zeros(self.n_samples - round(self.duration
                                                                              * self.fs))])
        if t is None:
            return rec
        return np.interp(np.asarray(t, float), np.arange(len(rec)) / self.fs, rec,
                         right=0.0)


@dataclass(frozen=True, eq=False)
class SampledForce(Excitation):
    """A recorded excitation (measured force, or amplifier voltage with ``unit="V"``) that
    drives a model sample by sample.

    ``sweep`` optionally describes the sweep the record follows (``{"kind": "log_chirp" |
    "linear_sweep", "f0", "f1", "t_start", "t_end"}``, e.g. from
    :func:`sensfw.signal.sweep.estimate_sweep`, or ``{"kind": "stepped_sine", "starts",
    "frequencies", "t_end"}`` from :func:`sensfw.signal.stepped.detect_steps`), which gives
    the instantaneous frequency for order or per-step analysis; without it the record is
    treated as broadband. ``amplitude`` is the
    level the record was measured at (it does not rescale the samples; :meth:`scaled` does).
    """

    kind: ClassVar[str] = "sampled"
    samples: np.ndarray = field(default_factory=lambda: np.zeros(0))
    fs: float = 20000.0
    amplitude: float = 1.0
    signal_unit: str = "N"
    sweep: Mapping[str, Any] | None = None
    gain: float = 1.0

    def __post_init__(self) -> None:
        x = np.asarray(self.samples, dtype=float)
        if x.ndim != 1 or len(x) < 2:
            raise SignalError("a sampled excitation needs a 1-D record of at least 2 samples")
        if not np.all(np.isfinite(x)):
            raise SignalError("a sampled excitation contains NaN or inf")
        x.setflags(write=False)
        object.__setattr__(self, "samples", x)

    @property
    def duration(self) -> float:
        return len(self.samples) / self.fs

    @property
    def tail(self) -> float:
        return 0.0

    @property
    def n_samples(self) -> int:
        return len(self.samples)

    @property
    def unit(self) -> str:
        return self.signal_unit

    @property
    def sweep_end(self) -> float:
        return float(self.sweep["t_end"]) if self.sweep else self.duration

    def scaled(self, gain: float) -> SampledForce:
        """The record times ``gain`` (e.g. N/V of a shaker driven by a voltage)."""
        return replace(self, gain=self.gain * float(gain), signal_unit="N")

    def with_amplitude(self, amplitude: float) -> SampledForce:
        return replace(self, samples=self.samples * (amplitude / self.amplitude),
                       amplitude=float(amplitude))

    def force(self, t: np.ndarray | None = None) -> np.ndarray:
        x = self.gain * self.samples
        if t is None:
            return np.array(x)
        return np.interp(np.asarray(t, float), np.arange(len(x)) / self.fs, x, right=0.0)

    def f_inst(self, t: np.ndarray | None = None) -> np.ndarray | None:
        if not self.sweep:
            return None
        t = self.time() if t is None else np.asarray(t, dtype=float)
        s = self.sweep
        if s["kind"] == "stepped_sine":  # step i holds frequencies[i] from starts[i] on
            i = np.searchsorted(np.asarray(s["starts"], float), t, side="right") - 1
            return np.asarray(s["frequencies"], float)[np.clip(i, 0, len(s["starts"]) - 1)]
        t0, t1 = float(s["t_start"]), float(s["t_end"])
        u = np.clip(t - t0, 0.0, t1 - t0)
        if s["kind"] == "linear_sweep":
            return s["f0"] + (s["f1"] - s["f0"]) * u / (t1 - t0)
        return s["f0"] * (s["f1"] / s["f0"]) ** (u / (t1 - t0))

    def digest(self) -> str:
        return hashlib.sha256(np.ascontiguousarray(self.samples).tobytes()).hexdigest()[:24]

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "samples": self.samples, "fs": self.fs,
                "amplitude": self.amplitude, "signal_unit": self.signal_unit,
                "sweep": dict(self.sweep) if self.sweep else None, "gain": self.gain}

    def identity(self) -> dict[str, Any]:
        out = self.to_dict()
        out["samples"] = {"sha256": self.digest(), "n": len(self.samples)}
        return out


KINDS: dict[str, type[Excitation]] = {c.kind: c for c in (Chirp, LinearSweep, SteppedSine,
                                                          RandomForce, SampledForce)}


def make_excitation(spec: Mapping[str, Any] | Excitation) -> Excitation:
    """An excitation from its :meth:`~Excitation.to_dict` (no ``kind``: the log chirp)."""
    if isinstance(spec, Excitation):
        return spec
    spec = dict(spec)
    kind = spec.pop("kind", "log_chirp")
    try:
        cls = KINDS[kind]
    except KeyError:
        raise SignalError(f"unknown excitation kind {kind!r}; known: {', '.join(KINDS)}") \
            from None
    known = {f.name for f in fields(cls)}
    unknown = set(spec) - known
    if unknown:
        raise SignalError(f"excitation {kind!r}: unknown field(s) {', '.join(sorted(unknown))};"
                          f" known: {', '.join(sorted(known))}")
    return cls(**spec)


def sweep_kinds() -> Sequence[str]:
    return ("log_chirp", "linear_sweep", "stepped_sine")
