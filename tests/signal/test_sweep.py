"""The sweep estimate of a recorded excitation (sensfw.signal.sweep)."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.excitation import chirp_phase
from sensfw.signal.sweep import estimate_sweep

FS = 2000.0


def chirp(f0=10.0, f1=500.0, T=4.0, delay=0.25, tail=0.25):
    t = np.arange(round((delay + T + tail) * FS)) / FS
    u = np.clip(t - delay, 0.0, T)
    return np.where((t >= delay) & (t <= delay + T), np.sin(chirp_phase(u, f0, f1, T)), 0.0)


def test_a_log_chirp_is_read_back():
    """A 10-500 Hz log chirp of 4 s after 0.25 s of silence: kind, f0 and start to 0.1 %
    and 0.5 ms; f1 to 0.5 % (the end is the envelope's, not refined: a 0.1 ms error is
    0.1 % of f1 at k = ln(50) / 4 s)."""
    e = estimate_sweep(chirp() + 0.3, FS)
    assert e.kind == "log_chirp"
    assert e.f0 == pytest.approx(10.0, rel=1e-3)
    assert e.f1 == pytest.approx(500.0, rel=5e-3)
    assert e.t_start == pytest.approx(0.25, abs=5e-4)
    assert e.offset == pytest.approx(0.3, abs=1e-3)


def test_unreadable_records_are_signal_errors():
    """A NaN sample gave kind 'linear_sweep' with NaN frequencies (a sweep to the caller);
    a band above 0.45 fs and a record shorter than the filter's padding raised scipy's
    ValueError."""
    x = chirp()
    x[100] = np.nan
    with pytest.raises(SignalError, match="x contains NaN or inf"):
        estimate_sweep(x, FS)
    with pytest.raises(SignalError, match=r"band \(3000, 5000\) Hz is not below 0.45 fs"):
        estimate_sweep(chirp(), FS, band=(3000, 5000))
    with pytest.raises(SignalError, match="x has 20 samples, too few for the band-pass"):
        estimate_sweep(chirp()[600:620], FS)
    with pytest.raises(SignalError, match="sample rate"):
        estimate_sweep(chirp(), 0.0)


def test_a_downward_log_chirp_is_read_back():
    """A 500-10 Hz log chirp (the 10-500 Hz one's phase read backwards) was 'random'
    (residual 76 rad): the log model allowed k > 0 only. Now f0, f1 to 0.1 % and 0.5 %,
    start to 0.5 ms; an upward chirp is read as before."""
    T, delay = 4.0, 0.25
    t = np.arange(round((delay + T + 0.25) * FS)) / FS
    u = np.clip(t - delay, 0.0, T)
    phi = chirp_phase(np.full_like(u, T), 10.0, 500.0, T) - chirp_phase(T - u, 10.0, 500.0, T)
    x = np.where((t >= delay) & (t <= delay + T), np.sin(phi), 0.0)
    e = estimate_sweep(x, FS)
    assert e.kind == "log_chirp"
    assert e.f0 == pytest.approx(500.0, rel=1e-3)
    assert e.f1 == pytest.approx(10.0, rel=5e-3)
    assert e.t_start == pytest.approx(delay, abs=5e-4)
    assert e.frequency(np.array([delay + T / 2]))[0] == pytest.approx(np.sqrt(5000), rel=5e-3)
