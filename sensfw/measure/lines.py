"""Model against a stepped-sine or FRF-only record: comparisons on frequency lines.

A stepped-sine test gives one FRF line per step and nothing else; many rigs export only
FRFs (an LMS ``FRF.mat``, UFF58 FRF records). The model is driven as such a test drives the
structure (:func:`frf_drive`): a stepped sine on the record's lines inside the study's
band, at the record's level, in the record's direction, each step long enough for the
model's transient to decay, and its steady state is read per step
(:func:`sensfw.signal.stepped.stepped_frf`). A stepped-sine record with time data is read
the same way on the steps found in its excitation. :func:`compare_lines` then gives the
usual :class:`~sensfw.measure.comparison.LevelComparison` on those lines (FRF error per
band, resonances, harmonics where there are time data), and :func:`jump` the jump between
an up and a down sweep at one level: the fingerprint of a nonlinear resonance whose
response has two stable branches (Worden & Tomlinson 2001, Ch. 3: the jump phenomenon).
"""

from __future__ import annotations

import numpy as np

from ..errors import MeasurementError, SignalError
from ..excitation import SteppedSine
from ..models.base import Signals
from ..signal.stepped import ORDERS, stepped_frf, steps_of
from .bands import analysis_bands
from .comparison import LevelComparison, display_unit
from .distortion import harmonic_rows, thd
from .measurement import FRFRecord, Measurement
from .resonance import fit_resonances, match_resonances, resonances

#: most steps the model is driven with (an FRF.mat from a sweep holds 641 lines of 1/16 Hz
#: over 70-110 Hz: every k-th line is simulated, and compared)
MAX_STEPS = 200
#: each step settles for this many decay times ``1 / (zeta omega)`` of the record's
#: sharpest resonance before the same time is fitted: e^-4 of a step's transient is left
#: at the fit's start (the transient is the change of the steady state from the previous
#: line: a few per cent for lines finer than the half-power bandwidth)
SETTLE_DECAYS = 4.0
#: and at least this many periods of the lowest line
MIN_PERIODS = 10
#: up and down sweeps that differ by more than this somewhere (dB) have jumped
JUMP_DB = 1.0
#: a model's stepped lines whose two fitted halves differ by more than this (dB) have not
#: settled: their record is stepped again with twice the dwell, at most LONGER times
SETTLED_DB = 0.1
LONGER = 2


def drive_lines(record: FRFRecord, band: tuple[float, float], max_steps: int = MAX_STEPS
                ) -> np.ndarray:
    """The record's lines inside ``band`` that the model is driven at: all of them, or
    every k-th (the smallest k that keeps ``max_steps``)."""
    lines = record.lines_in(*band)
    lines = lines[lines > 0]
    k = max(1, int(np.ceil(len(lines) / max_steps)))
    return lines[::k]


def settle_time(f: np.ndarray, h: np.ndarray) -> float | None:
    """Decay time ``1 / (zeta omega)`` of the slowest-decaying resonance of the FRF ``h`` on
    the lines ``f`` (its single-mode fit where that succeeds, which holds on lines coarser
    than the peak; else its half-power width, at least a line wide), or None without a
    resonance."""
    mag = np.abs(h)
    ok = mag > 0
    f, h = f[ok], h[ok]
    peaks = fit_resonances(f, h, resonances(f, 20 * np.log10(mag[ok])))
    line = float(np.min(np.diff(f))) if len(f) > 1 else 0.0
    taus = []
    for p in peaks:
        if p["fit_damping"]:
            taus.append(1 / (2 * np.pi * p["fit_frequency"] * p["fit_damping"]))
        elif p["damping_ratio"]:
            width = max(2 * p["damping_ratio"] * p["frequency"], line)
            taus.append(1 / (np.pi * width))
    return max(taus) if taus else None


def frf_drive(meas: Measurement, study) -> SteppedSine:
    """The stepped sine that stands for an FRF-only record (module docstring): on
    :func:`drive_lines` within the study's band, at ``meas.level`` (or the study's
    amplitude, with a note), in the record's direction (up where unknown, with a note),
    each step ``2 max(SETTLE_DECAYS tau, MIN_PERIODS / f_min)`` long (``tau`` from the
    record's own slowest-decaying resonance on the study's output, :func:`settle_time`),
    half of it to settle."""
    rec, ex = meas.frf, study.excitation
    lines = drive_lines(rec, (ex.f0, ex.f1))
    if len(lines) < 2:
        raise MeasurementError(meas.file, f"fewer than two FRF lines inside the study's band "
                                          f"{ex.f0:g}-{ex.f1:g} Hz (the record covers "
                                          f"{rec.f[0]:g}-{rec.f[-1]:g} Hz)")
    if lines[-1] >= 0.45 * ex.fs:
        raise MeasurementError(meas.file, f"the record's lines reach {lines[-1]:g} Hz, beyond "
                                          f"0.45 x the study's sample rate {ex.fs:g} Hz")
    sel = (rec.f >= lines[0]) & (rec.f <= lines[-1])
    tau = settle_time(rec.f[sel], rec.channel(study.output)[sel])
    settle = max(SETTLE_DECAYS * tau if tau else 0.0, MIN_PERIODS / lines[0])
    dwell = float(np.ceil(2 * settle * ex.fs) / ex.fs)  # whole samples per step
    level = meas.level
    if level is None:
        level = ex.amplitude
        meas.notes.append(f"the record states no level: the model is driven at the study's "
                          f"{level:g} {ex.unit}")
        meas.level = float(level)
    if rec.kind == "random":
        meas.notes.append(
            f"FRF-only record of a random test: its level {level:g} is the rig's setting, "
            "not the amplitude of the sine the model is stepped with (a random drive's RMS in "
            "the band is far below it and not in an FRF file), so a nonlinear model is driven "
            "harder than the rig was: compare the time record, or state its RMS as the level")
    direction = rec.direction or "up"
    if rec.direction is None:
        meas.notes.append("the record states no sweep direction: the model steps upwards")
    every = round(len(rec.lines_in(ex.f0, ex.f1)) / len(lines))
    by_decay = SETTLE_DECAYS * tau if tau else 0.0
    why = (f"{SETTLE_DECAYS:g} x the decay time {tau:.3g} s of its slowest resonance"
           if by_decay >= MIN_PERIODS / lines[0] else
           f"{MIN_PERIODS:g} periods of its lowest line, {lines[0]:g} Hz"
           + (f", more than {SETTLE_DECAYS:g} x the decay time {tau:.3g} s of its slowest "
              "resonance" if tau else ""))
    meas.notes.append(
        f"FRF-only record: the model is driven by a stepped sine on {len(lines)} of its lines "
        f"in {lines[0]:g}-{lines[-1]:g} Hz" + (f" (one line in {every})" if every > 1 else "")
        + f", {dwell:.3g} s per step (half of it to settle: {why})"
        + f", at {level:g} {rec.units.get('force', 'N')}, {direction}")
    return SteppedSine.at(lines, dwell, ex.fs, float(level), direction=direction,
                          signal_unit=rec.units.get("force", "N"))


def longer_drive(meas: Measurement, c: LevelComparison) -> bool:
    """Double the dwell of an FRF-only record's drive when the model's lines of ``c`` have
    not settled (:data:`SETTLED_DB`; transients last long near a resonance's jump), with a
    note; whether it did."""
    worst = c.settled_db.get("model", 0.0)
    ex = meas.drive
    if meas.frf is None or not isinstance(ex, SteppedSine) or not worst > SETTLED_DB:
        return False
    meas.drive = SteppedSine.at(ex.lines, 2 * ex.dwell, ex.fs, ex.amplitude,
                                direction=ex.direction, signal_unit=ex.signal_unit)
    meas.notes.append(f"the model's lines had not settled ({worst:.2f} dB between the halves "
                      f"of a step): stepped again with {2 * ex.dwell:.3g} s per step")
    return True


def _db(h: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return 20 * np.log10(np.abs(h))


def _stepped(sig: Signals, channel: str):
    """(steady-state FRF, amplitudes, settled dB) per step of a stepped-sine record."""
    s = sig.sweep()
    steps = steps_of(s.f_inst, s.fs)
    if steps is None:
        raise SignalError("the record is not a stepped sine (its instantaneous frequency is "
                          "not piecewise constant)")
    steps = [st for st in steps if st.end - st.start >= 2.0 / st.frequency]
    r = stepped_frf(s.force, {channel: s.channel(channel)}, s.fs, steps)
    return r.f, r.frf[channel], r.amplitudes[channel], r.settled_db[channel]


#: the measured side of recent comparisons (a calibration compares many model runs with
#: the same records): (id, channel) -> (record, result)
_MEASURED: dict[tuple, tuple] = {}


def _measured(rec: Signals, channel: str):
    key = (id(rec), channel)
    hit = _MEASURED.get(key)
    if hit is None or hit[0] is not rec:
        if len(_MEASURED) > 64:
            _MEASURED.clear()
        hit = _MEASURED[key] = (rec, _stepped(rec, channel))
    return hit[1]


def _on(f_model: np.ndarray, f_rec: np.ndarray) -> np.ndarray:
    """Indices of ``f_model``'s lines among ``f_rec``'s (to 1e-6 relative)."""
    i = np.clip(np.searchsorted(f_rec, f_model), 1, len(f_rec) - 1)
    i = np.where(np.abs(f_rec[i - 1] - f_model) < np.abs(f_rec[i] - f_model), i - 1, i)
    if np.any(np.abs(f_rec[i] - f_model) > 1e-6 * f_model):
        j = int(np.argmax(np.abs(f_rec[i] - f_model)))
        raise ValueError(f"the model was stepped at {f_model[j]:g} Hz, not a line of the "
                         f"record; drive it with the measurement's drive")
    return i


def _orders(a: np.ndarray, f: np.ndarray, fs: float) -> dict[int, float]:
    """Order amplitudes ``{1: P_1, k: P_k}`` of a stepped record from its steps' complex
    amplitudes ``a`` (:data:`ORDERS`): the RMS over the steps, as an order spectrum
    averages a sweep (Eqs. 12-17); each ratio ``P_k / P_1`` over the steps where order
    ``k`` stays below 0.45 fs (as :func:`sensfw.measure.distortion.harmonics`)."""
    p1 = float(np.sqrt(np.mean(np.abs(a[:, 0]) ** 2) / 2))
    out = {1: p1}
    for i, k in enumerate(ORDERS):
        sel = k * f < 0.45 * fs
        if k == 1 or not sel.any():
            continue
        part = np.sqrt(np.mean(np.abs(a[sel, 0]) ** 2))
        if part > 0:
            out[k] = p1 * float(np.sqrt(np.mean(np.abs(a[sel, i]) ** 2)) / part)
    return out


def compare_lines(measured: Signals | FRFRecord, model: Signals, channel: str,
                  band: tuple[float, float], level: float, file: str = "",
                  detail: bool = True, error_band: tuple[float, float] | None = None
                  ) -> LevelComparison:
    """The model's stepped-sine record against a stepped-sine or FRF-only record on
    ``channel``, on the model's steps inside ``band`` (module docstring). An FRF record's
    noise per line comes from its coherence ``g2`` and averages ``n`` where it has them:
    the standard error of ``|H1|`` is ``sqrt((1 - g2) / (2 n g2))`` (Bendat & Piersol 2010,
    Eq. 9.90), averaged over a band's lines."""
    f_m, h_m, a_m, set_m = _stepped(model, channel)
    notes, settled = [], {"model": float(np.nanmax(np.abs(set_m), initial=0.0))}
    err = None
    if isinstance(measured, FRFRecord):
        idx = _on(f_m, measured.f)
        h_x = measured.channel(channel)[idx]
        kind = "stepped_sine" if measured.kind == "stepped_sine" else "frf"
        direction, rows, unit = measured.direction, [], measured.units.get("force", "N")
        thds = (None, None)
        out_unit = measured.units.get(channel, "m/s^2")
        coh = measured.coherence.get(channel)
        if coh is not None and measured.averages:
            g2 = np.clip(coh[idx], 1e-6, 1 - 1e-12)
            err = np.sqrt((1 - g2) / (2 * measured.averages * g2))
        if measured.kind not in (None, "stepped_sine"):
            notes.append(f"the record is the FRF of a {measured.kind} test, the model's of a "
                         f"stepped sine at its level: alike for a linear structure only")
    else:
        f_x, h_x, a_x, set_x = _measured(measured, channel)
        if len(f_x) != len(f_m) or not np.allclose(f_x, f_m):
            raise ValueError("model and measurement have different steps; drive the model "
                             "with the measured record")
        kind, unit = "stepped_sine", measured.units.get("force", "N")
        out_unit = measured.units.get(channel, "m/s^2")
        direction = "up" if np.all(np.diff(f_x) > 0) else \
            "down" if np.all(np.diff(f_x) < 0) else None
        hm, hx = _orders(a_m, f_m, measured.fs), _orders(a_x, f_x, measured.fs)
        rows, thds = harmonic_rows(hm, hx), (thd(hm), thd(hx))
        settled["measured"] = float(np.nanmax(np.abs(set_x), initial=0.0))
    order = np.argsort(f_m)
    sel = order[(f_m[order] >= band[0]) & (f_m[order] <= band[1])]
    f, hm, hx = f_m[sel], h_m[sel], np.asarray(h_x)[sel]
    if len(f) < 2:
        raise ValueError(f"fewer than two stepped lines in {band[0]:g}-{band[1]:g} Hz")
    dbm, dbx = _db(hm), _db(hx)
    e = None if err is None else np.asarray(err)[sel]
    bands = []
    to_db = 20 / np.log(10)
    for lo, c, hi in analysis_bands(*band):
        inb = (f >= lo) & (f < hi)
        if not inb.any():
            continue
        d = dbm[inb] - dbx[inb]
        bands.append({"centre_hz": c, "lower_hz": lo, "upper_hz": hi,
                      "model_db": float(np.mean(dbm[inb])),
                      "measured_db": float(np.mean(dbx[inb])),
                      "mean_db": float(np.mean(d)), "rms_db": float(np.sqrt(np.mean(d**2))),
                      "noise_db": None if e is None else
                      float(to_db * np.sqrt(np.mean(e[inb] ** 2) / inb.sum())),
                      "scatter_db": None})
    px = fit_resonances(f, hx, resonances(f, dbx)) if detail else resonances(f, dbx)
    pm = fit_resonances(f, hm, resonances(f, dbm)) if detail else []

    return LevelComparison(
        level=level, file=file, f=f, db_model=dbm, db_measured=dbx, bands=bands,
        resonances=match_resonances(pm, px) if detail else [], harmonics=rows,
        thd_model=thds[0], thd_measured=thds[1], notes=notes,
        unit=unit, output_unit=display_unit(out_unit), peaks_model=pm, peaks_measured=px,
        kind=kind, direction=direction, band=tuple(band), error_band=error_band,
        measured_by=measured.kind if isinstance(measured, FRFRecord) else None,
        settled_db=settled)


def jump(up: LevelComparison, down: LevelComparison, threshold_db: float = JUMP_DB) -> dict:
    """The jump between an up and a down sweep at one level, measured and model: the
    largest difference of the two FRFs on their common lines (dB) and where, the band
    where they differ by more than ``threshold_db`` (the hysteresis of a resonance with
    two stable branches; None where they agree), and where each sweep jumps: the largest
    fall between neighbouring lines of the up sweep, the largest rise (going down) of the
    down sweep."""
    common, iu, id_ = np.intersect1d(np.round(up.f, 9), np.round(down.f, 9),
                                     return_indices=True)
    out = {"level": up.level, "unit": up.unit, "lines": len(common),
           "threshold_db": threshold_db}
    if len(common) < 2:
        return {**out, "measured": None, "model": None}
    for who, key in (("measured", "db_measured"), ("model", "db_model")):
        u, d = getattr(up, key)[iu], getattr(down, key)[id_]
        diff = u - d
        k = int(np.argmax(np.abs(diff)))
        over = common[np.abs(diff) > threshold_db]
        fall = int(np.argmin(np.diff(u)))
        rise = int(np.argmax(-np.diff(d)))  # going down in frequency: d[i] - d[i + 1]
        out[who] = {"max_difference_db": float(diff[k]), "at_hz": float(common[k]),
                    "hysteresis_hz": [float(over[0]), float(over[-1])] if len(over) else None,
                    "up_falls_at_hz": float(0.5 * (common[fall] + common[fall + 1])),
                    "up_fall_db": float(-np.diff(u)[fall]),
                    "down_rises_at_hz": float(0.5 * (common[rise] + common[rise + 1])),
                    "down_rise_db": float(-np.diff(d)[rise])}
    return out


def jump_text(j: dict) -> str:
    """One line on :func:`jump`'s result."""
    def side(who):
        x = j[who]
        if x is None:
            return f"{who}: no common lines"
        where = f", they differ by more than {j['threshold_db']:g} dB over " \
                f"{x['hysteresis_hz'][0]:g}-{x['hysteresis_hz'][1]:g} Hz" \
            if x["hysteresis_hz"] else ""
        return f"{who} up and down differ by at most {abs(x['max_difference_db']):.2f} dB " \
               f"(at {x['at_hz']:g} Hz){where}"
    verdict = "jump" if any(j[w] and j[w]["hysteresis_hz"] for w in ("measured", "model")) \
        else "no jump"
    return f"{verdict} at {j['level']:g} {j['unit']}: {side('measured')}; {side('model')}"
