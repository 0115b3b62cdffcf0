"""Prediction bands of a calibrated model (sensfw/measure/prediction.py)."""

import numpy as np
import pytest
from scipy.stats import chi2

from sensfw.measure.calibration import Coordinates
from sensfw.measure.prediction import ellipsoid_points, extrapolation
from sensfw.params import Parameter


def test_the_band_points_lie_on_the_95_percent_ellipsoid():
    """Each of the 2 d points is on the ellipsoid ``dz^T C^-1 dz = chi2_d(0.95)`` (7.81 for
    d = 3), along a principal axis (pairs symmetric about the centre)."""
    coords = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 5.0),
                                   Parameter("b", "", 0.0, -1.0, 1.0),
                                   Parameter("c", "N/mm", 1e5, 1e4, 1e7)])
    z0 = np.array([0.1, -0.2, 0.3])
    A = np.array([[0.02, 0.01, 0.0], [0.01, 0.03, -0.005], [0.0, -0.005, 0.01]])
    points = ellipsoid_points(coords, z0, A)
    assert len(points) == 6
    inv = np.linalg.inv(A)
    for p in points:
        dz = coords.code(p) - z0
        assert dz @ inv @ dz == pytest.approx(chi2.ppf(0.95, 3), rel=1e-9)
    for p, q in zip(points[::2], points[1::2], strict=True):
        assert coords.code(p) + coords.code(q) == pytest.approx(2 * z0)


def test_a_record_unlike_the_calibrations_is_an_extrapolation():
    seen = [{"kind": "linear_sweep", "level": 0.05}, {"kind": "linear_sweep", "level": 0.3},
            {"kind": "random", "level": 0.1}]
    assert extrapolation("linear_sweep", 0.15, seen) is None
    assert extrapolation("random", 0.105, seen) is None  # within 10 %
    assert "outside" in extrapolation("random", 0.3, seen)
    assert "saw none" in extrapolation("stepped_sine", 0.1, seen)
    assert extrapolation("random", 5.0, []) is None  # nothing known of the calibration
