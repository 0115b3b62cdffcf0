"""Contact laws (Eqs. 2, 3, 5, 6) evaluated with numbers."""

import numpy as np
import pytest

from sensfw.models.contact import (
    clearance_force,
    critical_damping,
    fit_power_law,
    friction_coefficient,
    impact_force,
    numpy_ops,
)

OPS = numpy_ops()


def test_impact_force_eq2():
    k, b, c, dmax = 2e8, 1.5, 1e3, 1e-5
    assert impact_force(OPS, -1e-6, 5.0, k, b, c, dmax) == 0.0  # open: no force
    d = 2e-6
    s = d / dmax
    expected = k * d**b + c * s * s * (3 - 2 * s) * 0.01  # damping ramps in (Adams STEP)
    assert impact_force(OPS, d, 0.01, k, b, c, dmax) == pytest.approx(expected, rel=1e-12)
    assert impact_force(OPS, 2e-5, 0.0, k, b, c, dmax) == pytest.approx(k * 2e-5**b)
    assert impact_force(OPS, 1e-9, -1e3, k, b, c, dmax) == 0.0  # never pulls
    # two-sided play: pushes back from whichever side is closed
    assert clearance_force(OPS, 3e-6, 0.0, 1e-6, k, b, c, dmax) == pytest.approx(-k * 2e-6**b)
    assert clearance_force(OPS, -3e-6, 0.0, 1e-6, k, b, c, dmax) == pytest.approx(k * 2e-6**b)
    assert clearance_force(OPS, 5e-7, 0.0, 1e-6, k, b, c, dmax) == 0.0


def test_friction_eq3_adams_convention():
    mu_s, mu_d, vs, vt = 0.1, 0.05, 1e-4, 1e-3
    assert friction_coefficient(OPS, 0.0, mu_s, mu_d, vs, vt) == 0.0  # mu(0) = 0
    assert friction_coefficient(OPS, vs, mu_s, mu_d, vs, vt) == pytest.approx(mu_s)
    assert friction_coefficient(OPS, -vs, mu_s, mu_d, vs, vt) == pytest.approx(-mu_s)
    assert friction_coefficient(OPS, 5e-3, mu_s, mu_d, vs, vt) == pytest.approx(mu_d)
    mid = friction_coefficient(OPS, 5.5e-4, mu_s, mu_d, vs, vt)
    assert mu_d < mid < mu_s  # the Stribeck drop between the transition velocities


def test_eq5_fit_recovers_a_hertz_curve_and_eq6():
    u = np.linspace(1e-4, 2e-2, 40)  # mm
    k, b = 4.2e4, 1.5  # Hertz point contact, N/mm^1.5
    F = k * u**b * (1 + 0.002 * np.sin(np.arange(40)))  # 0.2 % "FEM" scatter
    k_fit, b_fit = fit_power_law(u, F)
    assert b_fit == pytest.approx(1.5, abs=0.01)
    assert k_fit == pytest.approx(k, rel=0.03)
    assert critical_damping(4.0, 1.0) == 4.0  # 2 sqrt(k m)
