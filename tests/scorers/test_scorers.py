"""Each scorer returns its documented value on a constructed case (issue 2, item 3)."""

import numpy as np
import pytest

from sensfw.errors import SensfwError, UnknownPluginError
from sensfw.excitation import Chirp, chirp_phase
from sensfw.models.analytic import TwoDOF
from sensfw.models.base import Signals
from sensfw.plugins import scorers
from sensfw.scorers import make_scorer
from sensfw.signal import frf

EX = Chirp(50, 2000, 0.5, 20000, 1.0, tail=0.3)


@pytest.fixture(scope="module")
def run():
    m = TwoDOF()
    return m.simulate(m.parameters().nominal(), EX)


def scaled(sig, g):
    return Signals(t=sig.t, force=sig.force, channels={k: g * v for k, v in
                                                       sig.channels.items()},
                   fs=sig.fs, f_inst=sig.f_inst)


def test_frf_scalar_of_reference_is_zero(run):
    s = make_scorer("frf_scalar", channel="a1", band=[60.0, 1900.0])
    assert s.score(run, run)["value"] == 0.0


def test_frf_scalar_for_a_6db_gain_by_hand(run):
    s = make_scorer("frf_scalar", channel="a1", band=[60.0, 1900.0])
    _f, H = frf(run.force, run.channels["a1"], run.fs, estimator="Hv", fmin=60, fmax=1900)
    y0 = 20 * np.log10(np.abs(H))
    g_db = 20 * np.log10(2.0)
    # <y0 + g, y0> / <y0, y0> - 1 = g sum(y0) / sum(y0^2)
    expected = g_db * y0.sum() / (y0 @ y0)
    got = s.score(scaled(run, 2.0), run)["value"]
    assert got == pytest.approx(expected, rel=1e-9)
    # and it depends on the dB reference level (documented caveat)
    s2 = make_scorer("frf_scalar", channel="a1", band=[60.0, 1900.0], db_ref=1e-3)
    assert s2.score(scaled(run, 2.0), run)["value"] != pytest.approx(got, rel=0.1)


def test_frf_db_rms_of_a_6db_gain(run):
    s = make_scorer("frf_db_rms", channel="a1", band=[60.0, 1900.0])
    assert s.score(scaled(run, 2.0), run)["value"] == pytest.approx(20 * np.log10(2), rel=1e-9)
    s2 = make_scorer("frf_db_rms", channel="a1", band=[60.0, 1900.0], db_ref=1e-3)
    assert s2.score(scaled(run, 2.0), run)["value"] == pytest.approx(20 * np.log10(2),
                                                                      rel=1e-9)


def harmonic_signals(a2):
    t = EX.time()
    phi = chirp_phase(np.minimum(t, EX.duration), EX.f0, EX.f1, EX.duration)
    on = t < EX.duration
    x = np.where(on, 0.8 * np.sin(phi) + a2 * np.sin(2 * phi), 0.0)
    return Signals(t=t, force=EX.force(t), channels={"y": x}, fs=EX.fs, f_inst=EX.f_inst(t))


def test_order_amplitude_thd_and_rms():
    # only the sweep (not the silent tail) carries the harmonics; the tail frames carry
    # nothing, so score a record without tail
    ex = Chirp(50, 2000, 0.5, 20000, 1.0)
    t = ex.time()
    phi = chirp_phase(t, ex.f0, ex.f1, ex.duration)
    x = 0.8 * np.sin(phi) + 0.08 * np.sin(2 * phi)
    sig = Signals(t=t, force=ex.force(t), channels={"y": x}, fs=ex.fs, f_inst=ex.f_inst(t))
    assert make_scorer("order_amplitude", order=1).score(sig)["value"] == pytest.approx(
        0.8 / np.sqrt(2), rel=0.02)
    assert make_scorer("order_amplitude", order=2).score(sig)["value"] == pytest.approx(
        0.08 / np.sqrt(2), rel=0.02)
    assert make_scorer("thd").score(sig)["value"] == pytest.approx(10.0, rel=0.02)
    rms = np.sqrt(np.mean(x**2))
    assert make_scorer("rms", channel="y").score(sig)["value"] == pytest.approx(rms, rel=1e-12)


def test_unknown_scorer_and_bad_options_are_clear():
    with pytest.raises(UnknownPluginError, match=r"unknown scorer 'thdd'; available: .*thd"):
        scorers.get("thdd")
    with pytest.raises(SensfwError,
                       match="scorer 'thd': harmonics: unknown option; known: detrend"):
        make_scorer("thd", harmonics=3)
    with pytest.raises(SensfwError, match="order must be an integer >= 1"):
        make_scorer("order_amplitude", order=0)
    with pytest.raises(SensfwError, match="band must be"):
        make_scorer("frf_scalar", band=[5000.0, 50.0])
    with pytest.raises(SensfwError, match="no channel 'nope'"):
        make_scorer("rms", channel="nope").score(harmonic_signals(0.1))
    with pytest.raises(SensfwError, match=r"needs.*reference|compares with a reference"):
        make_scorer("frf_scalar").score(harmonic_signals(0.1))


def test_frf_scorers_refuse_a_band_without_lines_and_an_infinite_eps(run):
    """A band above the signals' Nyquist frequency (10 kHz here; the check against the
    study's excitation does not see a record at another rate) gave NaN (the mean of
    nothing); eps = inf gave an all-NaN Hv ((inf + inf) / inf) reported as 'no excitation'.
    Both are errors naming the option."""
    for name in ("frf_scalar", "frf_db_rms"):
        s = make_scorer(name, channel="a1", band=[12000.0, 15000.0])
        with pytest.raises(SensfwError, match=r"band \[12000, 15000\] Hz holds no line"):
            s.score(run, run)
        with pytest.raises(SensfwError, match="eps must be"):
            make_scorer(name, channel="a1", eps=float("inf"))
    with pytest.raises(SensfwError, match="eps must be a finite number > 0"):
        frf(run.force, run.channels["a1"], run.fs, eps=np.inf)
    # a large finite eps is H2 (eps -> inf), within 1e-9 relative where |Spx| > 0
    _f, h2 = frf(run.force, run.channels["a1"], run.fs, estimator="H2", nperseg=2048,
                fmin=60, fmax=1900)
    _, hv = frf(run.force, run.channels["a1"], run.fs, eps=1e15, nperseg=2048, fmin=60,
                fmax=1900)
    assert np.max(np.abs(hv / h2 - 1)) < 1e-9


def test_rms_and_value_refuse_nan_and_empty_channels():
    """A NaN sample made the RMS and the mean NaN (a score table entry, silently); an
    empty channel gave NaN and a RuntimeWarning. RMS of a sine of amplitude 2 with a DC
    offset of 0.5: sqrt(0.5^2 + 2^2 / 2) (Parseval), to 1e-12 on 200 whole periods."""
    t = np.arange(20000) / 1000.0
    x = 0.5 + 2 * np.sin(2 * np.pi * 10 * t)
    sig = Signals(t=t, force=x, channels={"y": x}, fs=1000.0)
    assert make_scorer("rms", channel="y").score(sig)["value"] == pytest.approx(
        np.sqrt(0.25 + 2.0), rel=1e-12)
    bad = Signals(t=t, force=x, channels={"y": np.where(t > 3, np.nan, x)}, fs=1000.0)
    for name in ("rms", "value"):
        with pytest.raises(SensfwError, match=rf"scorer '{name}': channel 'y' contains NaN"):
            make_scorer(name, channel="y").score(bad)
        empty = Signals(t=t[:0], force=x[:0], channels={"y": x[:0]}, fs=1000.0)
        with pytest.raises(SensfwError, match="has 0 samples"):
            make_scorer(name, channel="y").score(empty)


def test_frf_scorers_name_the_signal_that_is_zero(run):
    """A response channel of zeros (a sensor not connected) was reported as 'no excitation
    there?', blaming the force; each zero signal is named."""
    quiet = Signals(t=run.t, force=run.force, channels={**run.channels,
                                                        "a1": 0 * run.channels["a1"]},
                    fs=run.fs)
    silent = Signals(t=run.t, force=0 * run.force, channels=run.channels, fs=run.fs)
    for name in ("frf_scalar", "frf_db_rms"):
        s = make_scorer(name, channel="a1", band=[60.0, 1900.0])
        with pytest.raises(SensfwError, match="channel 'a1' is zero throughout"):
            s.score(quiet, run)
        with pytest.raises(SensfwError, match="the force is zero throughout"):
            s.score(silent, run)
        assert s.score(run, run)["value"] == 0.0


def test_signals_without_a_sensor_channel_are_a_scorer_error():
    """Signals holding the force only: the default channel (the first sensor) raised a bare
    StopIteration from every scorer; the force itself can still be named (its RMS: 1)."""
    t = np.arange(100) / 100.0
    s = Signals(t=t, force=np.ones(100), channels={}, fs=100.0)
    for name in ("rms", "value", "thd", "order_amplitude", "frf_scalar", "frf_db_rms"):
        with pytest.raises(SensfwError, match=f"scorer '{name}': the signals hold no sensor"):
            make_scorer(name).score(s, s)
    assert make_scorer("rms", channel="force").score(s)["value"] == 1.0
