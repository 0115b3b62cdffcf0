"""Checks of a measurement against a study, and how the model will be driven for it.

A rig's force is never the study's clean chirp: noise, a DC offset, an amplitude that drifts
near resonances, a delay, a silent tail, another kind of sweep, random excitation, or an
amplifier voltage instead of a force. :func:`prepare` therefore

1. refuses what cannot be compared (a missing channel, with the closest names; clipping);
2. estimates the excitation (:func:`sensfw.signal.sweep.estimate_sweep`: kind, f0, f1,
   start, end, level, drift, offset);
3. decides the model's drive: the study's ideal sweep at the measured level when the record
   is that sweep (within ``SWEEP_TOLERANCE``, its amplitude steady within
   ``DRIFT_TOLERANCE``) and the study allows it, else the measured record itself (a
   :class:`~sensfw.excitation.SampledForce`; a voltage drives the model through the
   study's ``excitation_gain``). A record that is not the study's sweep is a
   notice with the estimates, not a refusal;
4. aligns: for the ideal drive, resampled to the study's rate, the delay removed and cut to
   the study's record; for the measured drive, the DC offset removed (a force transducer's
   or amplifier's offset is not a static load) and the measured instantaneous frequency
   attached for order analysis (a stepped sine: its steps, for the per-step analysis of
   :mod:`sensfw.measure.lines`).

An FRF-only measurement (no time data) is driven by a stepped sine on its lines
(:func:`sensfw.measure.lines.frf_drive`). A random record's level is stated as its RMS in
the study's band.

Errors raise :class:`~sensfw.errors.MeasurementError` naming the file and channel.
"""

from __future__ import annotations

import difflib
from dataclasses import replace
from fractions import Fraction

import numpy as np
from scipy.signal import correlate, resample_poly

from ..errors import MeasurementError, SignalError
from ..excitation import Excitation, SampledForce
from ..models.base import Signals
from ..signal.stepped import detect_steps, direction_of
from ..signal.sweep import SweepEstimate, estimate_sweep
from .bands import ALIAS_FREE, band_rms
from .columns import fits
from .comparison import amount
from .lines import frf_drive
from .measurement import Measurement

#: relative tolerance on f0, f1 and duration for "the record is the study's sweep"
SWEEP_TOLERANCE = 0.03


def recorded_band(meas: Measurement, band: tuple[float, float], study_fs: float
                  ) -> tuple[float, float]:
    """``band`` cut to what a record sampled below the study's rate ``study_fs`` holds, at
    its own rate (before any resampling to the study's): up to its fs / :data:`ALIAS_FREE`.
    A record at the study's rate or above is compared on the study's band, as asked."""
    fs = meas.signals.meta.get("recorded_fs", meas.signals.fs)
    if fs >= study_fs * (1 - 1e-6):
        return band
    return band[0], min(band[1], fs / ALIAS_FREE)


#: a declared level (sidecar, folder name) further than this from the record's sweep
#: amplitude is named (the LMS reader's rule for its folder names)
LEVEL_TOLERANCE = 0.05

#: largest slow amplitude drift for which the ideal sweep stands for the applied force: a
#: nonlinear model feels the drift (measured on the quick study at 0.45 N: a +-20 % drift
#: driven by the ideal chirp left 1.9 dB FRF error against a 1.1 dB noise floor)
DRIFT_TOLERANCE = 0.10


def require_channels(meas: Measurement, channels: list[str]) -> None:
    have = list(meas.signals.channels)
    for ch in channels:
        if ch not in have:
            close = [h for h in have if h.lower() == ch.lower()] or \
                difflib.get_close_matches(ch, have, n=1, cutoff=0.5)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise MeasurementError(meas.file, f"missing channel (file has "
                                              f"{', '.join(['force', *have])}){hint}", ch)


def require_units(meas: Measurement, model) -> None:
    """Every measured channel the ``model`` also has is of the quantity the model computes
    (its ``units``): a velocity compared as an acceleration is off by ``20 log10(omega)``
    dB at every line (over 80 dB on the quick study's band), not a model error."""
    for ch, unit in meas.signals.units.items():
        want = model.units.get(ch) if ch != "force" else None
        if want and unit and not fits(unit, want):
            raise MeasurementError(meas.file, f"recorded in {unit}, but the model "
                                              f"{model.name}'s {ch} is in {want}: record (or "
                                              "label) the quantity the model computes", ch)


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


def check_channels(meas: Measurement, used: list[str]) -> None:
    """The excitation and the ``used`` channels (those the model computes too) neither
    clipped nor silent (a constant response: a dead sensor or cable). Channels the model
    does not have (a temperature, a torque) are not read."""
    force = meas.signals.force
    if np.ptp(force) == 0 and force[0] != 0:  # all zero: "silent", by the sweep estimate
        raise MeasurementError(meas.file, "the excitation is constant "
                               f"({force[0]:.4g}) over the whole record: no excitation (a "
                               "dead transducer or amplifier, or the wrong column?)", "force")
    for name in used:
        x = meas.signals.channels[name]
        if np.ptp(x) == 0:
            raise MeasurementError(meas.file, f"the response is constant ({x[0]:.4g}) over "
                                              "the whole record: a dead sensor or cable?", name)
    for name, x in [("force", meas.signals.force),
                    *((c, meas.signals.channels[c]) for c in used)]:
        n = clipped_runs(x)
        if n:
            raise MeasurementError(meas.file, f"clipped: {n} flat top(s) at full scale "
                                              f"(+-{np.max(np.abs(x)):.4g}); reduce the "
                                              f"level or the sensor range", name)


def _cut_by_the_record(est: SweepEstimate, excitation: Excitation, f_top: float | None,
                       tolerance: float) -> bool:
    """Whether the estimated sweep is the study's seen through a record that holds nothing
    above ``f_top`` (:func:`recorded_band`): it ends near ``f_top`` (the record's pass band
    fades it out there) and took the time the study's sweep takes from its start to that
    frequency."""
    f1 = getattr(excitation, "f1", None)
    if (f_top is None or f1 is None or not f_top < f1 or not est.is_sweep
            or not hasattr(excitation, "frequency")):
        return False
    if not f_top * (1 - 0.25) <= est.f1 <= f1 * (1 + tolerance):
        return False
    grid = np.linspace(0.0, excitation.duration, 4001)
    freq = np.maximum.accumulate(excitation.frequency(grid))
    span = float(np.interp(est.f1, freq, grid) - np.interp(est.f0, freq, grid))
    return span > 0 and abs(est.duration / span - 1) <= tolerance


def sweep_mismatch(est: SweepEstimate, excitation: Excitation,
                   tolerance: float = SWEEP_TOLERANCE, f_top: float | None = None
                   ) -> str | None:
    """Why the estimated excitation is not the study's (``None`` when it is). ``f_top``:
    the highest frequency the record holds where it was sampled below the study's rate
    (:func:`recorded_band`); there the record shows the study's sweep only up to it, so
    its end and duration are those of the study's sweep cut at ``f_top``
    (:func:`_cut_by_the_record`)."""
    if est.kind != excitation.kind:
        return f"it is a {est.kind.replace('_', ' ')}, the study's is a " \
               f"{excitation.kind.replace('_', ' ')}"
    if _cut_by_the_record(est, excitation, f_top, tolerance):
        f0 = getattr(excitation, "f0", None)
        if f0 is not None and not abs(est.f0 / f0 - 1) <= tolerance:
            return f"f0 = {est.f0:.4g} differs from the study's {f0:.4g} by more than " \
                   f"{tolerance:.0%}"
        return None
    for name, got, want in (("f0", est.f0, getattr(excitation, "f0", None)),
                            ("f1", est.f1, getattr(excitation, "f1", None)),
                            ("duration", est.duration, excitation.duration)):
        if want is not None and not abs(got / want - 1) <= tolerance:
            return f"{name} = {got:.4g} differs from the study's {want:.4g} by more than " \
                   f"{tolerance:.0%}"
    return None


def describe(est: SweepEstimate, unit: str = "N") -> str:
    """The estimated excitation in words; ``unit`` that of the force channel (N, or V)."""
    if est.is_sweep:
        return (f"{est.kind.replace('_', ' ')} {est.f0:.4g} -> {est.f1:.4g} Hz from "
                f"{est.t_start:.4g} s to {est.t_end:.4g} s, level {est.amplitude:.4g} {unit}, "
                f"drift +-{est.drift:.0%}, offset {est.offset:.3g} {unit}")
    if est.kind == "random":
        return "random, broadband"
    return (f"{est.kind.replace('_', ' ')} from {est.t_start:.4g} s to {est.t_end:.4g} s, "
            f"level {est.amplitude:.4g} {unit}"
            + (f" ({'; '.join(est.notes)})" if est.notes else ""))


def resample(sig: Signals, fs: float) -> Signals:
    """Polyphase resampling of every channel to ``fs`` (rational approximation)."""
    frac = Fraction(fs / sig.fs).limit_denominator(1000)
    up, down = frac.numerator, frac.denominator
    force = resample_poly(sig.force, up, down)
    channels = {k: resample_poly(v, up, down) for k, v in sig.channels.items()}
    n = len(force)
    return Signals(t=np.arange(n) / fs, force=force, channels=channels, fs=fs,
                   units=dict(sig.units), meta={"recorded_fs": sig.fs, **sig.meta})


def estimate_delay(measured: np.ndarray, reference: np.ndarray, fs: float,
                   max_delay: float = 0.05, around: float = 0.0) -> float:
    """Delay (s) of ``measured`` behind ``reference`` from the peak of their
    cross-correlation within ``around +- max_delay``, refined to a fraction of a sample by a
    parabola through the peak."""
    c = correlate(measured, reference, mode="full", method="fft")
    lags = np.arange(-len(reference) + 1, len(measured))
    window = np.abs(lags - around * fs) <= int(max_delay * fs)
    if not window.any():
        return float(around)
    if np.max(-c[window]) > 2.0 * max(np.max(c[window]), 0.0):
        raise SignalError("the excitation correlates negatively with the study's sweep "
                          "around its start: is the force channel's sign inverted?")
    c = np.where(window, c, -np.inf)
    i = int(np.argmax(c))
    if 0 < i < len(c) - 1 and np.isfinite(c[i - 1]) and np.isfinite(c[i + 1]):
        denom = c[i - 1] - 2 * c[i] + c[i + 1]
        frac = 0.5 * (c[i - 1] - c[i + 1]) / denom if denom != 0 else 0.0
    else:
        frac = 0.0
    return float((lags[i] + frac) / fs)


def align_to_ideal(meas: Measurement, excitation: Excitation, est: SweepEstimate
                   ) -> Signals:
    """Resample to the excitation's rate, remove the delay against it (near the estimated
    start, refined by cross-correlation) and cut to its record length."""
    sig = meas.signals
    if abs(sig.fs - excitation.fs) > 1e-6 * excitation.fs:
        meas.notes.append(f"resampled from {sig.fs:g} Hz to {excitation.fs:g} Hz")
        sig = resample(sig, excitation.fs)
    ideal = excitation.force()
    limit = 0.002
    try:
        delay = estimate_delay(sig.force - est.offset, ideal, sig.fs, max_delay=limit,
                               around=est.t_start)
    except SignalError as err:
        raise MeasurementError(meas.file, str(err), "force") from None
    shift = round(delay * sig.fs)
    if shift:
        meas.notes.append(f"removed a delay of {delay * 1e3:.3f} ms ({shift} samples)")
    if abs(delay - est.t_start) >= limit - 1.5 / sig.fs:
        meas.notes.append(f"the delay found lies on its search limit ({est.t_start * 1e3:.3g} "
                          f"+- {limit * 1e3:g} ms, the sweep's estimated start): the alignment "
                          "is not to be trusted")
    n = excitation.n_samples
    missing = n - (len(sig.force) - shift)
    if missing > max(2, 0.1 * (excitation.n_samples - excitation.sweep_end * sig.fs)):
        # the study's record (sweep + tail) reaches beyond the measured one: zeros in place
        # of the ring-down the model computes (1.4 dB at the sweep's end of the 2-DOF
        # model's quick chirp for a 0.05 s tail cut off)
        meas.warnings.append(f"the record ends {missing / sig.fs:.4g} s before the study's "
                             f"({excitation.n_samples / excitation.fs:.4g} s: sweep and tail) "
                             "and is padded with zeros: its ring-down after the sweep is "
                             "missing where the model's is not (the FRF near the sweep's end "
                             "is biased); record longer, or shorten the study's tail")
        meas.notes.append(meas.warnings[-1])

    def cut(x):
        x = x[shift:] if shift >= 0 else np.concatenate([np.zeros(-shift), x])
        if len(x) < n:
            x = np.concatenate([x, np.zeros(n - len(x))])
        return x[:n]

    t = excitation.time()
    return Signals(t=t, force=cut(sig.force - est.offset),
                   channels={k: cut(v) for k, v in sig.channels.items()}, fs=excitation.fs,
                   f_inst=excitation.f_inst(t), units=dict(sig.units),
                   meta={**sig.meta, "delay_s": delay}, sweep_end=excitation.sweep_end)


def measured_drive(meas: Measurement, est: SweepEstimate, level: float) -> SampledForce:
    """The measured record (offset removed) as the model's excitation; attaches the
    measured instantaneous frequency to the measurement's signals where it is a sweep, and
    the steps (:func:`sensfw.signal.stepped.detect_steps`) where it is a stepped sine."""
    sig = meas.signals
    record = sig.force - est.offset
    sweep = ({"kind": est.kind, "f0": est.f0, "f1": est.f1, "t_start": est.t_start,
              "t_end": est.t_end} if est.is_sweep else None)
    if est.kind == "stepped_sine":
        try:
            steps = detect_steps(record, sig.fs)
        except SignalError as err:
            raise MeasurementError(meas.file, f"a stepped sine whose steps cannot be told "
                                              f"apart: {err}", "force") from None
        sweep = {"kind": "stepped_sine", "starts": [s.start for s in steps],
                 "frequencies": [s.frequency for s in steps], "t_end": steps[-1].end}
        f = [s.frequency for s in steps]
        meas.notes.append(f"{len(steps)} steps found, {min(f):.4g}-{max(f):.4g} Hz, "
                          f"{direction_of(f) or 'neither up nor down'}")
    drive = SampledForce(record, sig.fs, amplitude=level, signal_unit=meas.input_unit,
                         sweep=sweep)
    meas.signals = replace(sig, force=record, f_inst=drive.f_inst(sig.t),
                           sweep_end=drive.sweep_end if sweep else None)
    return drive


def require_gain(meas: Measurement, study) -> None:
    if meas.input_unit != "N" and "excitation_gain" not in study.parameters:
        raise MeasurementError(meas.file, f"the excitation is recorded in {meas.input_unit}: "
                               "the study needs [excitation] gain (N per "
                               f"{meas.input_unit}) to drive the model with it", "force")


def random_level(meas: Measurement, band: tuple[float, float]) -> None:
    """A random record's level is its RMS in the band: a note says so, in place of the
    loader's comparison of a nominal level with a sine amplitude it does not have."""
    rms = band_rms(meas.signals.force - np.mean(meas.signals.force), meas.fs, band)
    meas.notes[:] = [n for n in meas.notes if "sweep amplitude" not in n]
    named = meas.signals.meta.get("level_from")
    meas.notes.append(f"random excitation, RMS {amount(rms, meas.input_unit)} in {band[0]:g}-"
                      f"{band[1]:g} Hz" + (f" (the {named}'s {meas.level:g} is the rig's "
                                           f"setting, not an amplitude)"
                                           if named not in (None, "amplitude") else ""))


def prepare(meas: Measurement, study) -> Measurement:
    """Checks, excitation estimate, drive decision and alignment (module docstring): what
    every measurement command does first. An FRF-only measurement is driven by a stepped
    sine on its lines (:func:`sensfw.measure.lines.frf_drive`)."""
    require_channels(meas, [study.output])
    if meas.frf is None:
        require_units(meas, study.model)
    ex = study.excitation
    if meas.frf is not None:
        require_gain(meas, study)
        meas.drive = frf_drive(meas, study)
        return meas
    check_channels(meas, [c for c in meas.signals.channels if c in study.model.sensors])
    sig = meas.signals
    span = len(sig.force) / sig.fs
    if span < 2.0 / ex.f0:
        raise MeasurementError(meas.file, f"the record is {span:.3g} s long ({len(sig.force)} "
                               f"samples), less than two periods of the study's lowest "
                               f"frequency, {ex.f0:g} Hz: too short for its FRF", "time")
    if sig.fs / ALIAS_FREE <= ex.f0:
        raise MeasurementError(meas.file, f"sampled at {sig.fs:.4g} Hz, it holds no line of "
                               f"the study's band {ex.f0:g}-{ex.f1:g} Hz (its lines end at "
                               f"fs / {ALIAS_FREE:g} = {sig.fs / ALIAS_FREE:.4g} Hz); if the "
                               "time column is in ms, say so in its header: 'time [ms]'",
                               "time")
    if sig.fs < ex.fs * (1 - 1e-6) and sig.fs / ALIAS_FREE < ex.f1:
        meas.notes.append(f"sampled at {sig.fs:g} Hz: it holds no lines above "
                          f"{sig.fs / ALIAS_FREE:.4g} Hz (fs / {ALIAS_FREE:g}, the anti-aliasing "
                          f"filter's pass band), below the study's {ex.f1:g} Hz; compare's "
                          "error leaves them out")
    try:
        est = estimate_sweep(sig.force, sig.fs, band=(ex.f0, ex.f1))
    except ValueError as err:  # scipy's filters on a record too short for them
        raise MeasurementError(meas.file, f"cannot read the excitation ({len(sig.force)} "
                               f"samples at {sig.fs:.4g} Hz): {err}", "force") from None
    if est.kind == "silent":
        raise MeasurementError(meas.file, "the excitation channel is silent", "force")
    meas.sweep = est
    level = meas.level if meas.level is not None else est.amplitude
    # a declared level the record contradicts: it drives the ideal sweep (below), so a
    # wrong one drives the model too hard or too soft (a measured drive only labels it)
    contradicted = (meas.level is not None and est.is_sweep and est.amplitude > 0
                    and abs(est.amplitude / meas.level - 1) > LEVEL_TOLERANCE)
    if meas.level is None:
        meas.notes.append(f"excitation level estimated from the record: {level:.4g} "
                          f"{meas.input_unit}")
    meas.level = float(level)
    if est.kind == "random":
        random_level(meas, (ex.f0, ex.f1))
    slow = sig.fs < ex.fs * (1 - 1e-6)
    mismatch = sweep_mismatch(est, ex, f_top=sig.fs / ALIAS_FREE if slow else None)
    if mismatch is None and est.drift > DRIFT_TOLERANCE:
        mismatch = f"its amplitude drifts by +-{est.drift:.0%}"
    voltage = meas.input_unit != "N"
    said = describe(est, meas.input_unit)
    require_gain(meas, study)
    if study.drive == "measured" or voltage or (mismatch and study.drive == "auto"):
        if mismatch and study.drive == "auto":
            meas.notes.append(f"the excitation is not the study's ({mismatch}): estimated "
                              f"{said}; the model is driven by the measured record")
        elif (est.is_sweep and hasattr(ex, "f1")
              and (est.f1 < ex.f0 or est.f0 > ex.f1
                   or min(est.f1, ex.f1) - max(est.f0, ex.f0)
                   < 0.5 * (ex.f1 - ex.f0))):
            meas.warnings.append(f"the record sweeps {est.f0:.4g} -> {est.f1:.4g} Hz, less than "
                                 f"half of the study's band {ex.f0:g}-{ex.f1:g} Hz: the model "
                                 "is driven by the record, but the comparison sees little of "
                                 "the band (the export's sample rate?)")
            meas.notes.append(meas.warnings[-1])
            meas.notes.append(f"the model is driven by the measured record ({said})")
        else:
            meas.notes.append(f"the model is driven by the measured record ({said})")
        if sig.fs < ex.fs * (1 - 1e-6):  # the model's output sampled as slowly would alias
            meas.notes.append(f"resampled from {sig.fs:g} Hz to the study's {ex.fs:g} Hz, so "
                              "the model's response is sampled as the study's")
            meas.signals = resample(sig, ex.fs)
        meas.drive = measured_drive(meas, est, meas.level)
        return meas
    if mismatch:  # drive = "ideal" asked for explicitly
        raise MeasurementError(meas.file, f"the excitation is not the study's ({mismatch}): "
                               f"estimated {said}; set [excitation] drive = "
                               "\"auto\" or \"measured\" to drive the model with the record",
                               "force")
    length = len(sig.force) / sig.fs - est.t_start
    if length < ex.duration * (1 - 1e-3):
        raise MeasurementError(meas.file, f"record is {length:.4g} s long after the sweep's "
                                          f"start, shorter than the {ex.duration:g} s sweep",
                               "force")
    if contradicted:
        meas.warnings.append(f"the declared level {meas.level:g} {meas.input_unit} is not the "
                             f"record's sweep amplitude, {est.amplitude:.4g} "
                             f"{meas.input_unit}: the model is driven at the declared level "
                             "(leave the level out to use the record's)")
        meas.notes.append(meas.warnings[-1])
    meas.drive = ex.with_amplitude(float(f"{meas.level:.4g}"))
    meas.signals = align_to_ideal(meas, ex, est)
    meas.notes.append(f"the record is the study's sweep ({said}); the model is "
                      "driven by the ideal sweep at the measured level")
    return meas
