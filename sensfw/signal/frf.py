"""Frequency response function estimators H1, H2 and Hv (paper Eqs. 8-10).

Convention (DESIGN.md): ``p`` is the input (force), ``x`` the output (response); auto
spectra ``Spp``, ``Sxx`` and the cross spectrum ``Spx = E[P* X]`` (scipy ``csd(p, x)``),
``Sxp = conj(Spx)``. Then

* ``H1 = Spx / Spp`` (unbiased by output noise),
* ``H2 = Sxx / Sxp`` (unbiased by input noise),
* ``Hv(eps) = ((eps Sxx - Spp) + sqrt((eps Sxx - Spp)^2 + 4 eps |Spx|^2)) / (2 eps Sxp)``
  (Eq. 8), the total-least-squares estimator for the noise-variance ratio
  ``eps = var(input noise) / var(output noise)`` (it is the ``eps = 1`` estimate of ``p`` and
  ``sqrt(eps) x``, divided by ``sqrt(eps)``: consistent when ``eps var(output noise)`` equals
  the input's): ``eps -> 0`` (no input noise) gives H1, ``eps -> inf`` (no output noise)
  gives H2, ``eps = 1`` is the eigenvector estimate (the FRF from the eigenvector of the
  smallest eigenvalue of ``[[Spp, Spx], [Sxp, Sxx]]``).

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


def _records(x, name: str) -> np.ndarray:
    """One record (1-D) or several equally long records, one per row (2-D)."""
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 2:
        if arr.shape[0] < 1:
            raise SignalError(f"{name} has no records (shape {arr.shape})")
        for i, row in enumerate(arr):
            as_signal(row, f"{name} record {i}")
        return arr
    return as_signal(arr, name)


def _segment_length(fs: float, nperseg: int | None, df: float | None) -> int | None:
    if df is None:
        return nperseg
    if nperseg is not None:
        raise SignalError(f"give nperseg ({nperseg}) or df ({df} Hz), not both")
    df = float(df)
    if not (np.isfinite(df) and df > 0):
        raise SignalError(f"frequency resolution df must be a positive number, got {df}")
    n = fs / df
    if abs(n - round(n)) > 1e-6 * n:
        raise SignalError(f"df = {df:g} Hz does not divide fs = {fs:g} Hz into a whole "
                          f"number of samples per segment ({n:.6g})")
    return round(n)


def spectra(x_in, x_out, fs: float, nperseg: int | None = None, noverlap: int | None = None,
            window: str | tuple | np.ndarray = "hann", *, df: float | None = None,
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Averaged auto and cross spectra ``(f, Spp, Sxx, Spx)`` (Welch, one-sided density).

    Parameters
    ----------
    x_in, x_out : array_like
        Input and output: one record each (1-D), or several records of equal length, one per
        row (2-D, the same number of rows in both). Several records are averaged linearly
        with equal weight over records and segments, as an analyser averages repeated
        acquisition frames (LMS Test.Lab "LINAVERAGE" with ``nr_of_averages`` frames).
    fs : float
        Sample rate, Hz.
    nperseg, noverlap, window
        Welch segmentation with :func:`scipy.signal.csd`/:func:`scipy.signal.welch`
        semantics: segment length, overlap in samples (``None``: half a segment) and any
        window :func:`scipy.signal.get_window` accepts (name, ``(name, parameter)`` tuple or
        array). ``nperseg=None`` (and no ``df``) uses one segment spanning the whole record
        with a rectangular window (``window`` and ``noverlap`` are then ignored): exact for
        a linear system driven by a chirp whose response has decayed inside the record
        (then H1 = H2 = Hv), but without averaging, so noise is not reduced.
    df : float, optional
        Frequency resolution, Hz: the segment length ``nperseg = fs / df`` (must be a whole
        number; give ``df`` or ``nperseg``, not both). The window is then ``window``.

    Notes
    -----
    Window amplitude/energy corrections and the one-sided doubling scale ``Spp``, ``Sxx``
    and ``Spx`` by the same factor, so they cancel in every FRF estimator and in the
    coherence; only the window's shape and the segmentation change an FRF.
    """
    p = _records(x_in, "x_in (input)")
    x = _records(x_out, "x_out (output)")
    if p.shape != x.shape:
        if p.ndim == x.ndim == 1:
            same_length(p, x, "x_in", "x_out")
        raise SignalError(f"x_in has shape {p.shape} but x_out has shape {x.shape}")
    fs = check_fs(fs)
    n = p.shape[-1]
    nperseg = _segment_length(fs, nperseg, df)
    if nperseg is None:
        nperseg, window, noverlap = n, "boxcar", 0
    nperseg = int(nperseg)
    if not 8 <= nperseg <= n:
        raise SignalError(f"nperseg={nperseg} must be between 8 and the record length {n}")
    if noverlap is not None and not 0 <= noverlap < nperseg:
        raise SignalError(f"noverlap={noverlap} must be between 0 and nperseg - 1 "
                          f"({nperseg - 1})")
    kw = dict(fs=fs, window=window, nperseg=nperseg, noverlap=noverlap, detrend=False)
    try:
        f, spx = csd(p, x, **kw)
    except ValueError as err:  # scipy's window checks: an unknown name, a wrong length
        raise SignalError(f"window {window!r} for segments of {nperseg} samples: {err}"
                          ) from None
    _, spp = welch(p, **kw)
    _, sxx = welch(x, **kw)
    if p.ndim == 2:  # equal-weight linear average over records (each has the same segments)
        spx, spp, sxx = spx.mean(axis=0), spp.mean(axis=0), sxx.mean(axis=0)
    return f, spp, sxx, spx


def hv_from_spectra(spp, sxx, spx, eps: float = 1.0) -> np.ndarray:
    """Eq. 8 evaluated without cancellation.

    With ``a = eps Sxx - Spp`` and ``b = 4 eps |Spx|^2`` the numerator is ``a + sqrt(a^2+b)``;
    for ``a < 0`` it is rewritten as ``b / (sqrt(a^2+b) - a)``, which gives the equivalent form
    ``Hv = 2 Spx / (sqrt(a^2+b) - a)`` (-> H1 as eps -> 0); for ``a >= 0`` Eq. 8 is used as
    printed (-> H2 as eps -> inf).
    """
    if not (np.isfinite(eps) and eps > 0):  # eps = inf: (inf + inf) / inf = NaN
        raise SignalError(f"eps must be a finite number > 0, got {eps} (eps -> inf is H2: "
                          "estimator='H2')")
    spp, sxx = np.asarray(spp, float), np.asarray(sxx, float)
    spx = np.asarray(spx, complex)
    a = eps * sxx - spp
    root = np.sqrt(a * a + 4.0 * eps * np.abs(spx) ** 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        neg = 2.0 * spx / (root - a)
        pos = (a + root) / (2.0 * eps * np.conj(spx))
    return np.where(a < 0, neg, pos)


def frf(x_in, x_out, fs: float, estimator: str = "Hv", eps: float = 1.0,
        nperseg: int | None = None, noverlap: int | None = None,
        window: str | tuple | np.ndarray = "hann",
        fmin: float | None = None, fmax: float | None = None,
        return_coherence: bool = False, *, df: float | None = None):
    """Frequency response function from ``x_in`` (force) to ``x_out`` (response).

    Parameters
    ----------
    x_in, x_out : array_like
        Input and output samples (same length); 2-D arrays hold several records, one per
        row, whose spectra are averaged (see :func:`spectra`).
    fs : float
        Sample rate, Hz.
    estimator : {"H1", "H2", "Hv"}
        See the module docstring; "Hv" with ``eps`` is Eq. 8.
    eps : float
        Noise-variance ratio of Eq. 8, input noise over output noise (0: H1, inf: H2); 1
        gives the TLS estimate.
    nperseg, noverlap, window
        Welch segmentation (see :func:`spectra`; ``nperseg=None`` is one full segment with
        a rectangular window).
    fmin, fmax : float, optional
        Keep only frequencies in ``[fmin, fmax]``.
    return_coherence : bool
        Also return the ordinary coherence ``|Spx|^2 / (Spp Sxx)``.
    df : float, optional
        Frequency resolution (Hz) instead of ``nperseg``: ``nperseg = fs / df``.

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
    f, spp, sxx, spx = spectra(x_in, x_out, fs, nperseg, noverlap, window, df=df)
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
    """Ordinary coherence ``(f, |Spx|^2 / (Spp Sxx))`` (needs averaging: default 1024-sample
    segments; a ``df`` keyword, see :func:`spectra`, replaces that default)."""
    if kw.get("df") is not None:
        nperseg = None
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
    if f.ndim != 1 or f.shape != p.shape:
        raise SignalError(f"f and H must be 1-D and equally long (got {f.shape}, {p.shape})")
    if not (np.isfinite(fraction) and fraction > 0):
        raise SignalError(f"fraction (windows of 1/fraction octave) must be > 0, got "
                          f"{fraction!r}")
    p = np.where((f > 0) & np.isfinite(p), p, 0.0)
    c = np.concatenate([[0.0], np.cumsum(p)])
    half = 2 ** (0.5 / fraction)
    lo = np.searchsorted(f, f / half, side="left")
    hi = np.searchsorted(f, f * half, side="right")
    n = np.maximum(hi - lo, 1)
    return np.sqrt((c[hi] - c[lo]) / n)
