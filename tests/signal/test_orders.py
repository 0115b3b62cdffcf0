"""Order spectrum and THD on swept signals with known harmonics (issue 2, item 2)."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.excitation import chirp_phase, log_chirp
from sensfw.signal import (
    harmonic_amplitudes,
    order_map,
    order_spectrum,
    thd,
    thd_from_spectrum,
)

FS = 20000.0
A2, A3 = 0.1, 0.05


def swept(f1, a2=A2, a3=A3, f0=50.0, T=1.0):
    t, _, f_inst = log_chirp(f0, f1, T, FS)
    phi = chirp_phase(t, f0, f1, T)
    return np.sin(phi) + a2 * np.sin(2 * phi) + a3 * np.sin(3 * phi), f_inst


def test_order_amplitudes_are_rms_of_the_harmonics():
    x, fi = swept(2000.0)
    orders, P = order_spectrum(x, FS, fi)
    expected = {1: 1 / np.sqrt(2), 2: A2 / np.sqrt(2), 3: A3 / np.sqrt(2)}
    for k, v in expected.items():
        i = np.argmin(np.abs(orders - k))
        assert orders[i] == k
        assert P[i] == pytest.approx(v, rel=0.02)
    # between harmonics the spectrum is (numerically) empty: the flat-top window leaks
    # nothing farther than a few bins
    between = (np.abs(orders - np.round(orders)) > 0.3) & (orders > 0.5)
    assert np.max(P[between]) < 1e-3


def test_thd_equals_the_harmonic_ratio():
    x, fi = swept(2000.0)
    assert thd(x, FS, fi) == pytest.approx(100 * np.hypot(A2, A3), rel=0.02)
    assert thd(x, FS, fi, unit="dBc") == pytest.approx(10 * np.log10(A2**2 + A3**2), abs=0.2)
    assert thd(x, FS, fi, n_harmonics=2) == pytest.approx(100 * A2, rel=0.02)


def test_pure_chirp_has_no_distortion():
    x, fi = swept(2000.0, 0.0, 0.0)
    assert thd(x, FS, fi) < 0.5


def test_only_order_2_below_nyquist_at_5khz_as_in_the_paper():
    x, fi = swept(5000.0)
    orders, _, _M = order_map(x, FS, fi)
    assert orders[-1] == 2.0  # fs / (2 f1) = 2: order 3 would alias at the end of the sweep
    # THD is then 100 |P2| / |P1| = 10 %, not 100 sqrt(a2^2 + a3^2) = 11.2 %: order 3 is not
    # counted (at the end of the sweep it is at 15 kHz and aliases to 5 kHz in the sampled
    # signal itself, which moves P1 by ~0.1 %, hence the 1 % tolerance below)
    no3, fi = swept(5000.0, a3=0.0)
    assert thd(x, FS, fi) == pytest.approx(100 * A2, rel=0.02)
    assert thd(x, FS, fi) == pytest.approx(thd(no3, FS, fi), rel=0.01)
    with pytest.raises(SignalError, match="order 3 is above"):
        harmonic_amplitudes(x, FS, fi, harmonics=[3])


def test_amplitude_conventions():
    x, fi = swept(2000.0)
    _, rms = order_spectrum(x, FS, fi, amplitude="rms")
    _, peak = order_spectrum(x, FS, fi, amplitude="peak")
    _, power = order_spectrum(x, FS, fi, amplitude="power")
    assert peak[16] == pytest.approx(1.0, rel=0.02)  # order 1 at resolution 1/16
    np.testing.assert_allclose(peak[1:], np.sqrt(2) * rms[1:], rtol=1e-12)
    assert power[16] == pytest.approx(rms[16] ** 2, rel=1e-3)


def test_bad_inputs():
    x, fi = swept(2000.0)
    with pytest.raises(SignalError, match="x has 20000 samples but f_inst has 10"):
        order_spectrum(x, FS, fi[:10])
    with pytest.raises(SignalError, match="unknown amplitude"):
        order_spectrum(x, FS, fi, amplitude="loud")
    with pytest.raises(SignalError, match="order_resolution"):
        order_spectrum(x, FS, fi, order_resolution=0.3)


def test_thd_over_fewer_than_two_harmonics_is_an_error():
    """n_harmonics counts the fundamental: 1 (or 0) leaves no harmonic, and THD came out
    0 % and -inf dBc (with a RuntimeWarning). With 2 it is 100 A2 (A1 = 1), and the
    default takes every order below Nyquist: 100 sqrt(A2^2 + A3^2) = 11.18 %, both to
    1e-6 (flat-top amplitudes of stationary orders)."""
    x, fi = swept(2000.0)
    for n in (0, 1):
        for unit in ("percent", "dBc"):
            with pytest.raises(SignalError, match=f"n_harmonics must be >= 2.*got {n}"):
                thd(x, FS, fi, n_harmonics=n, unit=unit)
    assert thd(x, FS, fi, n_harmonics=2) == pytest.approx(100 * A2, rel=1e-6)
    assert thd(x, FS, fi) == pytest.approx(100 * np.hypot(A2, A3), rel=1e-6)


def test_bad_order_arguments_are_signal_errors():
    """order_resolution 0 raised ZeroDivisionError; harmonic 1.5 was read as order 1 (its
    amplitude 0.707 returned as if it were 1.5's) and order 0 was called 'above the highest
    unaliased order'; an order spectrum with P of another length raised IndexError."""
    x, fi = swept(2000.0)
    for res in (0.0, -1 / 16, float("nan")):
        with pytest.raises(SignalError, match="order_resolution must be 1/W"):
            order_map(x, FS, fi, order_resolution=res)
    for k in (0, 1.5):
        with pytest.raises(SignalError, match=f"integer orders >= 1, got {k}"):
            harmonic_amplitudes(x, FS, fi, harmonics=[k])
    assert harmonic_amplitudes(x, FS, fi, harmonics=[2.0])[2] == pytest.approx(
        A2 / np.sqrt(2), rel=1e-6)
    orders, P = order_spectrum(x, FS, fi)
    with pytest.raises(SignalError, match="equally long"):
        thd_from_spectrum(orders, P[:40])
    assert thd_from_spectrum(orders, P) == pytest.approx(100 * np.hypot(A2, A3), rel=1e-6)
