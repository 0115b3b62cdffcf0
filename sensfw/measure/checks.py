"""Checks of a measurement against a study, and alignment with the simulation.

Each check raises :class:`~sensfw.errors.MeasurementError` naming the file and channel:
missing or misnamed channel (with the closest names), clipping (flat tops at full scale), a
record shorter than the chirp, and a force that does not look like the study's chirp
(reported with the estimated f0, f1 and duration). :func:`align` resamples to the study's
rate and removes the delay between the measured force and the ideal chirp.
"""

from __future__ import annotations

import difflib
from dataclasses import replace

import numpy as np
from scipy.signal import correlate, hilbert, resample_poly

from ..errors import MeasurementError
from ..excitation import Chirp
from ..models.base import Signals
from .io import Measurement


def require_channels(meas: Measurement, channels: list[str]) -> None:
    have = list(meas.signals.channels)
    for ch in channels:
        if ch not in have:
            close = difflib.get_close_matches(ch, have, n=1, cutoff=0.5)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise MeasurementError(meas.file, f"missing channel (file has "
                                              f"{', '.join(['force', *have])}){hint}", ch)


def clipped_runs(x: np.ndarray, min_run: int = 4) -> int:
    """Number of flat runs of at least ``min_run`` equal samples at the signal's extremes."""
    a = np.max(np.abs(x))
    if a == 0:
        return 0
    top = np.abs(x) >= 0.999 * a
    same = np.concatenate([[False], np.diff(x) == 0])
    flat = top & same
    runs, count = 0, 0
    for v in flat:
        count = count + 1 if v else 0
        if count == min_run - 1:
            runs += 1
    return runs


def check_clipping(meas: Measurement) -> None:
    for name, x in [("force", meas.signals.force), *meas.signals.channels.items()]:
        n = clipped_runs(x)
        if n:
            raise MeasurementError(meas.file, f"clipped: {n} flat top(s) at full scale "
                                              f"(+-{np.max(np.abs(x)):.4g}); reduce the "
                                              f"level or the sensor range", name)


def estimate_sweep(force: np.ndarray, fs: float) -> tuple[float, float, float]:
    """Estimated (f0, f1, duration) of an exponential sweep in ``force``.

    The phase of the analytic signal gives the instantaneous frequency, whose logarithm is
    linear in time for a log chirp (Eq. 17). The sweep is where the envelope exceeds half its
    median over the loud part; a robust (Theil-Sen) line through log f(t) on its inner 96 %
    gives f0 and f1 at its ends.
    """
    from scipy.stats import theilslopes

    z = hilbert(force - np.mean(force))
    env = np.abs(z)
    loud = env > 0.1 * np.max(env)
    if loud.sum() < 20:
        return float("nan"), float("nan"), 0.0
    on = np.flatnonzero(env > 0.5 * np.median(env[loud]))
    i0, i1 = on[0], on[-1]
    duration = (i1 - i0 + 1) / fs
    phase = np.unwrap(np.angle(z))
    finst = np.gradient(phase) * fs / (2 * np.pi)
    cut = int(0.02 * (i1 - i0))
    idx = np.arange(i0 + cut, i1 - cut)
    idx = idx[finst[idx] > 0]
    if len(idx) < 20:
        return float("nan"), float("nan"), duration
    idx = idx[:: max(1, len(idx) // 2000)]
    slope, intercept, *_ = theilslopes(np.log(finst[idx]), idx / fs)
    f0 = float(np.exp(intercept + slope * i0 / fs))
    f1 = float(np.exp(intercept + slope * i1 / fs))
    return f0, f1, float(duration)


def check_chirp(meas: Measurement, excitation: Chirp, tolerance: float = 0.15) -> None:
    sig = meas.signals
    length = len(sig.force) / sig.fs
    if length < excitation.duration * (1 - 1e-6):
        raise MeasurementError(meas.file, f"record is {length:.4g} s long, shorter than the "
                                          f"{excitation.duration:g} s chirp", "force")
    f0, f1, dur = estimate_sweep(sig.force, sig.fs)
    ok = (np.isfinite(f0) and np.isfinite(f1)
          and abs(np.log(f0 / excitation.f0)) < np.log1p(tolerance) * 3
          and abs(np.log(f1 / excitation.f1)) < np.log1p(tolerance)
          and abs(dur / excitation.duration - 1) < tolerance)
    if not ok:
        raise MeasurementError(meas.file, f"force does not look like the study's chirp "
                                          f"({excitation.f0:g} -> {excitation.f1:g} Hz in "
                                          f"{excitation.duration:g} s): estimated f0 = {f0:.4g}"
                                          f" Hz, f1 = {f1:.4g} Hz, duration = {dur:.4g} s",
                               "force")


def resample(sig: Signals, fs: float) -> Signals:
    """Polyphase resampling of every channel to ``fs`` (rational approximation)."""
    from fractions import Fraction

    frac = Fraction(fs / sig.fs).limit_denominator(1000)
    up, down = frac.numerator, frac.denominator
    force = resample_poly(sig.force, up, down)
    channels = {k: resample_poly(v, up, down) for k, v in sig.channels.items()}
    n = len(force)
    return Signals(t=np.arange(n) / fs, force=force, channels=channels, fs=fs,
                   units=dict(sig.units), meta=dict(sig.meta))


def estimate_delay(measured: np.ndarray, reference: np.ndarray, fs: float,
                   max_delay: float = 0.05) -> float:
    """Delay (s) of ``measured`` behind ``reference`` from the peak of their
    cross-correlation, refined to a fraction of a sample by a parabola through the peak."""
    n = min(len(measured), len(reference))
    c = correlate(measured[:n], reference[:n], mode="full", method="fft")
    lags = np.arange(-n + 1, n)
    window = np.abs(lags) <= int(max_delay * fs)
    c = np.where(window, c, -np.inf)
    i = int(np.argmax(c))
    if 0 < i < len(c) - 1 and np.isfinite(c[i - 1]) and np.isfinite(c[i + 1]):
        denom = c[i - 1] - 2 * c[i] + c[i + 1]
        frac = 0.5 * (c[i - 1] - c[i + 1]) / denom if denom != 0 else 0.0
    else:
        frac = 0.0
    return float((lags[i] + frac) / fs)


def align(meas: Measurement, excitation: Chirp) -> Measurement:
    """Resample to the study's rate, remove the delay against the ideal chirp force and cut
    to the study's record length (``duration + tail``)."""
    sig = meas.signals
    notes = list(meas.notes)
    if abs(sig.fs - excitation.fs) > 1e-6 * excitation.fs:
        notes.append(f"resampled from {sig.fs:g} Hz to {excitation.fs:g} Hz")
        sig = resample(sig, excitation.fs)
    ideal = excitation.force()
    delay = estimate_delay(sig.force, ideal, sig.fs)
    shift = round(delay * sig.fs)
    if shift:
        notes.append(f"removed a delay of {delay * 1e3:.3f} ms ({shift} samples)")
    n = excitation.n_samples

    def cut(x):
        x = x[shift:] if shift >= 0 else np.concatenate([np.zeros(-shift), x])
        if len(x) < n:
            x = np.concatenate([x, np.zeros(n - len(x))])
        return x[:n]

    t = excitation.time()
    aligned = Signals(t=t, force=cut(sig.force), channels={k: cut(v) for k, v in
                                                           sig.channels.items()},
                      fs=excitation.fs, f_inst=excitation.f_inst(t), units=dict(sig.units),
                      meta={**sig.meta, "delay_s": delay}, sweep_end=excitation.duration)
    return replace(meas, signals=aligned, notes=notes)


def prepare(meas: Measurement, excitation: Chirp, channels: list[str]) -> Measurement:
    """All checks, then alignment: what every measurement command does first."""
    require_channels(meas, channels)
    check_clipping(meas)
    check_chirp(meas, excitation)
    return align(meas, excitation)
