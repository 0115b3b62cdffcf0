"""What sweep a recorded excitation is: kind, start and end frequency, start and end time.

A rig's force is never the study's clean chirp: it carries noise, a DC offset, an amplitude
that drifts near resonances (shaker-structure interaction), a delay after the trigger and a
silent tail. :func:`estimate_sweep` fits the phase of the sweep models to the analytic signal
of the band-passed record, which is insensitive to all of these:

1. the DC offset and out-of-band noise are removed by a zero-phase band-pass;
2. the active part is where the smoothed Hilbert envelope exceeds half its median (a
   +-20 % drift stays far above that; a silent tail or a pre-trigger pause falls below);
3. the unwrapped phase ``phi(t)`` over the inner 90 % of the active part is fitted by the
   exponential-sweep model ``phi0 + B (exp(k tau) - 1)`` (Eq. 7 in the form of
   :mod:`sensfw.excitation`; ``B`` and ``phi0`` linear, ``k`` by a bounded scalar search,
   once for ``k > 0`` and once for ``k < 0``: a sweep up or down) and
   by the linear-sweep model ``phi0 + 2 pi (f_a tau + r tau^2 / 2)`` (linear least
   squares); the smaller phase residual decides the kind. Phase noise from additive noise
   of relative level ``s`` is about ``s`` rad per sample and averages down over thousands of
   samples, so the frequency law comes out far more precisely than from the envelope;
4. the start is refined to the nearest zero crossing of the fitted sweep (generators start a
   sine sweep at zero force to avoid a step), so ``f0 = f(t_start)`` does not inherit the
   envelope's rise time at low frequency.

A record whose phase follows neither model (residual above ``max_residual`` rad) is
classified ``"stepped_sine"`` when its instantaneous frequency dwells on a few levels, and
``"random"`` (broadband) otherwise.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import butter, hilbert, sosfiltfilt

from ..errors import SignalError
from ._checks import as_signal, check_fs


@dataclass(frozen=True)
class SweepEstimate:
    """The estimated excitation (times in s from the record's start, frequencies in Hz).

    ``residual`` is the RMS phase residual (rad) of the chosen sweep model, ``amplitude``
    the median envelope of the active part (the level of a sine), ``drift`` the largest
    relative deviation of the slowly varying envelope from that median, ``offset`` the
    record's DC offset.
    """

    kind: str
    f0: float
    f1: float
    t_start: float
    t_end: float
    residual: float
    amplitude: float
    drift: float
    offset: float
    notes: list[str] = field(default_factory=list)

    @property
    def duration(self) -> float:
        return self.t_end - self.t_start

    @property
    def is_sweep(self) -> bool:
        return self.kind in ("log_chirp", "linear_sweep")

    def frequency(self, t: np.ndarray) -> np.ndarray:
        """Instantaneous frequency of the fitted sweep at times ``t`` (held outside)."""
        u = np.clip(np.asarray(t, float) - self.t_start, 0.0, self.duration)
        if self.kind == "linear_sweep":
            return self.f0 + (self.f1 - self.f0) * u / self.duration
        return self.f0 * (self.f1 / self.f0) ** (u / self.duration)

    def to_dict(self) -> dict:
        out = asdict(self)
        out["duration"] = self.duration
        return out


def _envelope(x: np.ndarray, fs: float, smooth: float) -> tuple[np.ndarray, np.ndarray]:
    z = hilbert(x)
    n = max(1, round(smooth * fs))
    env = np.convolve(np.abs(z), np.ones(n) / n, mode="same")
    return z, env


def _active(env: np.ndarray, fs: float, min_gap: float = 0.005) -> tuple[int, int]:
    """First and last sample of the longest run where the envelope exceeds half the median
    of its loud part (gaps shorter than ``min_gap`` s bridged)."""
    loud = env > 0.2 * np.max(env)
    level = 0.5 * np.median(env[loud])
    on = env > level
    idx = np.flatnonzero(on)
    if len(idx) == 0:
        return 0, len(env) - 1
    gaps = np.flatnonzero(np.diff(idx) > max(1, round(min_gap * fs)))
    starts = np.concatenate([[idx[0]], idx[gaps + 1]])
    ends = np.concatenate([idx[gaps], [idx[-1]]])
    i = int(np.argmax(ends - starts))
    return int(starts[i]), int(ends[i])


def _crossing(env: np.ndarray, i: int, level: float, rising: bool) -> float:
    """Sub-sample position where the envelope crosses ``level`` next to sample ``i``."""
    j = i - 1 if rising else i + 1
    if j < 0 or j >= len(env) or env[j] == env[i]:
        return float(i)
    return float(j + (level - env[j]) / (env[i] - env[j]) * (i - j))


def _fit_log(tau: np.ndarray, phi: np.ndarray, k_max: float, sign: float = 1.0
             ) -> tuple[float, float, float, float]:
    """(k, B, phi0, rms residual) of ``phi0 + B (exp(k tau) - 1)`` with ``k`` of the sign
    ``sign`` (> 0: an upward sweep, < 0: a downward one)."""

    def solve(k):
        g = np.expm1(k * tau) / k if abs(k) > 1e-9 else tau
        A = np.column_stack([np.ones_like(tau), g])
        coef, *_ = np.linalg.lstsq(A, phi, rcond=None)
        r = phi - A @ coef
        return float(np.sqrt(np.mean(r * r))), coef

    res = minimize_scalar(lambda lk: solve(math.copysign(math.exp(lk), sign))[0],
                          bounds=(math.log(1e-4), math.log(k_max)), method="bounded",
                          options={"xatol": 1e-10})
    k = math.copysign(math.exp(res.x), sign)
    err, (phi0, bk) = solve(k)  # the fit's coefficient is B k (= 2 pi f at tau = 0)
    return k, float(bk) / k, float(phi0), err


def _fit_linear(tau: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, float]:
    A = np.column_stack([np.ones_like(tau), tau, 0.5 * tau * tau])
    coef, *_ = np.linalg.lstsq(A, phi, rcond=None)
    r = phi - A @ coef
    return coef, float(np.sqrt(np.mean(r * r)))


def _dwells(phase: np.ndarray, fs: float, window: float = 0.01) -> int:
    """Number of distinct frequency levels a stepped sine dwells on (0 if it does not):
    the frequency of each ``window`` is the slope of a line through its unwrapped phase."""
    n = max(8, round(window * fs))
    if len(phase) < 10 * n:
        return 0
    t = np.arange(n) / fs
    A = np.column_stack([np.ones(n), t])
    f = np.array([np.linalg.lstsq(A, phase[i:i + n], rcond=None)[0][1] / (2 * np.pi)
                  for i in range(0, len(phase) - n, n)])
    if np.any(f <= 0):
        return 0
    steady = np.abs(np.diff(np.log(f))) < 0.01
    if steady.mean() < 0.6:
        return 0
    # dwells: runs of at least two steady window pairs
    edges = np.diff(np.concatenate([[0], steady.astype(int), [0]]))
    runs = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    count = int(np.sum(runs >= 2))
    return count if count >= 3 else 0


def estimate_sweep(x: np.ndarray, fs: float, band: tuple[float, float] | None = None,
                   max_residual: float = 0.5) -> SweepEstimate:
    """Kind, frequencies and times of the sweep in the record ``x`` sampled at ``fs``.

    Parameters
    ----------
    x : the excitation record (force or voltage).
    fs : sample rate (Hz).
    band : expected frequency range (Hz); the record is band-passed to
        ``[band[0] / 2, min(2 band[1], 0.45 fs)]`` first (default: 0.5 Hz to 0.45 fs).
    max_residual : RMS phase residual (rad) above which the record is not a sweep.

    See the module docstring for the method. A silent or broadband record comes back with
    ``kind = "silent"`` or ``"random"``; a :class:`~sensfw.errors.SignalError` means a
    record that cannot be read at all (NaN or inf, a band above 0.45 ``fs``, too short for
    the band-pass).
    """
    x = as_signal(x, "x")
    fs = check_fs(fs)
    offset = float(np.median(x))
    lo = 0.5 if band is None else max(0.5, band[0] / 2)
    hi = 0.45 * fs if band is None else min(2 * band[1], 0.45 * fs)
    if not lo < hi:
        raise SignalError(f"the band-pass {lo:g}-{hi:g} Hz is empty: band {band} Hz is not "
                          f"below 0.45 fs = {0.45 * fs:g} Hz")
    sos = butter(4, [lo, hi], btype="bandpass", fs=fs, output="sos")
    try:
        y = sosfiltfilt(sos, x - offset)
    except ValueError as err:  # scipy: the record is shorter than the filter's padding
        raise SignalError(f"x has {len(x)} samples, too few for the band-pass: {err}"
                          ) from None
    if not np.any(y):
        return SweepEstimate("silent", math.nan, math.nan, 0.0, 0.0, math.inf, 0.0, 0.0,
                             offset)
    z, env = _envelope(y, fs, smooth=0.002)
    i0, i1 = _active(env, fs)
    level = 0.5 * np.median(env[i0:i1 + 1])
    t_start = _crossing(env, i0, level, rising=True) / fs
    t_end = _crossing(env, i1, level, rising=False) / fs
    amplitude = float(np.median(env[i0:i1 + 1]))
    slow = np.convolve(env[i0:i1 + 1], np.ones(max(1, round(0.02 * fs))) /
                       max(1, round(0.02 * fs)), mode="valid")
    drift = float(np.max(np.abs(slow / amplitude - 1))) if len(slow) else 0.0
    cut = max(1, int(0.05 * (i1 - i0)))
    idx = np.arange(i0 + cut, i1 - cut)
    if len(idx) < 50:
        return SweepEstimate("random", math.nan, math.nan, t_start, t_end, math.inf,
                             amplitude, drift, offset, ["active part too short to fit"])
    phi = np.unwrap(np.angle(z[idx]))
    tau = idx / fs - t_start
    if phi[-1] < phi[0]:  # a sweep read backwards: conjugate
        phi = -phi
    k_max = 50.0 / max(t_end - t_start, 1e-6)
    k, b, phi0, res_log = min((_fit_log(tau, phi, k_max, sign) for sign in (1.0, -1.0)),
                              key=lambda fit: fit[3])  # up or down
    lin, res_lin = _fit_linear(tau, phi)
    duration = t_end - t_start
    if min(res_log, res_lin) > max_residual:
        n = _dwells(np.unwrap(np.angle(z[i0:i1 + 1])), fs)
        kind = "stepped_sine" if n else "random"
        notes = [f"{n} frequency steps"] if n else ["no sweep: broadband"]
        return SweepEstimate(kind, math.nan, math.nan, t_start, t_end,
                             min(res_log, res_lin), amplitude, drift, offset, notes)
    if res_log <= res_lin:
        kind, residual = "log_chirp", res_log

        def phase(tt):
            return phi0 + b * np.expm1(k * tt)

        def freq(tt):
            return b * k * np.exp(k * tt) / (2 * np.pi)
    else:
        kind, residual = "linear_sweep", res_lin

        def phase(tt):
            return lin[0] + lin[1] * tt + 0.5 * lin[2] * tt * tt

        def freq(tt):
            return (lin[1] + lin[2] * tt) / (2 * np.pi)
    # the sine starts at zero force: the analytic phase of sin(psi) is psi - pi/2, so the
    # start is where phase + pi/2 is a multiple of pi; take the one nearest the envelope's
    # start, on the rising branch of the fitted law (f > 0)
    f_a = max(float(freq(0.0)), 1e-9)
    grid = np.linspace(-0.5 / f_a, 0.5 / f_a, 4001)
    grid = grid[freq(grid) > 0.2 * f_a]
    g = (phase(grid) + np.pi / 2) / np.pi
    cross = np.flatnonzero(np.floor(g[1:]) != np.floor(g[:-1]))
    notes, shift = [], 0.0
    if len(cross):
        j = cross[np.argmin(np.abs(grid[cross]))]
        level = np.floor(g[j + 1])
        shift = float(grid[j] + (level - g[j]) / (g[j + 1] - g[j]) * (grid[j + 1] - grid[j]))
        notes.append(f"start refined to the sweep's zero crossing ({shift * 1e3:+.3f} ms)")
    f0, f1 = float(freq(shift)), float(freq(duration))
    return SweepEstimate(kind, f0, f1, t_start + shift, t_end, residual, amplitude, drift,
                         offset, notes)
