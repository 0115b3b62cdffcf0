"""Single-mode fit of an FRF (sensfw.signal.modal.sdof_fit) against exact modal parameters:
around a peak (half-width from the damping) and over a given wide band."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.excitation import Chirp
from sensfw.measure.compare import resonances
from sensfw.models.analytic import TwoDOF
from sensfw.signal import frf, octave_smooth
from sensfw.signal.modal import sdof_fit

MODEL = TwoDOF()
P = MODEL.parameters().nominal()


def exact_modes():
    """Natural frequencies (Hz) and damping ratios from the state matrix's eigenvalues."""
    M, K, C = TwoDOF.matrices(P)
    A = np.block([[np.zeros((2, 2)), np.eye(2)],
                  [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0]
    fn, zeta = np.abs(lam) / (2 * np.pi), -lam.real / np.abs(lam)
    order = np.argsort(fn)
    return fn[order], zeta[order]


def test_analytic_sdof_frf_is_recovered_exactly():
    f = np.arange(100.0, 400.0, 2.0)
    fn, zeta, A, B = 250.0, 0.012, 3.0 - 1.0j, 0.02 + 0.01j
    H = A / (fn**2 - f**2 + 2j * zeta * fn * f) + B
    fit = sdof_fit(f, H, 248.0, 0.02)
    assert fit.frequency == pytest.approx(fn, rel=1e-6)
    assert fit.damping_ratio == pytest.approx(zeta, rel=1e-5)
    assert fit.residue == pytest.approx(A, rel=1e-5)
    assert fit.r2 == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("noise", [0.0, 0.05])
def test_short_chirp_two_dof_modes_within_half_a_percent_and_ten_percent(noise):
    """A 0.15 s chirp with a 0.02 s tail (the quick study's record): the fit of the
    unsmoothed FRF finds both modes within 0.05 % in frequency and 10 % in damping (the
    record's resolution is 5.9 Hz, 3 lines per half-power band of the first mode; the
    truncated ring-down biases the damping a few per cent), while the half-power bandwidth of
    the 1/24-octave smoothed FRF overestimates the first mode's damping by more than 20 %
    (its smoothing window is as wide as the peak)."""
    fn, zeta = exact_modes()
    ex = Chirp(50, 2000, 0.15, 20000.0, 1.0, tail=0.02)
    sig = MODEL.simulate(P, ex)
    y = sig.channels["a1"]
    y = y + noise * np.std(y) * np.random.default_rng(3).standard_normal(len(y))
    f, H = frf(sig.force, y, sig.fs, estimator="Hv")
    sel = (f >= 50) & (f <= 2000)
    db = 20 * np.log10(octave_smooth(f, H, 24)[sel])
    peaks = resonances(f[sel], db)
    assert len(peaks) == 2
    for p, f_true, z_true in zip(peaks, fn, zeta, strict=True):
        fit = sdof_fit(f, H, p["frequency"], p["damping_ratio"])
        assert fit.frequency == pytest.approx(f_true, rel=5e-4)
        assert fit.damping_ratio == pytest.approx(z_true, rel=0.10)
        assert fit.r2 > 0.99
    assert peaks[0]["damping_ratio"] > 1.2 * zeta[0]


def test_bad_inputs_are_signal_errors():
    f = np.arange(100.0, 400.0, 2.0)
    H = 1.0 / (250.0**2 - f**2 + 2j * 0.01 * 250.0 * f)
    with pytest.raises(SignalError, match="outside"):
        sdof_fit(f, H, 500.0)
    with pytest.raises(SignalError, match="equally long"):
        sdof_fit(f, H[:-1], 250.0)
    with pytest.raises(SignalError, match="frequency lines"):
        sdof_fit(f, H, 250.0, half_width=3.0)
    with pytest.raises(SignalError, match="f_peak or band"):
        sdof_fit(f, H)


def two_modes(f, quantity_power, noise=0.0, seed=0):
    """An FRF of two modes (95 Hz, zeta 1.5 %; 310 Hz, zeta 1 %) at 1/16 Hz resolution (the
    UNESP-BERT beam's records), of displacement, velocity or acceleration."""
    w = 2 * np.pi * f
    H = sum((1j * w) ** quantity_power * R / (wn**2 - w**2 + 2j * z * wn * w)
            for wn, z, R in ((2 * np.pi * 95.0, 0.015, 3.0e4 - 1.0e4j),
                             (2 * np.pi * 310.0, 0.01, 8.0e4)))
    rng = np.random.default_rng(seed)
    return H * (1 + noise * (rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))))


@pytest.mark.parametrize(("quantity", "power"), [("displacement", 0), ("velocity", 1),
                                                 ("acceleration", 2)])
def test_wide_band_recovers_the_mode_with_the_other_one_as_residual(quantity, power):
    f = np.arange(70.0, 110.0, 1 / 16)
    fit = sdof_fit(f, two_modes(f, power), band=(86.0, 104.0), quantity=quantity,
                   residual_terms=2)
    # the second mode is a smooth residual (B + i w C) over the band: the fit is exact to
    # the curvature it leaves, < 1e-4 of the frequency and 1 % of the damping
    assert fit.frequency == pytest.approx(95.0, rel=1e-4)
    assert fit.damping_ratio == pytest.approx(0.015, rel=0.01)
    # the residue of Eq. 1 (denominator in Hz^2) is the built one (denominator in
    # (rad/s)^2) over (2 pi)^2; to 0.1 % (the same residual curvature)
    assert fit.residue * (2 * np.pi) ** 2 == pytest.approx(3.0e4 - 1.0e4j, rel=1e-3)
    assert fit.r2 > 1 - 1e-6
    assert fit.peak_frequency == pytest.approx(95.0, abs=1 / 16)


def test_wide_band_noise_leaves_the_estimate_within_a_fraction_of_the_resolution():
    f = np.arange(70.0, 110.0, 1 / 16)
    fit = sdof_fit(f, two_modes(f, 1, noise=0.02), band=(86.0, 104.0), quantity="velocity",
                   residual_terms=2)
    # 2 % complex noise per bin over ~290 bins: the frequency to ~0.01 Hz (a sixth of the
    # 1/16 Hz resolution), the damping to a few per cent
    assert abs(fit.frequency - 95.0) < 0.01
    assert fit.damping_ratio == pytest.approx(0.015, rel=0.05)


def test_bad_band_or_quantity_is_a_clear_error():
    f = np.arange(70.0, 110.0, 1 / 16)
    with pytest.raises(SignalError, match=r"only 3 frequency lines in 90-90\.15 Hz"):
        sdof_fit(f, two_modes(f, 1), band=(90.0, 90.15))
    with pytest.raises(SignalError, match="quantity must be"):
        sdof_fit(f, two_modes(f, 1), band=(86.0, 104.0), quantity="jerk")


def test_an_frf_of_too_few_lines_is_a_signal_error():
    """An empty FRF raised IndexError (after numpy's 'Mean of empty slice'); one line was
    'f_peak outside the FRF's 97-97 Hz'."""
    for f in (np.array([]), np.array([97.0])):
        with pytest.raises(SignalError, match="hold min_lines = 7 lines or more"):
            sdof_fit(f, f * (1 + 0j), f_peak=97.0)
