"""FRF options for matching an analyser's settings: ``df`` and several records (issue 14,
item 5). The defaults are pinned by test_frf.py."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.signal import coherence, frf, octave_smooth, spectra

FS = 1024.0


@pytest.fixture(scope="module")
def frames():
    rng = np.random.default_rng(7)
    p = rng.standard_normal((4, 2048))
    h = np.array([0.5, 1.0, -0.3, 0.1])  # FIR "system": H(f) = sum h_k exp(-2 pi i f k / fs)
    x = np.array([np.convolve(r, h)[:2048] for r in p]) + 0.05 * rng.standard_normal(p.shape)
    return p, x, h


def test_df_is_the_segment_length(frames):
    p, x, _ = frames
    a = frf(p[0], x[0], FS, "H1", nperseg=512, window="hamming", noverlap=128)
    b = frf(p[0], x[0], FS, "H1", df=FS / 512, window="hamming", noverlap=128)
    for u, v in zip(a, b, strict=True):
        np.testing.assert_array_equal(u, v)
    assert b[0][1] - b[0][0] == pytest.approx(2.0)  # df = 2 Hz


def test_records_are_averaged_like_non_overlapping_segments(frames):
    # independent computation: the records laid end to end and cut back into record-long
    # Welch segments without overlap give the same segments, hence the same averages
    p, x, _ = frames
    f, spp, sxx, spx = spectra(p, x, FS, nperseg=2048, window="boxcar")
    g, qpp, qxx, qpx = spectra(p.ravel(), x.ravel(), FS, nperseg=2048, noverlap=0,
                               window="boxcar")
    np.testing.assert_array_equal(f, g)
    for a, b in ((spp, qpp), (sxx, qxx), (spx, qpx)):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-14 * np.max(np.abs(b)))


def test_averaged_records_recover_the_fir_response(frames):
    p, x, h = frames
    f, H, coh = frf(p, x, FS, "H1", df=4.0, window="hann", return_coherence=True)
    exact = np.polyval(h[::-1], np.exp(-2j * np.pi * f / FS))
    # 4 records x 15 half-overlapping Hann segments of 256 samples: with 5 % output noise
    # the H1 error is 1.6 % here (10 % allowed); one unaveraged full-record segment of one
    # record is off by up to 300 % in bins where the random input's |P| is small
    sel = np.abs(exact) > 0.3
    assert np.max(np.abs(H[sel] / exact[sel] - 1)) < 0.1
    assert np.median(coh) > 0.98


def test_option_errors():
    x = np.arange(2048.0) % 7
    with pytest.raises(SignalError, match=r"nperseg .* or df .*, not both"):
        frf(x, x, FS, nperseg=512, df=2.0)
    with pytest.raises(SignalError, match="does not divide fs"):
        frf(x, x, FS, df=3.0)
    with pytest.raises(SignalError, match=r"shape \(2, 1024\) but x_out has shape \(1, 2048\)"):
        frf(x.reshape(2, 1024), x.reshape(1, 2048), FS)
    with pytest.raises(SignalError, match="record 1 contains NaN"):
        y = x.reshape(2, 1024).copy()
        y[1, 5] = np.nan
        frf(y, y, FS)


def test_coherence_with_df(frames):
    p, x, _ = frames
    f, c = coherence(p[0], x[0], FS, df=8.0)
    assert f[1] == pytest.approx(8.0) and np.all((c >= 0) & (c <= 1 + 1e-12))


def test_bad_welch_settings_are_signal_errors(frames):
    """A negative overlap was accepted (segments with gaps); an overlap of a whole segment,
    an unknown window or a window array of the wrong length raised scipy's ValueError."""
    p, x, h = frames
    for kw, msg in [({"noverlap": -3}, "noverlap=-3 must be between 0 and nperseg - 1"),
                    ({"noverlap": 256}, "noverlap=256 must be between 0"),
                    ({"window": "nope"}, "window 'nope' for segments of 256 samples"),
                    ({"window": np.ones(100)}, "for segments of 256 samples")]:
        with pytest.raises(SignalError, match=msg):
            frf(p[0], x[0], FS, "H1", nperseg=256, **kw)
    # a valid overlap still gives the FIR's FRF (0.05 output noise, 15 segments of 256
    # with 128 overlap: random error ~ 0.05 / sqrt(15) = 0.013 per line; measured RMS
    # 0.015, largest of 129 lines 0.032)
    f, H = frf(p[0], x[0], FS, "H1", nperseg=256, noverlap=128)
    exact = np.exp(-2j * np.pi * np.outer(f, np.arange(4)) / FS) @ h
    assert np.sqrt(np.mean(np.abs(H - exact) ** 2)) < 0.02
    assert np.max(np.abs(H - exact)) < 0.05


def test_bad_spectrogram_settings_are_signal_errors():
    from sensfw.signal import spectrogram

    x = np.sin(2 * np.pi * 50 * np.arange(100) / FS)
    with pytest.raises(SignalError, match="noverlap=448 must be between 0 and nperseg - 1"):
        spectrogram(x, FS, noverlap=448)  # nperseg 512 shortened to the record's 100
    with pytest.raises(SignalError, match="window 'xx'"):
        spectrogram(x, FS, window="xx")


def test_octave_smooth_checks_its_arguments():
    """fraction 0 raised ZeroDivisionError and H of another length numpy's broadcast
    error. A flat |H| = 2 stays 2 to 1e-12 (energy average of a constant) from 1 Hz on;
    the 0 Hz bin has no octave around it and reads 0."""
    f = np.arange(0, 100, 0.5)
    np.testing.assert_allclose(octave_smooth(f, 2 * np.ones_like(f), 3)[2:], 2.0,
                               rtol=1e-12)
    for bad in (0, -3, float("nan")):
        with pytest.raises(SignalError, match=r"fraction .* must be > 0"):
            octave_smooth(f, np.ones_like(f), bad)
    with pytest.raises(SignalError, match="equally long"):
        octave_smooth(f, np.ones(9))


def test_a_sample_rate_that_is_no_number_is_a_signal_error(frames):
    """fs = 'abc' (a unit left in a string) or None raised float()'s ValueError/TypeError."""
    p, x, _ = frames
    for fs in ("abc", None, -1.0):
        with pytest.raises(SignalError, match="sample rate fs must be a positive number"):
            frf(p[0], x[0], fs)
