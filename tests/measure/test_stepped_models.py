"""Stepped sines on the shipped models (issue 27, item 5): simulated up and down on the shaft
model and on the beam, exported as FRF-only records, compared with the model that made them
and with the same model's swept FRF; and the BERT sweeps' ``FRF.mat`` on its own against
the calibrated beam. Simulation-heavy: every test is slow.

Measured on this branch (README "FRF-only and stepped-sine records"): the linear beam's
stepped and swept FRFs agree (a linear structure has one FRF); the micro-slip beam at 0.30 V
differs by up to 0.42 dB between up and down near its peak and by 0.66 dB RMS from its 5 Hz/s
sweep; the shaft model is near-linear at 0.01 N and at 0.1 N jumps: its up and down sweeps
take different branches, up to 14 dB apart over about 1350-1440 Hz.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from sensfw.evaluate import simulate, variant_spec
from sensfw.excitation import SteppedSine
from sensfw.measure.compare import compare_measurements
from sensfw.measure.io import FRFRecord, write_uff
from sensfw.measure.prepared import load_measurements
from sensfw.runs import Runner, RunStore
from sensfw.signal import frf
from sensfw.signal.stepped import stepped_frf, steps_of
from sensfw.study import Study

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.slow


def _bert_loop():
    """The calibrated beam models stored in test_bert_loop.py (one source for them)."""
    spec = importlib.util.spec_from_file_location("bert_loop", Path(__file__).with_name(
        "test_bert_loop.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


BERT_LOOP = _bert_loop()


def model_runs(study: Study, excitations, tmp: Path) -> list:
    """The study's model at its nominal values driven by each of ``excitations``: the runs
    in parallel (two workers), their signals in order."""
    specs = [variant_spec(study, {}, ex) for ex in excitations]
    with Runner(RunStore(tmp / "model-runs"), backend="processes", workers=2) as runner:
        signals, errors = simulate(runner, specs)
    assert all(sig is not None for sig in signals), errors
    return signals


def stepping(study: Study, level: float, lines, direction: str, dwell: float) -> SteppedSine:
    return SteppedSine.at(lines, dwell, study.excitation.fs, level, direction=direction,
                          signal_unit=study.excitation.unit)


def stepped(study: Study, sig, direction: str) -> FRFRecord:
    """The steady-state FRF record of a stepped-sine run ``sig`` of the study's model."""
    r = stepped_frf(sig.force, sig.channels, sig.fs, steps_of(sig.f_inst, sig.fs))
    return FRFRecord.checked("model", r.f, r.frf, {"force": study.excitation.unit,
                                                    **sig.units}, kind="stepped_sine",
                             direction=direction)


def up_down_swept(study: Study, level: float, lines, dwell: float, tmp: Path,
                  sweep: bool = True):
    """The study's model stepped up and down on ``lines`` at ``level`` (FRF records) and,
    with ``sweep``, the dB of its swept FRF at ``level`` (the study's sweep, Hv over the
    whole record, unsmoothed) at ``lines``: the three runs in parallel."""
    excitations = [stepping(study, level, lines, d, dwell) for d in ("up", "down")]
    if sweep:
        excitations.append(study.excitation.with_amplitude(level))
    up, down, *swept = model_runs(study, excitations, tmp)
    out = [stepped(study, up, "up"), stepped(study, down, "down")]
    for sig in swept:
        f, h = frf(sig.force, sig.channel(study.output), sig.fs, estimator="Hv")
        out.append(20 * np.log10(np.abs(np.interp(lines, f, h.real)
                                        + 1j * np.interp(lines, f, h.imag))))
    return out


def db(rec: FRFRecord, channel: str) -> np.ndarray:
    return 20 * np.log10(np.abs(rec.channel(channel)))


def compare_records(study: Study, records, tmp: Path):
    """``compare`` of the study's model with FRF-only records (a UFF file)."""
    path = write_uff(tmp / "records.uff", records)
    meas = load_measurements(study, [str(path)])
    with Runner(RunStore(tmp / "runs"), backend="processes", workers=2) as runner:
        return meas, compare_measurements(study, meas, runner)


def test_linear_beam_stepped_is_swept_and_compares_with_itself(tmp_path):
    """The calibrated linear beam at 0.05 V, 90-100 Hz in 0.5 Hz steps of 1.2 s (eleven
    decay times of its 0.0154 damping ratio at 97 Hz): up and down agree to 0.01 dB, and
    the stepped lines agree with the unsmoothed Hv of the study's sweep (exact for a linear
    model: the record holds the whole ring-down) to 0.05 dB. ``compare`` of the two records
    with the model, driven by its own stepped sine (eight decay times from the records'
    fit, not the records' 1.2 s), finds the same: error below 0.05 dB, the same resonance
    line, no jump."""
    study = Study.load(BERT_LOOP.calibrated_study(tmp_path, BERT_LOOP.LINEAR))
    lines = np.arange(90.0, 100.01, 0.5)
    up, down, sweep = up_down_swept(study, 0.05, lines, 1.2, tmp_path)
    assert np.max(np.abs(db(up, "Laser") - db(down, "Laser"))) < 0.01
    assert np.max(np.abs(db(up, "Laser") - sweep)) < 0.05
    meas, cmp = compare_records(study, [(up, 0.05), (down, 0.05)], tmp_path)
    assert all(m.drive.dwell != 1.2 for m in meas)
    for c in cmp.levels:
        assert c.error_db < 0.05, c.error_db
        assert [(r["measured_hz"], r["model_hz"]) for r in c.resonances if r["measured_hz"]
                and r["model_hz"]] == [(97.0, 97.0)]
    (j,) = cmp.jumps
    assert j["measured"]["hysteresis_hz"] is None and j["model"]["hysteresis_hz"] is None


def test_micro_slip_beam_up_down_and_sweep_differ(tmp_path):
    """The second round's micro-slip beam (AUGMENTED2) at 0.30 V, 88.5-94 Hz in 0.5 Hz
    steps of 0.85 s: up and down peak on the same line (91.5 Hz) and differ by 0.2-1 dB
    just below it (measured 0.42 dB at 90.5 Hz: the Iwan joint's hysteresis, no jump), and
    the stepped FRF differs from the unsmoothed Hv of the study's 5 Hz/s sweep by more than
    0.3 dB RMS (measured 0.66 over 86-100 Hz): the sweep of a nonlinear structure is not its
    steady state."""
    study = Study.load(BERT_LOOP.augmented_study(
        tmp_path, BERT_LOOP.AUGMENTED2, (("micro_slip", "joint"), ("dry_friction", "beam1"))))
    lines = np.arange(88.5, 94.01, 0.5)
    up, down, sweep = up_down_swept(study, 0.3, lines, 0.85, tmp_path)
    du, dd = db(up, "Laser"), db(down, "Laser")
    assert lines[np.argmax(du)] == lines[np.argmax(dd)] == 91.5
    diff = np.abs(du - dd)
    assert 0.2 < diff.max() < 1.0 and 89.5 <= lines[np.argmax(diff)] <= 91.5
    assert np.sqrt(np.mean((du - sweep) ** 2)) > 0.3


def test_shaft_model_near_linear_then_jumping(tmp_path):
    """The shaft model (studies/quick.toml) around its 1.5 kHz mode, 1300-1700 Hz in 10 Hz
    steps of 0.06 s. At 0.01 N it is nearly linear: up, down and the swept FRF (the study's
    0.25 s chirp, unsmoothed Hv) agree to 0.5 dB on every line of 1300-1650 Hz 30 Hz or more
    from the sharp peak at about 1505 Hz (measured: 0.31 dB at most; at the antiresonance
    near 1680 Hz the chirp's 3.7 Hz lines, interpolated, differ by up to 1.7 dB). At 0.1 N
    it jumps: the up sweep rises onto a branch about 27 dB high near 1450 Hz and falls off
    it near 1660 Hz, the down sweep stays on it down to about 1340 Hz: up and down differ by
    more than 10 dB over part of 1340-1450 Hz.
    ``compare`` of the 0.1 N records with the model reports that hysteresis for both."""
    study = Study.load(ROOT / "studies" / "quick.toml")
    lines = np.arange(1300.0, 1700.01, 10.0)
    ch = study.output
    up, down, sweep = up_down_swept(study, 0.01, lines, 0.06, tmp_path / "0.01")
    away = (np.abs(lines - 1505.0) >= 30.0) & (lines <= 1650.0)
    for rec in (up, down):
        assert np.max(np.abs(db(rec, ch) - sweep)[away]) < 0.5
    up, down = up_down_swept(study, 0.1, lines, 0.06, tmp_path / "0.1", sweep=False)
    diff = db(down, ch) - db(up, ch)
    branch = lines[diff > 10.0]
    assert len(branch) and branch.min() >= 1330.0 and branch.max() <= 1450.0, branch
    _, cmp = compare_records(study, [(up, 0.1), (down, 0.1)], tmp_path)
    (j,) = cmp.jumps
    for who in ("measured", "model"):
        lo, hi = j[who]["hysteresis_hz"]
        assert lo <= 1400.0 <= hi, (who, j[who])


def test_bert_frf_mat_alone_against_the_calibrated_beam(bert, tmp_path):
    """The 0.05 V sweep's FRF.mat on its own against the calibrated linear beam, error band
    80-105 Hz: 161 steps (every 4th line of 70-110 Hz), settled to 0.1 dB; resonance 95.50
    Hz measured (Test.Lab's H1 peak, as the data set's README says) against the model's
    97.00 Hz (as from the time record); the error within 0.25 dB of the time record's
    0.82 dB (measured 0.98: the same rig through LMS's H1 of a 5 Hz/s sweep instead of the
    smoothed Hv of the record)."""
    study = Study.load(BERT_LOOP.calibrated_study(tmp_path, BERT_LOOP.LINEAR))
    meas = load_measurements(study, [str(bert / "level_0p05" / "FRF.mat")])
    assert meas[0].drive.steps == 161
    with Runner(RunStore(tmp_path / "runs"), backend="processes", workers=2) as runner:
        cmp = compare_measurements(study, meas, runner, error_band=(80.0, 105.0))
    (c,) = cmp.levels
    assert c.settled_db["model"] < 0.1
    (r,) = [r for r in c.resonances if r["measured_hz"] and r["model_hz"]]
    assert (r["measured_hz"], r["model_hz"]) == (95.5, 97.0)
    assert abs(c.error_db - 0.82) < 0.25, c.error_db
