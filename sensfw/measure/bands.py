"""The FRF of a record in fractional-octave bands, and the record's own noise.

The comparison bands (:func:`analysis_bands`: one-third octaves, finer for a narrow sweep),
the smoothed Hv FRF in dB (:func:`frf_db`), each band's coherent H1 (:func:`band_frf_db`) and
its standard error from the record's white noise on output and excitation
(:func:`band_white_noise`, :func:`noise_sigma`, :func:`excitation_noise_sigma`), and its
total scatter, noise and distortion (:func:`band_noise`: one local fit of the FRF,
:func:`_local_fit`).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import ShortTimeFFT, windows

from ..models.base import Signals
from ..signal import frf, octave_smooth

#: FRF settings of every comparison: Hv over the whole record, smoothed for the metrics
SMOOTH = 24  # 1/24 octave


def octave_bands(fmin: float, fmax: float, fraction: int = 3
                 ) -> list[tuple[float, float, float]]:
    """(lower, centre, upper) of the base-10 1/``fraction``-octave bands (IEC 61260:
    centres ``1000 * 10^(3n / (10 fraction))``) inside ``[fmin, fmax]``."""
    out = []
    step = 3.0 / (10.0 * fraction)  # decades per band
    for n in range(int(np.floor(np.log10(fmin / 1000) / step)) - 1,
                   int(np.ceil(np.log10(fmax / 1000) / step)) + 2):
        c = 1000.0 * 10 ** (n * step)
        lo, hi = c / 10 ** (step / 2), c * 10 ** (step / 2)
        if lo >= fmin * (1 - 1e-9) and hi <= fmax * (1 + 1e-9):
            out.append((lo, c, hi))
    return out


def third_octave_bands(fmin: float, fmax: float) -> list[tuple[float, float, float]]:
    """The one-third-octave bands (IEC 61260) inside ``[fmin, fmax]``."""
    return octave_bands(fmin, fmax, 3)


#: fractions of an octave the comparison bands may take
FRACTIONS = (3, 6, 12, 24, 48)


def analysis_bands(fmin: float, fmax: float, at_least: int = 12
                   ) -> list[tuple[float, float, float]]:
    """The comparison bands of a sweep over ``[fmin, fmax]``: one-third octaves, or the
    coarsest finer fraction that gives ``at_least`` bands (a narrow sweep, such as 70-110 Hz,
    holds only one third-octave)."""
    for fraction in FRACTIONS:
        bands = octave_bands(fmin, fmax, fraction)
        if len(bands) >= at_least:
            return bands
    return bands


def frf_db(sig: Signals, channel: str, band: tuple[float, float], smooth: int = SMOOTH,
           complex_frf: bool = False):
    """(f, dB magnitude) of the Hv FRF, 1/``smooth``-octave smoothed, inside ``band``
    (with ``complex_frf`` also the unsmoothed complex FRF on the same lines)."""
    f, H = frf(sig.force, sig.channel(channel), sig.fs, estimator="Hv")
    mag = octave_smooth(f, H, smooth)
    sel = (f >= band[0]) & (f <= band[1]) & (mag > 0)
    if complex_frf:
        return f[sel], 20 * np.log10(mag[sel]), H[sel]
    return f[sel], 20 * np.log10(mag[sel])


def band_frf_db(sig: Signals, channel: str, bands) -> np.ndarray:
    """dB magnitude of the FRF averaged coherently over each band,
    ``H_b = sum_b conj(P) X / sum_b |P|^2`` (H1 over the band's bins): noise averages down
    with the number of bins while the swept signal adds up."""
    P = np.fft.rfft(sig.force)
    X = np.fft.rfft(sig.channel(channel))
    f = np.fft.rfftfreq(len(sig.force), 1 / sig.fs)
    out = []
    for lo, _, hi in bands:
        sel = (f >= lo) & (f < hi)
        num = np.sum(np.conj(P[sel]) * X[sel])
        den = np.sum(np.abs(P[sel]) ** 2)
        out.append(20 * np.log10(np.abs(num / den)) if den > 0 and num != 0 else np.nan)
    return np.array(out)


def _local_fit(sig: Signals, channel: str, half_width: int = 4):
    """(f, P, H_k, per-bin residual power) of the local fit of :func:`band_noise`: ``X_j ~
    (a_k + b_k (j - k)) P_j`` over the ``2 half_width + 1`` bins around each bin ``k`` (an
    FRF that varies linearly across the window, so a resonance of a few per cent damping
    leaves little structure in the residual), ``H_k = a_k``, the residual corrected for the
    two fitted degrees of freedom."""
    P = np.fft.rfft(sig.force)
    X = np.fft.rfft(sig.channel(channel))
    f = np.fft.rfftfreq(len(sig.force), 1 / sig.fs)
    j = np.arange(-half_width, half_width + 1, dtype=float)
    pp = np.abs(P) ** 2
    px = np.conj(P) * X

    def local(x, weights):  # sum over the window around each bin of weights[j] x[k + j]
        return np.convolve(x, weights[::-1], mode="same")

    s0, s1, s2 = local(pp, np.ones_like(j)), local(pp, j), local(pp, j * j)
    t0, t1 = local(px, np.ones_like(j)), local(px, j)
    det = s0 * s2 - s1 * s1
    ok = det > 1e-12 * np.maximum(s0 * s2, 1e-300)
    Hk = np.divide(t0 * s2 - t1 * s1, det, out=np.zeros_like(t0), where=ok)
    resid = np.abs(X - Hk * P) ** 2 * (len(j) / (len(j) - 2))
    return f, P, Hk, resid


def band_noise(sig: Signals, channel: str, bands, half_width: int = 4) -> np.ndarray:
    """Relative standard error of each band's H1 (:func:`band_frf_db`) from the output
    noise of the record itself.

    With ``X = H P + N`` the band estimate ``sum conj(P) X / sum |P|^2`` has the relative
    error ``sqrt(sigma_N^2 / sum_b |H P|^2)``. The per-bin noise variance ``sigma_N^2`` is
    estimated from the residual of the local fit of :func:`_local_fit`. Bands whose error is
    large are noise-limited: the measurement cannot say there how wrong the model is (and
    a nonlinear structure's distortion counts as noise here: :func:`compare_level` takes the
    model's own share out)."""
    f, P, Hk, resid = _local_fit(sig, channel, half_width)
    out = []
    for lo, _, hi in bands:
        sel = (f >= lo) & (f < hi)
        signal = np.sum(np.abs(Hk[sel] * P[sel]) ** 2)
        noise = np.sum(resid[sel]) / max(int(sel.sum()), 1)  # per-bin variance
        out.append(float(np.sqrt(noise / signal)) if signal > 0 else np.inf)
    return np.array(out)


#: a record's usable bandwidth is its sample rate over this (the pass band of a data
#: acquisition's anti-aliasing filter: LMS, B&K and NI analysers show fs / 2.56)
ALIAS_FREE = 2.56


def usable_limit(sig: Signals) -> float:
    """The highest frequency a record holds: its Nyquist frequency, or for one recorded
    below its present rate and resampled to it (``meta["recorded_fs"]``,
    :func:`sensfw.measure.checks.prepare`) the recorded rate over :data:`ALIAS_FREE`: above
    that its spectrum is the resampling filter's stop band, not the structure's."""
    fr = float(sig.meta.get("recorded_fs", sig.fs))
    return sig.fs / 2 if fr >= sig.fs * (1 - 1e-6) else fr / ALIAS_FREE


def tf_noise_sigma(x: np.ndarray, fs: float, top: float | None = None,
                   quantile: float = 0.05, nperseg: int | None = None) -> float:
    """Standard deviation of the white noise in ``x`` from a low quantile of its
    short-time spectrum's power (Hann frames of ``nperseg`` samples, half overlapping;
    default the power of 2 nearest ``sqrt(2 n)``, as many frames as lines) over the frames
    inside the record and the lines between the second and the last below ``top``.

    A sweep's response, its harmonics and the ring-down of its resonances hold a few
    lines of each frame; white noise holds every cell, with power exponential of mean
    ``sigma^2 sum w^2`` (the first line and the last are not circular: left out), so the
    ``q``-quantile is ``-ln(1 - q)`` times that mean where at least a fraction ``q`` of
    the cells is noise alone (minimum statistics: R. Martin, "Noise power spectral density
    estimation based on optimal smoothing and minimum statistics", IEEE Trans. Speech
    Audio Process. 9, 2001). The structure's response leaks into every cell a little, so
    this is an upper bound: over the quick study's random cases at 1-5 % noise, 1.15 times
    the output noise (median; 5-95 % 1.06-1.26) and 1.12 times the excitation's
    (``bench/noise_estimates.py``; ``tests/measure/test_bands.py``). A response that
    fills the plane (a random excitation over the whole band) reads as noise."""
    x = np.asarray(x, float)
    n = len(x)
    if nperseg is None:
        nperseg = int(np.clip(2 ** np.round(np.log2(np.sqrt(2 * n))), 16, 4096))
    nperseg = min(nperseg, n)
    w = windows.hann(nperseg, sym=False)
    sft = ShortTimeFFT(w, hop=nperseg // 2, fs=fs)
    S = sft.stft(x)
    f = sft.f
    top = fs / 2 if top is None else top
    lines = np.flatnonzero(f < top * (1 - 1e-9))[1:-1]
    p0, p1 = sft.lower_border_end[1], sft.upper_border_begin(n)[1]
    if len(lines) < 2 or p1 <= p0:
        return 0.0
    power = np.abs(S[lines][:, p0:p1]) ** 2
    mean = float(np.quantile(power, quantile)) / -np.log1p(-quantile)
    return float(np.sqrt(mean / np.sum(w**2)))


def noise_sigma(sig: Signals, channel: str, quantile: float = 0.05) -> float:
    """Standard deviation of the output noise of a record (assumed white): the lower of
    two upper bounds, each exact for white noise alone.

    - The residual of the local fit of :func:`band_noise`: per bin ``E|N_k|^2 = n
      sigma^2``, read off a low quantile of the residual power over the bins (the power of
      complex Gaussian noise is exponential, so its ``q``-quantile is ``-ln(1 - q)`` times
      its mean). Close for a linear response (1.1-1.2 times the noise at 1 % on a
      two-degree-of-freedom sweep), but a swept record's harmonic distortion does not
      follow the local fit (its phase turns by ~1 rad per line relative to the force's),
      and a contact's distortion fills every line: over the quick study's random cases at
      1-5 % noise 1.58 times the noise (median; 5-95 % 1.18-5.48).
    - The short-time spectrum's low quantile (:func:`tf_noise_sigma`): a sweep's response
      and its harmonics hold a few lines of each frame, so the other cells are noise,
      whatever the distortion (1.15 times the noise there, 5-95 % 1.06-1.26:
      ``bench/noise_estimates.py``); a random excitation's response fills them, where the
      local fit holds. On the UNESP-BERT records it reads about the same floor on all
      twelve sweep and random records (Acc1 0.0043-0.0052 in the record's unit) where the
      local fit grows with the level (0.016-1.4 on the sweeps).

    The lower of two estimates that are each exact on noise alone reads a few per cent
    low there. 0 for a noise-free linear record. The signature classes' harmonic floors
    keep the first bound alone (:func:`local_fit_noise_sigma`).

    A record resampled from a lower rate holds its noise below :func:`usable_limit` only;
    both quantiles are taken over those lines, which gives the white noise at the present
    rate of the same density there (for the mean over the record, the same standard
    error as the recorded samples give: ``sigma_r^2 / n_r``). Over every line it would be
    the empty stop band's, nearly 0."""
    return min(local_fit_noise_sigma(sig, channel, quantile),
               tf_noise_sigma(sig.channel(channel), sig.fs, usable_limit(sig), quantile))


def local_fit_noise_sigma(sig: Signals, channel: str, quantile: float = 0.05) -> float:
    """The first bound of :func:`noise_sigma` alone: the output noise read off a low
    quantile of the local fit's residual power (:func:`_local_fit`) over the lines below
    :func:`usable_limit`. Where a swept record's distortion fills every line it reads that
    distortion as noise too (1.6 times the noise, median, over the quick study's random
    cases; ``bench/noise_estimates.py``): an upper bound that the signature classes'
    harmonic floors keep on purpose (:func:`sensfw.measure.distortion.harmonic_floor`)."""
    f, _, _, resid = _local_fit(sig, channel)
    held = resid[1:][f[1:] < usable_limit(sig)]
    q = float(np.quantile(held if len(held) else resid[1:], quantile)) / -np.log1p(-quantile)
    return float(np.sqrt(q / len(sig.force)))


def excitation_noise_sigma(sig: Signals, band: tuple[float, float],
                           min_bins: int = 32) -> float:
    """Standard deviation of the noise on a record's excitation channel (assumed white):
    the lower of two upper bounds.

    - Its spectrum above the excitation's band: between ``1.15 band[1]`` and 0.95 of
      :func:`usable_limit` the force holds only its noise (and the sweep's leakage, which
      the median leaves out), so per bin ``E|N_k|^2 = n sigma^2`` is the median power over
      those bins divided by ``ln 2`` (the power of complex Gaussian noise is
      exponential). A sweep's own spectrum does not end at its last frequency (its start
      and end splatter over every bin), which reads as noise of about 2 % of the force's
      RMS on a short log chirp: at 1 % noise 2-3 times the noise, at 10 % within 5 %. Not
      used where fewer than ``min_bins`` such bins exist.
    - The short-time spectrum's low quantile (:func:`tf_noise_sigma`): a sweep holds one
      line of each frame (1.0-1.3 times the noise at 1-10 %); a random excitation fills
      its band, where the bound above holds.

    ``tests/measure/test_bands.py`` measures both. A force without noise gives about 0."""
    tf = tf_noise_sigma(np.asarray(sig.force, float), sig.fs, usable_limit(sig))
    above = above_band_noise_sigma(sig, band, min_bins)
    return tf if above is None else min(tf, above)


def above_band_noise_sigma(sig: Signals, band: tuple[float, float],
                           min_bins: int = 32) -> float | None:
    """The first bound of :func:`excitation_noise_sigma` alone: the excitation's noise
    from the median power of its spectrum between ``1.15 band[1]`` and 0.95 of
    :func:`usable_limit`; ``None`` where fewer than ``min_bins`` lines lie there."""
    x = np.asarray(sig.force, float)
    P = np.fft.rfft(x)
    f = np.fft.rfftfreq(len(x), 1 / sig.fs)
    sel = (f > 1.15 * band[1]) & (f < 0.95 * usable_limit(sig))
    if int(sel.sum()) < min_bins:
        return None
    per_bin = float(np.median(np.abs(P[sel]) ** 2)) / np.log(2.0)
    return float(np.sqrt(per_bin / len(x)))


def band_white_noise(sig: Signals, channel: str, bands, band: tuple[float, float],
                     excitation_sigma: float | None = None,
                     output_sigma: float | None = None) -> np.ndarray:
    """Relative standard error of each band's H1 (:func:`band_frf_db`, ``H_b = sum conj(P)
    X / sum |P|^2``) from white noise on the output (``output_sigma``, default
    :func:`noise_sigma`) and on the excitation (``excitation_sigma``, default
    :func:`excitation_noise_sigma` over the excitation's ``band``), to first order (the
    delta method; Bendat & Piersol, *Random Data*, 4th ed. 2010, ch. 9, for the errors of
    frequency-response estimates with noise on input and output):

    ``e_b^2 = n (sigma_x^2 sum |P|^2 + sigma_p^2 sum |X|^2) / |sum conj(P) X|^2``.

    The second term carries the part of the response that is not coherent with the force
    in the band (a swept record's harmonics, the ring-down of other modes): input noise
    multiplies all of it, so a band whose response is mostly distortion scatters far more
    than its output noise alone says. Unlike :func:`band_noise` (the residual of a local
    fit, which also holds the model's own distortion and the fit's bias across a
    resonance, and is itself a noisy estimate per band), every band's error follows from
    two noise levels estimated over thousands of bins (``bench/whitening.py`` measures how
    white the entries are at the truth)."""
    P = np.fft.rfft(np.asarray(sig.force, float))
    X = np.fft.rfft(sig.channel(channel))
    f = np.fft.rfftfreq(len(sig.force), 1 / sig.fs)
    n = len(sig.force)
    sx = noise_sigma(sig, channel) if output_sigma is None else output_sigma
    sp = excitation_noise_sigma(sig, band) if excitation_sigma is None else excitation_sigma
    out = []
    for lo, _, hi in bands:
        sel = (f >= lo) & (f < hi)
        cross = float(np.abs(np.sum(np.conj(P[sel]) * X[sel])) ** 2)
        noise = n * (sx**2 * np.sum(np.abs(P[sel]) ** 2) + sp**2 * np.sum(np.abs(X[sel]) ** 2))
        out.append(float(np.sqrt(noise / cross)) if cross > 0 else np.inf)
    return np.array(out)


def band_rms(x: np.ndarray, fs: float, band: tuple[float, float]) -> float:
    """RMS of ``x`` within ``band`` (Parseval over the record's DFT lines in the band): the
    level of a random excitation over the band a comparison looks at."""
    X = np.fft.rfft(np.asarray(x, float))
    f = np.fft.rfftfreq(len(x), 1 / fs)
    tol = 1e-9 * band[1]  # a line on the band's edge counts, whatever the rate's rounding
    sel = (f >= band[0] - tol) & (f <= band[1] + tol) & (f > 0)
    weight = np.where((f[sel] == fs / 2), 1.0, 2.0)  # the Nyquist line is not mirrored
    return float(np.sqrt(np.sum(weight * np.abs(X[sel]) ** 2)) / len(x))


def line_noise_db(sig: Signals, channel: str, band: tuple[float, float], draws: int = 3,
                  seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(f, per-line dB) of what the record's own output noise does to its smoothed FRF
    (:func:`frf_db`): white noise of the record's level (:func:`noise_sigma`) is added
    ``draws`` times and the RMS change of each line taken. A correct (noise-free) model
    differs from the record by one noise realisation, so this is the line error the
    measurement's noise alone gives it (the record's own noise is common to both smoothed
    FRFs and cancels to first order)."""
    sigma = noise_sigma(sig, channel)
    x = sig.channel(channel)
    base = Signals(t=sig.t, force=sig.force, channels={channel: x}, fs=sig.fs)
    f, db = frf_db(base, channel, band)
    rng = np.random.default_rng(seed)
    acc = np.zeros(len(f))
    for _ in range(draws):
        noisy = Signals(t=sig.t, force=sig.force, fs=sig.fs,
                        channels={channel: x + sigma * rng.standard_normal(len(x))})
        f2, db2 = frf_db(noisy, channel, band)
        if len(f2) != len(f):  # a line whose magnitude vanished: compare on the common ones
            db2 = np.interp(f, f2, db2)
        acc += (db2 - db) ** 2
    return f, np.sqrt(acc / draws)
