"""What a linear FRF does not show: harmonic order amplitudes of a swept record (Eqs. 12-17)
with their noise floor, and the DC offset with its standard error.
"""

from __future__ import annotations

import numpy as np

from ..models.base import Signals
from ..signal import harmonic_amplitudes
from .bands import local_fit_noise_sigma


def _part(fr: np.ndarray, f_max: float) -> int:
    """Samples of the sweep before its instantaneous frequency first passes ``f_max``."""
    return int(np.searchsorted(np.maximum.accumulate(fr), f_max))


def harmonics(sig: Signals, channel: str, orders: tuple[int, ...] = (2, 3),
              f_max: float | None = None) -> dict[int, float]:
    """RMS order amplitudes ``P_1`` and ``P_k`` (Eqs. 12-17) of a swept record, each ratio
    ``P_k / P_1`` over the part of the sweep where order ``k`` stays below 0.45 fs (so H3 is
    measured even where the whole sweep only allows order 2) and below ``f_max`` (the
    highest frequency the compared record holds, :func:`~sensfw.measure.bands.usable_limit`:
    a record resampled from a lower rate has nothing above it, and its orders read there
    would be the resampling filter's; both sides of a comparison take the same). Returns
    ``{1: P_1, k: P_1(part) * ratio_k}``, ``P_1`` over the whole sweep or, with an
    ``f_max`` below 0.45 fs, its part below ``f_max``; empty without a sweep (random
    excitation)."""
    if sig.f_inst is None:
        return {}
    s = sig.sweep()
    x, fr = s.channel(channel), np.asarray(s.f_inst, float)
    top = 0.45 * s.fs if f_max is None else min(0.45 * s.fs, f_max)
    n1 = len(fr) if top >= 0.45 * s.fs else _part(fr, top)
    out = harmonic_amplitudes(x[:n1], s.fs, fr[:n1], harmonics=(1,))
    for k in orders:
        n = _part(fr, top / k)
        if n < 0.1 * len(fr):
            continue
        part = harmonic_amplitudes(x[:n], s.fs, fr[:n], harmonics=(1, k))
        if part[1] > 0:
            out[k] = out[1] * part[k] / part[1]
    return out


def harmonic_floor(sig: Signals, channel: str, orders: tuple[int, ...] = (2, 3),
                   seed: int = 0, f_max: float | None = None) -> dict[int, float]:
    """Noise floor of each ratio ``P_k / P_1`` of :func:`harmonics`: the order amplitude
    that the record's output noise alone gives at order ``k``, over the same part of the
    sweep, divided by that part's ``P_1``.

    The noise is white with the standard deviation of
    :func:`~sensfw.measure.bands.local_fit_noise_sigma`, an upper bound kept on purpose:
    the signature classes' thresholds (:data:`sensfw.measure.signatures.THRESHOLDS`,
    ``floor_db``) were set against it, and diagnosis prunes candidates by those classes.
    With the short-time spectrum's estimate (:func:`~sensfw.measure.bands.noise_sigma`,
    1.1-1.2 times the noise where this reads 1.6) the floors fall, even harmonics count at
    more levels, and in recovery seeds 2041 and 2044 (a friction at slide bearing 1, a
    cubic stiffness at the crankshaft) the truth was left out (``bench/RECOVERY.md``, stop
    63). Its order amplitude is computed on a realisation of the noise (the order spectrum
    averages over frames, so one realisation varies by a few per cent). Noise adds in
    power, ``P_k^2 ~ P_k,true^2 + P_k,noise^2``: a measured ratio within a few dB of its
    floor says little about the harmonic. (The spectrum between the orders is no noise
    estimate for a fast sweep: the ring-down of each resonance smears across orders
    there.)"""
    if sig.f_inst is None:
        return {}
    sigma = local_fit_noise_sigma(sig, channel)
    s = sig.sweep()
    x, fr = s.channel(channel), np.asarray(s.f_inst, float)
    noise = sigma * np.random.default_rng(seed).standard_normal(len(x))
    top = 0.45 * s.fs if f_max is None else min(0.45 * s.fs, f_max)
    out = {}
    for k in orders:
        n = _part(fr, top / k)
        if n < 0.1 * len(fr):
            continue
        p1 = harmonic_amplitudes(x[:n], s.fs, fr[:n], harmonics=(1,))[1]
        pk = harmonic_amplitudes(noise[:n], s.fs, fr[:n], harmonics=(k,))[k]
        if p1 > 0:
            out[k] = float(pk / p1)
    return out


def dc_offset(sig: Signals, channel: str) -> float:
    """Mean of the output over the sweep (an asymmetric contact or a preload can shift it;
    for an accelerometer mostly the sensor's own offset)."""
    return float(np.mean(sig.sweep().channel(channel)))


def dc_standard_error(sig: Signals, channel: str) -> float:
    """Standard error of :func:`dc_offset` from the output noise: ``sigma / sqrt(n)`` for
    the mean over the sweep's ``n`` samples (the upper bound
    :func:`~sensfw.measure.bands.local_fit_noise_sigma`, as for :func:`harmonic_floor`:
    the DC difference in these errors is a signature class)."""
    return local_fit_noise_sigma(sig, channel) / float(np.sqrt(len(sig.sweep().force)))


def harmonic_rows(hm: dict[int, float], hx: dict[int, float],
                  floor: dict[int, float] | None = None) -> list[dict]:
    """The harmonic table of a comparison: per order both sides have, the model's and the
    measured amplitude (``{1: P_1, k: P_k}`` as :func:`harmonics` gives them), their
    ratios to ``P_1``, the measured ratio's noise floor and the difference (dB)."""
    rows = []
    for k in sorted(set(hm) & set(hx)):
        rows.append({"order": k, "model": hm[k], "measured": hx[k],
                     "model_ratio": hm[k] / hm[1] if hm.get(1) else None,
                     "measured_ratio": hx[k] / hx[1] if hx.get(1) else None,
                     "measured_floor_ratio": (floor or {}).get(k),
                     "difference_db": float(20 * np.log10(hm[k] / hx[k]))
                     if hm[k] > 0 and hx[k] > 0 else None})
    return rows


def thd_floor(h: dict[int, float], floor: dict[int, float] | None) -> float | None:
    """The THD (%) that the record's output noise alone reads over the orders of ``h``
    (:func:`harmonic_floor`): noise adds in power, so a model without noise reads as
    ``sqrt(THD_model^2 + floor^2)`` on the rig. None without a floor."""
    return thd({1: 1.0, **{k: v for k, v in (floor or {}).items() if k >= 2 and k in h}})


def thd(h: dict[int, float]) -> float | None:
    """THD (%) of order amplitudes ``{1: P_1, k: P_k}``: ``100 sqrt(sum_k>=2 P_k^2) / P_1``
    (Eq. 16), None without harmonics."""
    return float(100 * np.sqrt(sum(v**2 for k, v in h.items() if k >= 2)) / h[1]) \
        if h.get(1) and len(h) > 1 else None
