"""Model against measurement: where and how they differ ("see where it fails").

For one excitation level: FRF error in dB (overall RMS and per one-third-octave band),
a resonance table (model vs measured frequency, shift, half-power damping ratio, refined by
a single-mode fit), a harmonic table (order amplitudes and their noise floor, dB
difference), THD and the DC offset. Over the levels: the amplitude-dependence table and the
signature classes of :mod:`sensfw.measure.signatures` (amplitude dependence is the
fingerprint of contact nonlinearity).

(A little over the usual 400 lines: the per-level noise estimates (band errors, harmonic
floor, DC standard error) share one local fit and belong with the numbers they qualify.)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.signal import find_peaks

from ..models.base import Signals
from ..signal import frf, harmonic_amplitudes, octave_smooth
from .signatures import amplitude_dependence

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


def resonances(f: np.ndarray, db: np.ndarray, prominence: float = 6.0,
               dynamic_range: float = 30.0) -> list[dict]:
    """Peaks of a (smoothed) FRF magnitude with their half-power damping ratio
    ``zeta = (f2 - f1) / (2 fn)`` from the -3 dB crossings. Peaks more than
    ``dynamic_range`` dB below the highest one are ignored (noise ripple where the response
    is weak)."""
    peaks, props = find_peaks(db, prominence=prominence)
    keep = db[peaks] >= np.max(db) - dynamic_range
    peaks, proms = peaks[keep], props["prominences"][keep]
    out = []
    for i, prom in zip(peaks, proms, strict=True):
        target = db[i] - 3.0
        lo = i
        while lo > 0 and db[lo] > target:
            lo -= 1
        hi = i
        while hi < len(db) - 1 and db[hi] > target:
            hi += 1
        zeta = None
        if db[lo] <= target and db[hi] <= target:
            f1 = np.interp(target, [db[lo], db[lo + 1]], [f[lo], f[lo + 1]])
            f2 = np.interp(target, [db[hi], db[hi - 1]], [f[hi], f[hi - 1]])
            zeta = float((f2 - f1) / (2 * f[i]))
        out.append({"frequency": float(f[i]), "peak_db": float(db[i]),
                    "prominence_db": float(prom), "damping_ratio": zeta})
    return out


#: a single-mode fit replaces the half-power values when it explains this fraction of the
#: complex FRF's variance near the peak (below it the peak is no clean mode: a distorted
#: nonlinear response, two modes within a few bandwidths)
MIN_FIT_R2 = 0.9


def fit_resonances(f: np.ndarray, H: np.ndarray, peaks: list[dict],
                   min_r2: float = MIN_FIT_R2) -> list[dict]:
    """Each peak of :func:`resonances` with a single-mode fit of the unsmoothed complex FRF
    ``H`` (:func:`sensfw.signal.modal.sdof_fit`): ``fit_frequency``, ``fit_damping`` and
    ``fit_r2``, or ``None`` where the fit fails or explains less than ``min_r2``. The
    half-power values stay in ``frequency`` and ``damping_ratio``; whoever compares two
    FRFs uses the fitted values only where both sides have them (the half-power damping of
    a 1/24-octave smoothed FRF is biased upwards, see :mod:`sensfw.signal.modal`)."""
    from ..errors import SignalError
    from ..signal.modal import sdof_fit

    out = []
    for p in peaks:
        fit = None
        try:
            fit = sdof_fit(f, H, p["frequency"], p["damping_ratio"] or 0.02)
        except SignalError:
            pass
        ok = fit is not None and fit.r2 >= min_r2 and \
            abs(np.log(fit.frequency / p["frequency"])) < 0.05
        out.append({**p, "fit_frequency": fit.frequency if ok else None,
                    "fit_damping": fit.damping_ratio if ok else None,
                    "fit_r2": fit.r2 if fit is not None else None})
    return out


def match_resonances(model: list[dict], measured: list[dict], tol: float = 0.25) -> list[dict]:
    """Pair each measured resonance with the nearest model resonance within ``tol``
    (relative); unmatched ones are listed with the other side empty (a missing or an extra
    mode)."""
    rows, used = [], set()
    for m in measured:
        best, dist = None, tol
        for j, s in enumerate(model):
            d = abs(np.log(s["frequency"] / m["frequency"]))
            if j not in used and d < dist:
                best, dist = j, d
        if best is None:
            rows.append({"measured_hz": m["frequency"], "model_hz": None, "shift_pct": None,
                         "measured_damping": m["damping_ratio"], "model_damping": None,
                         "note": "no model resonance nearby (missing mode?)"})
        else:
            used.add(best)
            s = model[best]
            rows.append({"measured_hz": m["frequency"], "model_hz": s["frequency"],
                         "shift_pct": 100 * (s["frequency"] / m["frequency"] - 1),
                         "measured_damping": m["damping_ratio"],
                         "model_damping": s["damping_ratio"], "note": ""})
    for j, s in enumerate(model):
        if j not in used:
            rows.append({"measured_hz": None, "model_hz": s["frequency"], "shift_pct": None,
                         "measured_damping": None, "model_damping": s["damping_ratio"],
                         "note": "not in the measurement (extra model mode?)"})
    return sorted(rows, key=lambda r: r["measured_hz"] or r["model_hz"])


def harmonics(sig: Signals, channel: str, orders: tuple[int, ...] = (2, 3)
              ) -> dict[int, float]:
    """RMS order amplitudes ``P_1`` and ``P_k`` (Eqs. 12-17) of a swept record, each ratio
    ``P_k / P_1`` over the part of the sweep where order ``k`` stays below 0.45 fs (so H3 is
    measured even where the whole sweep only allows order 2). Returns ``{1: P_1 (whole
    sweep), k: P_1(part) * ratio_k}``; empty without a sweep (random excitation)."""
    if sig.f_inst is None:
        return {}
    s = sig.sweep()
    x, fr = s.channel(channel), np.asarray(s.f_inst, float)
    out = harmonic_amplitudes(x, s.fs, fr, harmonics=(1,))
    for k in orders:
        n = int(np.searchsorted(np.maximum.accumulate(fr), 0.45 * s.fs / k))
        if n < 0.1 * len(fr):
            continue
        part = harmonic_amplitudes(x[:n], s.fs, fr[:n], harmonics=(1, k))
        if part[1] > 0:
            out[k] = out[1] * part[k] / part[1]
    return out


def harmonic_floor(sig: Signals, channel: str, orders: tuple[int, ...] = (2, 3),
                   seed: int = 0) -> dict[int, float]:
    """Noise floor of each ratio ``P_k / P_1`` of :func:`harmonics`: the order amplitude
    that the record's output noise alone gives at order ``k``, over the same part of the
    sweep, divided by that part's ``P_1``.

    The noise is white with the standard deviation of :func:`noise_sigma`; its order
    amplitude is computed on a realisation of it (the order spectrum averages over frames,
    so one realisation varies by a few per cent). Noise adds in power, ``P_k^2 ~ P_k,true^2
    + P_k,noise^2``: a measured ratio within a few dB of its floor says little about the
    harmonic. (The spectrum between the orders is no noise estimate for a fast sweep: the
    ring-down of each resonance smears across orders there.)"""
    if sig.f_inst is None:
        return {}
    sigma = noise_sigma(sig, channel)
    s = sig.sweep()
    x, fr = s.channel(channel), np.asarray(s.f_inst, float)
    noise = sigma * np.random.default_rng(seed).standard_normal(len(x))
    out = {}
    for k in orders:
        n = int(np.searchsorted(np.maximum.accumulate(fr), 0.45 * s.fs / k))
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


def noise_sigma(sig: Signals, channel: str, quantile: float = 0.05) -> float:
    """Standard deviation of the output noise of a record (assumed white), from the
    residual of the local fit of :func:`band_noise`: per bin ``E|N_k|^2 = n sigma^2``,
    read off a low quantile of the residual power over the bins (the power of complex
    Gaussian noise is exponential, so its ``q``-quantile is ``-ln(1 - q)`` times its mean).

    Exact for a linear response; harmonic distortion of a swept record does not follow
    the local fit either (its phase turns by ~1 rad per line relative to the force's), so a
    strongly nonlinear record gives an upper bound: the low quantile keeps to the lines
    where the distortion is weakest. 0 for a noise-free linear record."""
    _, _, _, resid = _local_fit(sig, channel)
    q = float(np.quantile(resid[1:], quantile)) / -np.log1p(-quantile)
    return float(np.sqrt(q / len(sig.force)))


def dc_standard_error(sig: Signals, channel: str) -> float:
    """Standard error of :func:`dc_offset` from the output noise: ``sigma / sqrt(n)`` for
    the mean over the sweep's ``n`` samples (:func:`noise_sigma`)."""
    return noise_sigma(sig, channel) / float(np.sqrt(len(sig.sweep().force)))


@dataclass
class LevelComparison:
    """Model against measurement at one excitation level."""

    level: float
    file: str
    f: np.ndarray
    db_model: np.ndarray
    db_measured: np.ndarray
    bands: list[dict]
    resonances: list[dict]
    harmonics: list[dict]
    thd_model: float | None
    thd_measured: float | None
    notes: list[str] = field(default_factory=list)
    unit: str = "N"  # of the excitation channel (the FRF's denominator)
    output_unit: str = "m/s²"  # of the compared channel (the FRF's numerator)
    dc_model: float = 0.0
    dc_measured: float = 0.0
    dc_standard_error: float = 0.0  # of dc_measured, from the record's noise
    peaks_model: list[dict] = field(default_factory=list)
    peaks_measured: list[dict] = field(default_factory=list)

    dynamic_range: float = 35.0

    #: largest standard error (dB) of a used band from the measurement's own noise
    #: (:func:`band_noise`; 1.5 dB is a relative error of 0.25, an SNR of 12 dB; the
    #: first-order standard error underestimates the spread beyond that)
    noise_limit_db: float = 1.5
    #: largest total scatter (dB) of a used band's measured FRF (noise and distortion, before
    #: the model's share is taken out): beyond it the measured band level says little
    scatter_limit_db: float = 3.0

    @property
    def used_bands(self) -> list[dict]:
        """Bands within ``dynamic_range`` dB of the strongest measured band whose own noise
        error is below ``noise_limit_db`` and whose total scatter is below
        ``scatter_limit_db`` (weaker ones are noise-limited on a shaker rig)."""
        top = max(b["measured_db"] for b in self.bands)

        def ok(b, key, limit):
            return b.get(key) is None or b[key] <= limit

        return [b for b in self.bands if b["measured_db"] >= top - self.dynamic_range
                and ok(b, "noise_db", self.noise_limit_db)
                and ok(b, "scatter_db", self.scatter_limit_db)]

    @property
    def noise_floor_db(self) -> float:
        """The FRF error (RMS over the used bands) that the measurement's noise alone
        exceeds with 0.1 % probability: a correct model stays below it. The band errors of a
        correct model are independent with the standard errors ``noise_db``, so their mean
        square is ``chi^2_n / n`` times the mean square standard error."""
        from scipy.stats import chi2

        v = [b["noise_db"] for b in self.used_bands if b.get("noise_db") is not None]
        if not v:
            return 0.0
        n = len(v)
        return float(np.sqrt(np.mean(np.square(v)) * chi2.ppf(0.999, n) / n))

    @property
    def frf_rms_db(self) -> float:
        """RMS of the band errors within the dynamic range."""
        return float(np.sqrt(np.mean([b["mean_db"] ** 2 for b in self.used_bands])))

    def frf_rms_db_between(self, fmin: float, fmax: float) -> float:
        """RMS over the lines in ``[fmin, fmax]`` of the dB difference model - measurement
        of the smoothed FRFs (:func:`frf_db`): the error of one band as a user states it
        ("dB RMS over 80-105 Hz")."""
        sel = (self.f >= fmin) & (self.f <= fmax)
        if not sel.any():
            raise ValueError(f"no FRF line in {fmin:g}-{fmax:g} Hz (the comparison covers "
                             f"{self.f[0]:g}-{self.f[-1]:g} Hz)")
        d = self.db_model[sel] - self.db_measured[sel]
        return float(np.sqrt(np.mean(d * d)))

    def to_dict(self) -> dict:
        used = {b["centre_hz"] for b in self.used_bands}
        bands = [{**b, "used": b["centre_hz"] in used} for b in self.bands]
        return {"level": self.level, "file": self.file,
                "frf_error_db": {"rms": self.frf_rms_db, "dynamic_range_db": self.dynamic_range,
                                 "noise_floor_db": self.noise_floor_db,
                                 "rms_all_bands": float(np.sqrt(np.mean(
                                     [b["mean_db"] ** 2 for b in self.bands]))),
                                 "bands": bands},
                "resonances": self.resonances, "harmonics": self.harmonics,
                "thd": {"model": self.thd_model, "measured": self.thd_measured,
                        "difference_db": 20 * np.log10(self.thd_model / self.thd_measured)
                        if self.thd_model and self.thd_measured else None},
                "dc_offset": {"model": self.dc_model, "measured": self.dc_measured,
                              "standard_error": self.dc_standard_error},
                "input_unit": self.unit, "notes": self.notes}


@dataclass
class _Side:
    """What :func:`compare_level` reads off one record (model or measurement)."""

    f: np.ndarray
    db: np.ndarray
    bands_db: np.ndarray
    noise: np.ndarray
    peaks: list[dict]
    harmonics: dict[int, float]


def _side(sig: Signals, channel: str, band: tuple[float, float], edges, detail: bool
          ) -> _Side:
    f, db, H = frf_db(sig, channel, band, complex_frf=True)
    return _Side(f, db, band_frf_db(sig, channel, edges), band_noise(sig, channel, edges),
                 fit_resonances(f, H, resonances(f, db)) if detail else [],
                 harmonics(sig, channel))


#: the measured side of recent comparisons (a calibration compares hundreds of model runs
#: with the same few records): (id, channel, band) -> (record, side, harmonic floor)
_MEASURED: dict[tuple, tuple] = {}


def _measured_side(sig: Signals, channel: str, band: tuple[float, float], edges):
    key = (id(sig), channel, tuple(band))
    hit = _MEASURED.get(key)
    if hit is None or hit[0] is not sig:
        if len(_MEASURED) > 64:
            _MEASURED.clear()
        hit = _MEASURED[key] = (sig, _side(sig, channel, band, edges, True),
                                harmonic_floor(sig, channel))
    return hit[1], hit[2]


def _unit(u: str) -> str:
    return u.replace("^2", "²")


def compare_level(measured: Signals, model: Signals, channel: str, band: tuple[float, float],
                  level: float, file: str = "", detail: bool = True) -> LevelComparison:
    """The model's record against the measured one on ``channel`` (module docstring).
    ``detail=False`` (a calibration's many evaluations) leaves out the model's resonance
    fits, which no residual uses: the comparison's ``resonances`` are then empty."""
    edges = analysis_bands(*band)
    mx, floor = _measured_side(measured, channel, band, edges)
    mm = _side(model, channel, band, edges, detail)
    f, dbm, dbx = mm.f, mm.db, mx.db
    if len(f) != len(mx.f) or not np.allclose(f, mx.f):
        raise ValueError("model and measurement have different frequency axes; align first")
    bands = []
    bm, bx = mm.bands_db, mx.bands_db
    # the measurement's scatter minus what the model's own record shows (nonlinear
    # distortion and leakage, shared by both): its random noise (floored at a quarter)
    e_meas, e_model = mx.noise, mm.noise
    noise = np.sqrt(np.maximum(e_meas**2 - e_model**2, (0.25 * e_meas) ** 2))
    to_db = 20 / np.log(10) / np.sqrt(2)  # standard error in dB: ln|1 + e z| ~ Re(e z)
    for (lo, c, hi), a, b, e, et in zip(edges, bm, bx, noise, e_meas, strict=True):
        sel = (f >= lo) & (f < hi)
        if sel.sum() == 0 or not (np.isfinite(a) and np.isfinite(b)):
            continue
        d = dbm[sel] - dbx[sel]
        bands.append({"centre_hz": c, "lower_hz": lo, "upper_hz": hi,
                      "model_db": float(a), "measured_db": float(b),
                      "mean_db": float(a - b), "rms_db": float(np.sqrt(np.mean(d**2))),
                      "noise_db": float(to_db * e) if np.isfinite(e) else None,
                      "scatter_db": float(to_db * et) if np.isfinite(et) else None})
    pm, px = mm.peaks, mx.peaks
    res = match_resonances(pm, px) if detail else []
    hm, hx = mm.harmonics, mx.harmonics
    rows = []
    for k in sorted(set(hm) & set(hx)):
        rows.append({"order": k, "model": hm[k], "measured": hx[k],
                     "model_ratio": hm[k] / hm[1] if hm.get(1) else None,
                     "measured_ratio": hx[k] / hx[1] if hx.get(1) else None,
                     "measured_floor_ratio": floor.get(k),
                     "difference_db": float(20 * np.log10(hm[k] / hx[k]))
                     if hm[k] > 0 and hx[k] > 0 else None})

    def thd(h):
        return float(100 * np.sqrt(sum(v**2 for k, v in h.items() if k >= 2)) / h[1]) \
            if h.get(1) and len(h) > 1 else None

    return LevelComparison(level=level, file=file, f=f, db_model=dbm, db_measured=dbx,
                           bands=bands, resonances=res, harmonics=rows, thd_model=thd(hm),
                           thd_measured=thd(hx), unit=measured.units.get("force", "N"),
                           output_unit=_unit(measured.units.get(channel, "m/s^2")),
                           dc_model=dc_offset(model, channel),
                           dc_measured=dc_offset(measured, channel),
                           dc_standard_error=dc_standard_error(measured, channel),
                           peaks_model=pm,
                           peaks_measured=px)


@dataclass
class Comparison:
    """The model against every measured level (what ``sensfw compare`` writes)."""

    study: str
    output: str
    levels: list[LevelComparison]
    pairs: list[tuple[float, Signals, Signals]]  # (level, measured, model) signals
    amplitude: dict | None  # :func:`sensfw.measure.signatures.amplitude_dependence`
    notes: list[str]

    def to_dict(self) -> dict:
        return {"study": self.study, "output": self.output,
                "levels": [c.to_dict() for c in self.levels],
                "amplitude_dependence": self.amplitude, "notes": self.notes}


def compare_measurements(study, measurements, runner, values=None, effects=()) -> Comparison:
    """Simulate the study's model (with extra ``effects`` and parameter ``values``) for
    every prepared measurement (:func:`sensfw.measure.prepared.load_measurements`) and
    compare."""
    from ..errors import SensfwError
    from ..evaluate import simulate, variant_spec

    specs = [variant_spec(study, dict(values or {}), m.drive, effects) for m in measurements]
    sims, _ = simulate(runner, specs, "model")
    ex = study.excitation
    levels, pairs, notes = [], [], []
    for i, m in enumerate(measurements):
        notes += [f"{m.file}: {n}" for n in m.notes]
        sig = sims[i]
        if sig is None:
            raise SensfwError(f"the model failed for {m.file} (level {m.level:g} "
                              f"{m.input_unit}); its error is in the run store")
        levels.append(compare_level(m.signals, sig, study.output, (ex.f0, ex.f1), m.level,
                                    m.file))
        pairs.append((m.level, m.signals, sig))
    return Comparison(study=study.name, output=study.output, levels=levels, pairs=pairs,
                      amplitude=amplitude_dependence(levels), notes=notes)
