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

from dataclasses import dataclass, replace

import numpy as np

from ..evaluate import simulate, variant_spec
from ..models.base import Signals
from ..signal.stepped import steps_of
from ..study import schema
from .bands import (
    FRACTIONS,
    SMOOTH,
    analysis_bands,
    band_frf_db,
    band_noise,
    band_rms,
    band_white_noise,
    excitation_noise_sigma,
    frf_db,
    line_noise_db,
    noise_sigma,
    octave_bands,
    third_octave_bands,
    usable_limit,
)
from .checks import recorded_band
from .comparison import ERROR_DEFINITION, Comparison, LevelComparison, display_unit
from .distortion import (
    dc_offset,
    dc_standard_error,
    harmonic_floor,
    harmonic_rows,
    harmonics,
    thd,
    thd_floor,
)
from .lines import LONGER, compare_lines, jump, longer_drive
from .measurement import FRFRecord
from .prediction import bands, calibration_result, ellipsoid_points
from .resonance import MIN_FIT_R2, fit_resonances, match_resonances, resonances
from .signatures import amplitude_dependence, twin_scatter

__all__ = ["ERROR_DEFINITION", "FRACTIONS", "MIN_FIT_R2", "SMOOTH", "Comparison",
           "LevelComparison",
           "analysis_bands", "band_frf_db", "band_noise", "compare_level",
           "compare_measurements", "dc_offset", "dc_standard_error", "fit_resonances",
           "frf_db", "harmonic_floor", "harmonics", "match_resonances", "noise_sigma",
           "octave_bands", "resonances", "third_octave_bands"]


@dataclass
class _Side:
    """What :func:`compare_level` reads off one record (model or measurement)."""

    f: np.ndarray
    db: np.ndarray
    bands_db: np.ndarray
    noise: np.ndarray | None  # the band's total scatter (measured side only)
    peaks: list[dict]
    harmonics: dict[int, float]


def _side(sig: Signals, channel: str, band: tuple[float, float], edges, detail: bool,
          f_max: float, scatter: bool = False) -> _Side:
    f, db, H = frf_db(sig, channel, band, complex_frf=True)
    return _Side(f, db, band_frf_db(sig, channel, edges),
                 band_noise(sig, channel, edges) if scatter else None,
                 fit_resonances(f, H, resonances(f, db)) if detail else [],
                 harmonics(sig, channel, f_max=f_max))


#: the measured side of recent comparisons (a calibration compares hundreds of model runs
#: with the same few records): (id, channel, band) -> (record, side, harmonic floor)
_MEASURED: dict[tuple, tuple] = {}


def _measured_side(sig: Signals, channel: str, band: tuple[float, float], edges):
    key = (id(sig), channel, tuple(band))
    hit = _MEASURED.get(key)
    if hit is None or hit[0] is not sig:
        if len(_MEASURED) > 64:
            _MEASURED.clear()
        top = usable_limit(sig)
        hit = _MEASURED[key] = (sig, _side(sig, channel, band, edges, True, top, True),
                                harmonic_floor(sig, channel, f_max=top),
                                line_noise_db(sig, channel, band),
                                excitation_noise_sigma(sig, band), {})
    return hit[1], hit[2], hit[3], hit[4], hit[5]


def _white_noise(measured: Signals, model: Signals, channel: str, band, edges, spectral: float,
                 cache: dict) -> np.ndarray:
    """The band errors of :func:`~.bands.band_white_noise` for ``measured``, its
    excitation's noise the lower of two upper bounds: the force's spectrum above its band
    (``spectral``) and, where the model was driven by the study's ideal sweep, the
    measured force less that sweep (its noise, and what else the rig's force holds: a
    shaker's distortion, a drift). A model driven by the record itself shares its noise
    as input, but the structure never felt it: the spectral bound stays."""
    sp = spectral
    if len(model.force) == len(measured.force):
        x = np.asarray(measured.force, float)
        diff = float(np.std(x - np.asarray(model.force, float)))
        if diff > 1e-6 * float(np.std(x)):  # else the model was driven by the record itself
            sp = min(sp, diff)
    key = round(sp, 12)
    if key not in cache:
        cache[key] = band_white_noise(measured, channel, edges, band, excitation_sigma=sp)
    return cache[key]


#: how a band's standard error is estimated (``[calibration] noise`` of a study):
#: ``"scatter"``, the record's own scatter about a local fit less the model's (the default),
#: or ``"propagated"``, its white noise on output and excitation carried through the band's
#: H1 (:func:`~.bands.band_white_noise`), with the THD entry read against the record's
#: noise floor (:class:`~.discrepancy.Entries`); defined with the study's schema
NOISE_MODELS = schema.NOISE_MODELS


def noise_model(study) -> str:
    """A study's noise model for the band errors (its ``[calibration] noise``; default
    ``"scatter"``)."""
    cal = study.spec.calibration
    return cal.noise if cal is not None else "scatter"


def compare_level(measured: Signals | FRFRecord, model: Signals, channel: str,
                  band: tuple[float, float], level: float, file: str = "",
                  detail: bool = True, error_band: tuple[float, float] | None = None,
                  noise: str = "scatter") -> LevelComparison:
    """The model's record against the measured one on ``channel`` (module docstring).
    ``detail=False`` (a calibration's many evaluations) leaves out the model's resonance
    fits, which no residual uses: the comparison's ``resonances`` are then empty.

    ``measured`` is a measurement's ``signals``: time signals, or the
    :class:`~sensfw.measure.measurement.FRFRecord` of an FRF-only measurement; a
    stepped-sine record (an FRF record, or time signals whose instantaneous frequency
    steps, as :func:`sensfw.measure.checks.prepare` leaves them) is compared on its lines
    (:func:`sensfw.measure.lines.compare_lines`: the model must have been driven by the
    measurement's ``drive``). ``error_band`` is the band of the record's error figure
    (:attr:`LevelComparison.error_db`; default: every compared line). ``noise`` is the
    band errors' model (:data:`NOISE_MODELS`)."""
    if noise not in NOISE_MODELS:
        raise ValueError(f"noise model {noise!r}: one of {', '.join(NOISE_MODELS)}")
    if isinstance(measured, FRFRecord) or steps_of(measured.f_inst, measured.fs) is not None:
        return compare_lines(measured, model, channel, band, level, file, detail, error_band)
    edges = analysis_bands(*band)
    mx, floor, (fn, line_noise), spectral, cache = _measured_side(measured, channel, band,
                                                                  edges)
    mm = _side(model, channel, band, edges, detail, usable_limit(measured),
               scatter=noise == "scatter")
    f, dbm, dbx = mm.f, mm.db, mx.db
    if len(f) != len(mx.f) or not np.allclose(f, mx.f):
        raise ValueError("model and measurement have different frequency axes; align first")
    bands = []
    bm, bx = mm.bands_db, mx.bands_db
    e_meas = mx.noise
    if noise == "propagated":
        # the record's white noise on output and excitation carried through the band's H1
        # (bands.band_white_noise). The total scatter (the local fit's residual: noise, but
        # also distortion that a correct model shares) still judges which bands can speak
        # (LevelComparison.used_bands): as the error it is a noisy estimate, a third to six
        # times a band's scatter over noise realisations, and it leaves out input noise
        # times the part of the response not coherent with the force (bench/whitening.py)
        err = _white_noise(measured, model, channel, band, edges, spectral, cache)
    else:
        # the measurement's scatter minus what the model's own record shows (nonlinear
        # distortion and leakage, shared by both): its random noise (floored at a quarter)
        err = np.sqrt(np.maximum(e_meas**2 - mm.noise**2, (0.25 * e_meas) ** 2))
    to_db = 20 / np.log(10) / np.sqrt(2)  # standard error in dB: ln|1 + e z| ~ Re(e z)
    for (lo, c, hi), a, b, e, et in zip(edges, bm, bx, err, e_meas, strict=True):
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
    rows = harmonic_rows(hm, hx, floor)
    return LevelComparison(level=level, file=file, f=f, db_model=dbm, db_measured=dbx,
                           bands=bands, resonances=res, harmonics=rows, thd_model=thd(hm),
                           thd_measured=thd(hx), thd_floor=thd_floor(hx, floor),
                           unit=measured.units.get("force", "N"),
                           output_unit=display_unit(measured.units.get(channel, "m/s^2")),
                           dc_model=dc_offset(model, channel),
                           dc_measured=dc_offset(measured, channel),
                           dc_standard_error=dc_standard_error(measured, channel),
                           peaks_model=pm, peaks_measured=px,
                           kind="random" if measured.f_inst is None else "sweep",
                           level_rms=band_rms(measured.sweep().force, measured.fs, band),
                           band=tuple(band), error_band=error_band,
                           line_noise=np.interp(f, fn, line_noise))


def _bands_of(m, band: tuple[float, float], study_fs: float,
              error_band: tuple[float, float] | None
              ) -> tuple[tuple[float, float], tuple[float, float]]:
    """A record's comparison band (the study's, cut to a slow record's own,
    :func:`~sensfw.measure.checks.recorded_band`) and its error band (``error_band`` or the
    study's, cut likewise); an error naming the record where the error band holds none of
    its lines."""
    from ..errors import SensfwError

    own = band if m.frf is not None else recorded_band(m, band, study_fs)
    err = error_band or band
    err = (err[0], min(err[1], own[1]))
    if err[0] >= err[1]:
        raise SensfwError(f"{m.file}: the error band {err[0]:g}-{(error_band or band)[1]:g}"
                          f" Hz holds no line of the record (up to {own[1]:.4g} Hz) "
                          f"inside the study's band {band[0]:g}-{band[1]:g} Hz")
    return own, err


#: the relative change of a twin run's drive (:func:`twin_drive`): far below any
#: measurement's resolution, far above the solver's round-off (1e-16)
TWIN = 1e-9


def twin_drive(drive, k: int = 1):
    """``drive`` scaled by ``1 + k TWIN``: a run that a model determined by its drive gives
    again to within 1e-9, and one that is not (stick-slip under a random drive: a
    round-off change of the drive grows to an O(1) change of the response within a tenth
    of a second on the quick study at 0.5 N) gives as differently as another realisation of
    itself. The differences of such runs are the model's own scatter
    (:attr:`~.comparison.LevelComparison.error_scatter_db`)."""
    from ..excitation import SampledForce

    if isinstance(drive, SampledForce):  # its amplitude is the level it was measured at
        return replace(drive, gain=drive.gain * (1 + k * TWIN))
    return drive.with_amplitude(drive.amplitude * (1 + k * TWIN))


def _add_twins(study, measurements, runner, values, effects, levels, twins: int) -> None:
    """Run each record's model again on ``twins`` twin drives (:func:`twin_drive`) and keep
    the twins' FRFs and peaks in its comparison (``db_twins``, ``peaks_twins``), and in
    each resonance row the model's own scatter of its frequency (``model_scatter_pct``)."""
    specs = [variant_spec(study, dict(values or {}), twin_drive(m.drive, k), effects)
             for k in range(1, twins + 1) for m in measurements]
    sims, _ = simulate(runner, specs, "model twins")
    for i, sig in enumerate(sims):
        m, c = measurements[i % len(measurements)], levels[i % len(measurements)]
        if sig is None:  # a twin failed where the model did not: it counts for nothing
            continue
        t = compare_level(m.signals, sig, study.output, c.band, m.level, m.file,
                          noise=noise_model(study),
                          error_band=c.error_band)
        c.db_twins.append(t.db_model if len(t.f) == len(c.f)
                          else np.interp(c.f, t.f, t.db_model))
        c.peaks_twins.append(t.peaks_model)
    for c in levels:
        for r in c.resonances:
            if r.get("model_hz") and c.peaks_twins:
                r["model_scatter_pct"] = twin_scatter({"frequency": r["model_hz"]},
                                                      c.peaks_twins, None)


def compare_measurements(study, measurements, runner, values=None, effects=(),
                         error_band: tuple[float, float] | None = None,
                         twins: int = 0) -> Comparison:
    """Simulate the study's model (with extra ``effects`` and parameter ``values``) for
    every prepared measurement (:func:`sensfw.measure.prepared.load_measurements`) and
    compare:
    per record on the study's output over the study's band, the error over ``error_band``
    (default: the study's band); the jump between up and down sweeps at each level that
    has both; the amplitude dependence over the levels (one record per level: the up
    sweep where there are two; random records at their RMS in the band). An FRF-only
    record whose model lines have not settled (:data:`~sensfw.measure.lines.SETTLED_DB`) is
    stepped again with twice the dwell, up to :data:`~sensfw.measure.lines.LONGER` times
    (the runs already made come from the run store). With ``twins`` each record's model
    runs that many times more on :func:`twin_drive` of its drive: its FRF error then states
    the model's own scatter beside the measurement's noise, and the amplitude dependence
    does not read a resonance shift that the model itself does not determine as
    evidence."""
    from ..errors import SensfwError
    from ..evaluate import simulate, variant_spec

    ex = study.excitation
    band = (ex.f0, ex.f1)
    bands = [_bands_of(m, band, ex.fs, error_band) for m in measurements]  # before any run
    for attempt in range(LONGER + 1):
        specs = [variant_spec(study, dict(values or {}), m.drive, effects)
                 for m in measurements]
        sims, _ = simulate(runner, specs, "model")
        levels, pairs = [], []
        for i, m in enumerate(measurements):
            sig = sims[i]
            if sig is None:
                raise SensfwError(f"the model failed for {m.file} (level {m.level:g} "
                                  f"{m.input_unit}); its error is in the run store")
            own, err = bands[i]
            c = compare_level(m.signals, sig, study.output, own, m.level, m.file,
                              noise=noise_model(study),
                              error_band=err)
            if m.sweep is not None and c.kind == "sweep":
                c.kind = m.sweep.kind
            levels.append(c)
            pairs.append((m.level, m.signals, sig))
        if not any([longer_drive(m, c) for m, c in zip(measurements, levels, strict=True)
                    if attempt < LONGER]):
            break
    if twins:
        _add_twins(study, measurements, runner, values, effects, levels, twins)
    notes = [f"{m.file}: {n}" for m in measurements for n in m.notes]
    jumps = []
    for lv in sorted({c.level for c in levels}):
        by = {c.direction: c for c in levels if c.level == lv and c.stepped}
        if "up" in by and "down" in by:
            jumps.append(jump(by["up"], by["down"]))
    one = {}
    for c in levels:  # one record per level for the amplitude dependence
        if c.level not in one or c.direction == "up":
            one[c.level] = c
    one = list(one.values())
    if all(c.kind == "random" and c.level_rms for c in one):  # their levels as what they are
        one = [replace(c, level=c.level_rms) for c in one]
    return Comparison(study=study.name, output=study.output, levels=levels, pairs=pairs,
                      amplitude=amplitude_dependence(one), notes=notes,
                      error_band=error_band or band, jumps=jumps,
                      bands=prediction_bands(study, measurements, runner, levels, effects,
                                             error_band or band))


def prediction_bands(study, measurements, runner, levels, effects=(),
                     error_band: tuple[float, float] | None = None) -> list:
    """The prediction band of each record (:mod:`sensfw.measure.prediction`) when the study
    holds the calibration it was written from; ``levels`` are the records' comparisons
    with the calibrated model."""
    cal = calibration_result(study)
    if cal is None:
        return []
    space = study.calibration_space(cal.coords.names)
    points = [space.to_parameters(p) for p in
              ellipsoid_points(cal.coords, cal.z, cal.covariance)]
    specs = [variant_spec(study, p, m.drive, effects) for p in points for m in measurements]
    sims, _ = simulate(runner, specs, "prediction band")
    sims = iter(sims)  # point-major, as the specs
    samples = [[None if (sig := next(sims)) is None else compare_level(
        m.signals, sig, study.output, c.band, m.level, m.file, error_band=error_band)
        for m, c in zip(measurements, levels, strict=True)] for _ in points]
    return bands(levels, samples, cal.records, [m.kind for m in measurements])
