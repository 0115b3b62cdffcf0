"""Frequency response function estimators H1, H2 and Hv (paper Eqs. 8-10).

Convention (DESIGN.md): ``p`` is the input (force), ``x`` the output (response); auto
spectra ``Spp``, ``Sxx`` and the cross spectrum ``Spx = E[P* X]`` (scipy ``csd(p, x)``),
``Sxp = conj(Spx)``. Then

* ``H1 = Spx / Spp`` (unbiased by output noise),
* ``H2 = Sxx / Sxp`` (unbiased by input noise),
* ``Hv(eps) = ((eps Sxx - Spp) + sqrt((eps Sxx - Spp)^2 + 4 eps |Spx|^2)) / (2 eps Sxp)``
  (Eq. 8), the total-least-squares estimator for a noise-variance ratio ``eps``: ``eps -> 0``
  gives H1, ``eps -> inf`` gives H2, ``eps = 1`` is the eigenvector estimate (the FRF from
  the eigenvector of the smallest eigenvalue of ``[[Spp, Spx], [Sxp, Sxx]]``).

MATLAB's ``modalfrf(..., 'Estimator', 'Hv')`` is a different quantity (magnitude
``sqrt(|H1||H2|)`` with the phase of ``Spx``); it coincides with ``Hv(1)`` only when the
coherence is one.

References: Rocklin, Crowley & Vold (1985), "A comparison of H1, H2 and Hv frequency
response functions", Proc. IMAC 3; Shin & Hammond (2008), *Fundamentals of Signal
Processing for Sound and Vibration Engineers*, Sect. 9.3.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import csd, welch

from ..errors import SignalError
from ._checks import as_signal, check_fs, same_length

ESTIMATORS = ("H1", "H2", "Hv")


def spectra(x_in, x_out, fs: float, nperseg: int | None = None, noverlap: int | None = None,
            window: str = "hann") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Averaged auto and cross spectra ``(f, Spp, Sxx, Spx)`` (Welch, one-sided density).

    ``nperseg=None`` uses one segment spanning the whole record with a rectangular window:
    exact for a linear system driven by a chirp whose response has decayed inside the record
    (then H1 = H2 = Hv), but without averaging, so noise is not reduced.
    """
    p = as_signal(x_in, "x_in (input)")
    x = as_signal(x_out, "x_out (output)")
    same_length(p, x, "x_in", "x_out")
    fs = check_fs(fs)
    if nperseg is None:
        nperseg, window, noverlap = len(p), "boxcar", 0
    nperseg = int(nperseg)
    if not 8 <= nperseg <= len(p):
        raise SignalError(f"nperseg={nperseg} must be between 8 and the record length {len(p)}")
    kw = dict(fs=fs, window=window, nperseg=nperseg, noverlap=noverlap, detrend=False)
    f, spx = csd(p, x, **kw)
    _, spp = welch(p, **kw)
    _, sxx = welch(x, **kw)
    return f, spp, sxx, spx


def hv_from_spectra(spp, sxx, spx, eps: float = 1.0) -> np.ndarray:
    """Eq. 8 evaluated without cancellation.

    With ``a = eps Sxx - Spp`` and ``b = 4 eps |Spx|^2`` the numerator is ``a + sqrt(a^2+b)``;
    for ``a < 0`` it is rewritten as ``b / (sqrt(a^2+b) - a)``, which gives the equivalent form
    ``Hv = 2 Spx / (sqrt(a^2+b) - a)`` (-> H1 as eps -> 0); for ``a >= 0`` Eq. 8 is used as
    printed (-> H2 as eps -> inf).
    """
    if not eps > 0:
        raise SignalError(f"eps must be > 0, got {eps}")
    spp, sxx = np.asarray(spp, float), np.asarray(sxx, float)
    spx = np.asarray(spx, complex)
    a = eps * sxx - spp
    root = np.sqrt(a * a + 4.0 * eps * np.abs(spx) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        neg = 2.0 * spx / (root - a)
        pos = (a + root) / (2.0 * eps * np.conj(spx))
    return np.where(a < 0, neg, pos)


def frf(x_in, x_out, fs: float, estimator: str = "Hv", eps: float = 1.0,
        nperseg: int | None = None, noverlap: int | None = None, window: str = "hann",
        fmin: float | None = None, fmax: float | None = None,
        return_coherence: bool = False):
    """Frequency response function from ``x_in`` (force) to ``x_out`` (response).

    Parameters
    ----------
    x_in, x_out : array_like
        Input and output samples (same length).
    fs : float
        Sample rate, Hz.
    estimator : {"H1", "H2", "Hv"}
        See the module docstring; "Hv" with ``eps`` is Eq. 8.
    eps : float
        Noise-variance ratio of Eq. 8 (output over input); 1 gives the TLS estimate.
    nperseg, noverlap, window
        Welch segmentation (see :func:`spectra`; ``nperseg=None`` is one full segment).
    fmin, fmax : float, optional
        Keep only frequencies in ``[fmin, fmax]``.
    return_coherence : bool
        Also return the ordinary coherence ``|Spx|^2 / (Spp Sxx)``.

    Returns
    -------
    f : ndarray
        Frequencies, Hz.
    H : ndarray of complex
        The FRF (output unit per input unit).
    coh : ndarray, optional
        Coherence, when ``return_coherence``.
    """
    if estimator not in ESTIMATORS:
        raise SignalError(f"unknown FRF estimator {estimator!r}; use one of {ESTIMATORS}")
    f, spp, sxx, spx = spectra(x_in, x_out, fs, nperseg, noverlap, window)
    with np.errstate(divide="ignore", invalid="ignore"):
        if estimator == "H1":
            H = spx / spp
        elif estimator == "H2":
            H = sxx / np.conj(spx)
        else:
            H = hv_from_spectra(spp, sxx, spx, eps)
        coh = np.abs(spx) ** 2 / (spp * sxx)
    keep = np.ones(len(f), bool)
    if fmin is not None:
        keep &= f >= fmin
    if fmax is not None:
        keep &= f <= fmax
    if return_coherence:
        return f[keep], H[keep], coh[keep]
    return f[keep], H[keep]


def coherence(x_in, x_out, fs: float, nperseg: int | None = 1024, **kw):
    """Ordinary coherence ``(f, |Spx|^2 / (Spp Sxx))`` (needs averaging: default 1024)."""
    f, _, coh = frf(x_in, x_out, fs, estimator="H1", nperseg=nperseg, return_coherence=True,
                    **kw)
    return f, coh


def octave_smooth(f, H, fraction: int = 24) -> np.ndarray:
    """Magnitude of ``H`` smoothed over 1/``fraction``-octave windows (energy average
    ``sqrt(mean |H|^2)`` over ``[f 2^(-1/2n), f 2^(1/2n)]``), for plots of swept-sine FRFs
    whose fine ripple hides the resonances. The 0 Hz bin (no octave around it, and often an
    FRF of 0/0 for a force without DC) is left out of every window."""
    f = np.asarray(f, float)
    p = np.abs(np.asarray(H)) ** 2
    p = np.where((f > 0) & np.isfinite(p), p, 0.0)
    c = np.concatenate([[0.0], np.cumsum(p)])
    half = 2 ** (0.5 / fraction)
    lo = np.searchsorted(f, f / half, side="left")
    hi = np.searchsorted(f, f * half, side="right")
    n = np.maximum(hi - lo, 1)
    return np.sqrt((c[hi] - c[lo]) / n)
