"""The exponential sweep (Sect. 2.3, Eqs. 7 and 17)."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.excitation import Chirp, chirp_phase, log_chirp


def test_instantaneous_frequency_is_f0_exp_kt_and_ends_at_f1():
    f0, f1, T, fs = 50.0, 5000.0, 1.0, 200000.0
    t, force, f_inst = log_chirp(f0, f1, T, fs, amplitude=2.0)
    k = np.log(f1 / f0) / T
    np.testing.assert_allclose(f_inst, f0 * np.exp(k * t), rtol=1e-12)
    # d(phase)/dt / 2 pi equals f_inst (central differences, error O(dt^2))
    phase = chirp_phase(t, f0, f1, T)
    f_num = np.gradient(phase, t) / (2 * np.pi)
    np.testing.assert_allclose(f_num[1:-1], f_inst[1:-1], rtol=1e-6)
    assert chirp_frequency_at_end(f0, f1, T) == pytest.approx(f1, rel=1e-12)
    assert np.max(np.abs(force)) == pytest.approx(2.0, rel=1e-6)


def chirp_frequency_at_end(f0, f1, T):
    from sensfw.excitation import chirp_frequency

    return float(chirp_frequency(np.array([T]), f0, f1, T)[0])


def test_eq7_as_printed_does_not_end_at_f1():
    # Eq. 7: phase 2 pi f0 t (f1/f0)^(t/T); its frequency at t = T is f1 (1 + ln(f1/f0))
    f0, f1, T = 50.0, 5000.0, 1.0
    t = np.linspace(0.999, 1.0, 2001)
    phase = 2 * np.pi * f0 * t * (f1 / f0) ** (t / T)
    f_end = np.gradient(phase, t)[-1] / (2 * np.pi)
    assert f_end == pytest.approx(f1 * (1 + np.log(f1 / f0)), rel=1e-3)
    assert f_end > 5 * f1  # far from the intended end frequency; hence the exponential sweep


def test_chirp_object_with_tail():
    c = Chirp(50, 5000, 0.5, 20000, 1.5, tail=0.1)
    t = c.time()
    assert len(t) == 12000 and c.n_samples == 12000
    assert np.all(c.force()[t >= 0.5] == 0)
    np.testing.assert_allclose(c.f_inst()[t >= 0.5], 5000.0, rtol=1e-12)
    with pytest.raises(SignalError, match="Nyquist"):
        Chirp(50, 5000, 1.0, 8000)
    with pytest.raises(SignalError, match="0 < f0 < f1"):
        Chirp(500, 50, 1.0, 8000)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"kind": "random", "tail": -0.05}, r"random tail must be >= 0"),
    ({"kind": "stepped_sine", "tail": -0.1}, r"stepped_sine tail must be >= 0"),
    ({"kind": "log_chirp", "duration": 1e-5}, r"duration 1e-05 s holds 0 sample\(s\)"),
    ({"kind": "stepped_sine", "steps": 100000, "duration": 0.05},
     r"dwells 5e-07 s per step, less than two samples"),
    ({"kind": "random", "f0": 1010.0, "f1": 1020.0, "duration": 0.01},
     r"random band \[1010, 1020\] Hz holds no frequency line of a 0.01 s record \(lines "
     r"100 Hz apart\)"),
])
def test_excitations_that_cannot_be_made_are_refused(kwargs, message):
    """Each of these was accepted: a negative tail cut a stepped sine's last steps (or
    crashed a random one), a sweep of no sample gave a zero force (or a division by zero in
    the FRF scorer's check), a random band between two lines a NaN force reported as the
    model diverging."""
    from sensfw.excitation import make_excitation

    spec = {"f0": 50.0, "f1": 5000.0, "duration": 0.25, "fs": 20000.0, **kwargs}
    with pytest.raises(SignalError, match=message):
        make_excitation(spec)
