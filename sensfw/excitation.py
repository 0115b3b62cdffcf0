"""The logarithmic (exponential) chirp excitation of the paper, Sect. 2.3.

Eq. 7 as printed, ``A0 cos(2 pi f0 t (f1/f0)^(t/T))``, does not end at ``f1``: its
instantaneous frequency ``d(phase)/dt / 2pi = f0 (f1/f0)^(t/T) (1 + t ln(f1/f0)/T)`` reaches
``f1 (1 + ln(f1/f0))`` at ``t = T``. We use the standard exponential sweep (Farina 2000)

    phase(t) = 2 pi f0 T / ln(f1/f0) * ((f1/f0)^(t/T) - 1),

whose instantaneous frequency is ``f0 exp(k t)`` with ``k = ln(f1/f0)/T``, exactly the
``rpm(t)/60`` of Eq. 17 that the order analysis needs.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .errors import SignalError


def _check_sweep(f0: float, f1: float, duration: float, fs: float) -> None:
    if not (f0 > 0 and f1 > f0):
        raise SignalError(f"chirp needs 0 < f0 < f1, got f0={f0}, f1={f1}")
    if not duration > 0:
        raise SignalError(f"chirp duration must be > 0, got {duration}")
    if not fs > 2 * f1:
        raise SignalError(f"sample rate fs={fs} Hz must exceed 2*f1={2 * f1} Hz (Nyquist)")


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


@dataclass(frozen=True)
class Chirp:
    """The excitation of a study: a log chirp, optionally followed by a silent tail.

    ``tail`` seconds of zero force after the sweep let the last resonances ring down inside
    the record, so that FRF and order analysis see the whole response.
    """

    f0: float = 50.0
    f1: float = 5000.0
    duration: float = 1.0
    fs: float = 20000.0
    amplitude: float = 1.0
    tail: float = 0.0

    def __post_init__(self) -> None:
        _check_sweep(self.f0, self.f1, self.duration, self.fs)
        if self.tail < 0:
            raise SignalError(f"chirp tail must be >= 0, got {self.tail}")

    @property
    def k(self) -> float:
        """Sweep rate ``ln(f1/f0)/T`` of Eq. 17, 1/s."""
        return float(np.log(self.f1 / self.f0) / self.duration)

    @property
    def n_samples(self) -> int:
        return round((self.duration + self.tail) * self.fs)

    def time(self) -> np.ndarray:
        return np.arange(self.n_samples) / self.fs

    def force(self, t: np.ndarray | None = None) -> np.ndarray:
        t = self.time() if t is None else np.asarray(t, dtype=float)
        f = self.amplitude * np.sin(chirp_phase(t, self.f0, self.f1, self.duration))
        return np.where(t < self.duration, f, 0.0)

    def force_expression(self, ops, t):
        """The force as an expression of time ``t`` for a model's load function (``ops``:
        :func:`sensfw.models.contact.symbolic_ops` for Exudyn, or numpy), zero after the
        sweep."""
        k = self.k
        phase = (2.0 * math.pi * self.f0 / k) * (ops.exp(k * t) - 1.0)
        return ops.where(t < self.duration, self.amplitude * ops.sin(phase), 0.0)

    def f_inst(self, t: np.ndarray | None = None) -> np.ndarray:
        """Instantaneous frequency; held at ``f1`` during the tail."""
        t = self.time() if t is None else np.asarray(t, dtype=float)
        return chirp_frequency(np.minimum(t, self.duration), self.f0, self.f1, self.duration)

    def to_dict(self) -> dict[str, float]:
        return asdict(self)
