"""Time-frequency magnitude of a response for reports (the paper's Fig. 11)."""

from __future__ import annotations

import numpy as np
from scipy import signal as _sig

from ..errors import SignalError
from ._checks import as_signal, check_fs


def spectrogram(x, fs: float, nperseg: int = 512, noverlap: int | None = None,
                window: str = "hann", ref: float = 1.0):
    """Short-time Fourier magnitude in dB, ``(f, t, S_dB)`` with ``S_dB`` of shape
    ``(len(f), len(t))``: ``20 log10(|STFT| / ref)`` with amplitude scaling (a sine of
    amplitude A reads about ``20 log10(A/2/ref)`` one-sided). Thin wrapper on
    :func:`scipy.signal.spectrogram` (``mode="magnitude"``)."""
    x = as_signal(x, "x")
    fs = check_fs(fs)
    nperseg = min(int(nperseg), len(x))
    noverlap = nperseg * 7 // 8 if noverlap is None else noverlap
    if not 0 <= noverlap < nperseg:
        raise SignalError(f"noverlap={noverlap} must be between 0 and nperseg - 1 "
                          f"({nperseg - 1}; nperseg is at most the record's length)")
    try:
        f, t, S = _sig.spectrogram(x, fs=fs, window=window, nperseg=nperseg,
                                   noverlap=noverlap, mode="magnitude", scaling="spectrum")
    except ValueError as err:  # scipy's window checks: an unknown name, a wrong length
        raise SignalError(f"window {window!r} for segments of {nperseg} samples: {err}"
                          ) from None
    with np.errstate(divide="ignore"):
        return f, t, 20 * np.log10(np.maximum(S, 1e-300) / ref)
