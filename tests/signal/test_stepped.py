"""Stepped-sine analysis (sensfw.signal.stepped): the steady-state response per step, and the
steps of a recorded stepped sine."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.excitation import SteppedSine, make_excitation
from sensfw.models.analytic import TwoDOF
from sensfw.signal.stepped import (
    Step,
    detect_steps,
    direction_of,
    step_amplitudes,
    stepped_frf,
    steps_of,
)

FS = 5000.0
#: both modes of the 2-DOF model (225 and 450 Hz, damping ratios 0.018 and 0.035: decay
#: times 1 / (zeta omega) of 0.04 and 0.01 s) and the lines between them
LINES = np.linspace(150, 550, 21)


def simulate(ex):
    m = TwoDOF()
    p = m.parameters().nominal()
    return m, p, m.simulate(p, ex)


def steady_state(m, p, f, fs):
    """The steady-state response per unit force of the 2-DOF model as simulated: its
    first-order-hold discretisation at ``fs`` (as ``TwoDOF.simulate``) evaluated at
    ``z = exp(i 2 pi f / fs)``, ``Cd (z I - Ad)^-1 Bd + Dd``: independent of the stepped
    sine and free of the discretisation's own error against the closed form."""
    from scipy.signal import cont2discrete

    M, K, C = m.matrices(m.parameters().complete(p))
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ K, -Mi @ C]])
    B = np.vstack([np.zeros((2, 1)), Mi @ np.array([[1.0], [0.0]])])
    Co = np.hstack([-Mi @ K, -Mi @ C])
    Ad, Bd, Cd, Dd, _ = cont2discrete((A, B, Co, Mi @ np.array([[1.0], [0.0]])), 1 / fs,
                                      method="foh")
    z = np.exp(2j * np.pi * np.asarray(f) / fs)
    return np.array([(Cd @ np.linalg.solve(zi * np.eye(4) - Ad, Bd) + Dd)[:, 0] for zi in z])


@pytest.mark.parametrize("direction", ["up", "down"])
def test_stepped_frf_of_a_linear_model_is_its_steady_state(direction):
    """Steps of 0.6 s, half of it to settle: the slowest decay (0.04 s) has fallen by
    e^-7.5 before the fit. Every line agrees with the model's steady state
    (:func:`steady_state`) to 0.005 dB and 0.001 rad, in either direction, even at a1's
    antiresonance; and with the closed-form FRF to the simulation's own discretisation
    (0.007 dB below 200 Hz at 20 kHz; 0.1 dB at the antiresonance, where little moves)."""
    ex = SteppedSine.at(LINES, 0.6, FS, 0.5, direction=direction)
    m, p, sig = simulate(ex)
    steps = steps_of(sig.f_inst, sig.fs)
    assert [s.frequency for s in steps] == list(ex.frequencies())
    r = stepped_frf(sig.force, sig.channels, sig.fs, steps)
    assert r.direction == direction
    ref = steady_state(m, p, r.f, FS)
    for i, ch in enumerate(("a1", "a2")):
        ratio = r.frf[ch] / ref[:, i]
        assert np.max(np.abs(20 * np.log10(np.abs(ratio)))) < 0.005, ch
        assert np.max(np.abs(np.angle(ratio))) < 0.001, ch
        assert np.max(np.abs(r.settled_db[ch])) < 0.01, ch


def test_a_step_that_has_not_settled_says_so():
    """Steps of 20 ms (10 ms to settle, a quarter of the first mode's decay time): the transient
    is still in the fitted periods, and the first and last half of them differ."""
    ex = SteppedSine.at(LINES, 0.02, FS, 0.5)
    m, p, sig = simulate(ex)
    r = stepped_frf(sig.force, sig.channels, sig.fs, steps_of(sig.f_inst, sig.fs))
    err = np.abs(20 * np.log10(np.abs(r.frf["a1"] / steady_state(m, p, r.f, FS)[:, 0])))
    assert err.max() > 0.1 and np.nanmax(np.abs(r.settled_db["a1"])) > 0.1


def test_harmonics_come_with_the_fundamental():
    """A response with 10 % third and 3 % second harmonic (phases arbitrary): the fit over
    whole periods returns them exactly, and the fundamental is untouched."""
    fs, f = 1024.0, 97.25
    t = np.arange(int(2 * fs)) / fs
    w = 2 * np.pi * f * t
    x = 2 * np.cos(w + 0.3) + 0.06 * np.cos(2 * w - 1) + 0.2 * np.cos(3 * w + 2) + 0.5
    whole, halves = step_amplitudes(x, fs, Step(0.0, 2.0, f))
    np.testing.assert_allclose(whole, [2 * np.exp(0.3j), 0.06 * np.exp(-1j),
                                       0.2 * np.exp(2j)], atol=1e-9)
    np.testing.assert_allclose(halves, [whole, whole], atol=1e-9)
    with pytest.raises(SignalError, match="less than one period"):
        step_amplitudes(x, fs, Step(0.0, 0.01, f))


@pytest.mark.parametrize(("lines", "dwell", "fs"), [
    (np.linspace(60, 200, 57), 0.2, 20000.0),       # 1.3-4 % steps
    (np.arange(85, 105.01, 0.25), 0.4, 1024.0),     # 0.25 Hz steps at the beam's rate
    (np.arange(1300, 1700, 10.0), 0.04, 20000.0),   # 40 ms steps
])
@pytest.mark.parametrize("direction", ["up", "down"])
def test_detect_steps_in_a_noisy_record(lines, dwell, fs, direction):
    """A recorded stepped sine with 5 % noise and an offset: every step found, its
    frequency within 1e-3 (relative) and its end within 0.5 ms, or 8 % of its dwell where
    two phase lines of nearly the same slope meet (0.25 Hz steps: up to 6.1 % measured;
    the fitted last half then holds up to 12 % of the next step, whose line differs from
    this one's by a few per cent at most near a resonance: an error of a few 0.01 dB). The analysis
    fits the step's last half, so its start matters little."""
    ex = SteppedSine.at(lines, dwell, fs, 0.05, direction=direction)
    x = ex.force()
    x = x + 0.05 * np.std(x) * np.random.default_rng(3).standard_normal(len(x)) + 0.01
    found = detect_steps(x, fs)
    true = steps_of(ex.f_inst(), fs)
    assert len(found) == len(true)
    assert direction_of([s.frequency for s in found]) == direction
    for a, b in zip(found, true, strict=True):
        assert a.frequency == pytest.approx(b.frequency, rel=1e-3)
    for a, b in zip(found[:-1], true[:-1], strict=True):
        assert abs(a.end - b.end) < max(0.08 * dwell, 5e-4)


def test_steps_of_a_sweep_is_none_and_the_excitation_round_trips():
    from sensfw.excitation import LinearSweep

    sweep = LinearSweep(70, 110, 1.0, 1024.0)
    assert steps_of(sweep.f_inst(), sweep.fs) is None
    ex = SteppedSine.at([100, 90, 95], 0.1, 1000.0, direction="down")
    assert list(ex.frequencies()) == [100, 95, 90]
    assert make_excitation(ex.to_dict()) == ex
    # the log-spaced steps of a study keep the run hashes they had
    assert set(SteppedSine().to_dict()) == {"kind", "f0", "f1", "steps", "duration", "fs",
                                            "amplitude", "tail"}
    with pytest.raises(SignalError, match="direction"):
        SteppedSine(direction="sideways")


def test_a_step_past_the_record_is_an_error_not_a_fit_of_the_step_before():
    """A 1 s record at 97.3 Hz, then 200 Hz from 0.9 s; the 200 Hz step, claimed from 0.9
    to 1.5 s, was fitted (its last 50 %: 0.3 s) over 0.7-1.0 s of the record, two thirds
    of it on the 97.3 Hz step (amplitude 0.33 for 1): refused, naming the step and the
    record's end."""
    fs = 12345.6
    t = np.arange(round(fs)) / fs
    x = np.where(t < 0.9, np.cos(2 * np.pi * 97.3 * t), np.cos(2 * np.pi * 200 * t))
    with pytest.raises(SignalError, match=r"ends at 1\.5 s, after the record's end"):
        step_amplitudes(x, fs, Step(0.9, 1.5, 200.0))
    # a step that ends with the record is fitted as before: amplitude 1 within 1e-9
    whole, _ = step_amplitudes(x, fs, Step(0.9, len(t) / fs, 200.0))
    assert abs(whole[0]) == pytest.approx(1.0, abs=1e-9)


def test_stepped_frf_checks_its_records():
    """A response with a NaN gave a NaN line silently; a response of another length and
    orders without 1 raised numpy's and list's ValueError. A clean record: the line of
    0.5 cos(...) over cos(...) is 0.5 to 1e-12."""
    fs = 5000.0
    t = np.arange(5000) / fs
    force = np.cos(2 * np.pi * 120 * t)
    steps = [Step(0.0, 1.0, 120.0)]
    assert stepped_frf(force, {"y": 0.5 * force}, fs, steps).frf["y"][0] == pytest.approx(
        0.5, abs=1e-12)
    with pytest.raises(SignalError, match="response 'y' contains NaN"):
        stepped_frf(force, {"y": np.where(t > 0.7, np.nan, force)}, fs, steps)
    with pytest.raises(SignalError, match="force has 5000 samples but response 'y' has 4990"):
        stepped_frf(force, {"y": force[:-10]}, fs, steps)
    with pytest.raises(SignalError, match=r"orders \(2, 3\) must hold 1"):
        stepped_frf(force, {"y": force}, fs, steps, orders=(2, 3))
