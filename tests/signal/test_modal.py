"""Single-mode fit of a resonance (sensfw.signal.modal_fit) on analytic FRFs."""

import numpy as np
import pytest

from sensfw.errors import SignalError
from sensfw.signal import modal_fit


def two_modes(f, quantity_power, noise=0.0, seed=0):
    """An FRF of two modes (95 Hz, zeta 1.5 %; 310 Hz, zeta 1 %) at 1/16 Hz resolution."""
    w = 2 * np.pi * f
    H = sum((1j * w) ** quantity_power * R / (wn**2 - w**2 + 2j * z * wn * w)
            for wn, z, R in ((2 * np.pi * 95.0, 0.015, 3.0e4 - 1.0e4j),
                             (2 * np.pi * 310.0, 0.01, 8.0e4)))
    rng = np.random.default_rng(seed)
    return H * (1 + noise * (rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))))


@pytest.mark.parametrize(("quantity", "power"), [("displacement", 0), ("velocity", 1),
                                                 ("acceleration", 2)])
def test_recovers_the_mode_with_the_other_one_as_residual(quantity, power):
    f = np.arange(70.0, 110.0, 1 / 16)
    fit = modal_fit(f, two_modes(f, power), (86.0, 104.0), quantity)
    # the second mode is a smooth residual (A + i w B) over the band: the fit is exact to
    # the curvature it leaves, < 1e-4 of the frequency and 1 % of the damping
    assert fit.fn_hz == pytest.approx(95.0, rel=1e-4)
    assert fit.zeta == pytest.approx(0.015, rel=0.01)
    assert fit.misfit < 1e-3


def test_noise_leaves_the_estimate_within_a_fraction_of_the_resolution():
    f = np.arange(70.0, 110.0, 1 / 16)
    fit = modal_fit(f, two_modes(f, 1, noise=0.02), (86.0, 104.0))
    # 2 % complex noise per bin over ~290 bins: the frequency to ~0.01 Hz (a sixth of the
    # 1/16 Hz resolution), the damping to a few per cent
    assert abs(fit.fn_hz - 95.0) < 0.01
    assert fit.zeta == pytest.approx(0.015, rel=0.05)


def test_bad_input_is_a_clear_error():
    f = np.arange(70.0, 110.0, 1 / 16)
    with pytest.raises(SignalError, match="holds 3 frequencies"):
        modal_fit(f, two_modes(f, 1), (90.0, 90.15))
    with pytest.raises(SignalError, match="quantity must be"):
        modal_fit(f, two_modes(f, 1), (86.0, 104.0), "jerk")
