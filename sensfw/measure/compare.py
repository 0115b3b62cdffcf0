"""Model against measurement: where and how they differ ("see where it fails").

For one excitation level, :func:`compare_level`: FRF error in dB (per band, with the
measurement's noise: :mod:`sensfw.measure.bands`), a resonance table (model vs measured
frequency, shift, damping: :mod:`sensfw.measure.resonance`), a harmonic table, THD and the
DC offset (:mod:`sensfw.measure.distortion`). Over the levels, :func:`compare_measurements`
adds the amplitude-dependence table and the signature classes of
:mod:`sensfw.measure.signatures` (amplitude dependence is the fingerprint of contact
nonlinearity).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..models.base import Signals
from .bands import (
    FRACTIONS,
    SMOOTH,
    analysis_bands,
    band_frf_db,
    band_noise,
    frf_db,
    noise_sigma,
    octave_bands,
    third_octave_bands,
)
from .distortion import dc_offset, dc_standard_error, harmonic_floor, harmonics
from .resonance import MIN_FIT_R2, fit_resonances, match_resonances, resonances
from .signatures import amplitude_dependence

__all__ = ["FRACTIONS", "MIN_FIT_R2", "SMOOTH", "Comparison", "LevelComparison",
           "analysis_bands", "band_frf_db", "band_noise", "compare_level",
           "compare_measurements", "dc_offset", "dc_standard_error", "fit_resonances",
           "frf_db", "harmonic_floor", "harmonics", "match_resonances", "noise_sigma",
           "octave_bands", "resonances", "third_octave_bands"]


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


def compare_measurements(study, measurements, runner, variant=None) -> Comparison:
    """Simulate the study's model (with ``variant``: effects, parameter values) for every
    prepared measurement (:func:`sensfw.measure.session.load_measurements`) and compare."""
    from ..errors import SensfwError
    from .session import Variant, simulate

    variant = variant or Variant()
    sims = simulate(study, runner, [variant], measurements)
    ex = study.excitation
    levels, pairs, notes = [], [], []
    for i, m in enumerate(measurements):
        notes += [f"{m.file}: {n}" for n in m.notes]
        sig = sims[(variant, i)]
        if sig is None:
            raise SensfwError(f"the model failed for {m.file} (level {m.level:g} "
                              f"{m.input_unit}); its error is in the run store")
        levels.append(compare_level(m.signals, sig, study.output, (ex.f0, ex.f1), m.level,
                                    m.file))
        pairs.append((m.level, m.signals, sig))
    return Comparison(study=study.name, output=study.output, levels=levels, pairs=pairs,
                      amplitude=amplitude_dependence(levels), notes=notes)
