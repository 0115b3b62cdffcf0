"""The explicit step of a run (sensfw.models.stepsize) on systems whose eigenvalues are known
in closed form, and RK4's own stability function at the limits it uses."""

import numpy as np
import pytest

from sensfw.models.stepsize import (
    ADAPTIVE_METHOD,
    OSCILLATORY_LIMIT,
    REAL_LIMIT,
    STIFF_REAL_LAMBDA_H,
    VERLET_OSCILLATORY_LIMIT,
    VERLET_REAL_LIMIT,
    choose_integration,
    explicit_step,
    first_order_eigenvalues,
    grid_step,
)

FS = 20000.0  # Hz; sample period 50 us


@pytest.mark.parametrize("step_max, k", [(1e-5, 5), (3e-6, 17), (5e-5, 1), (2e-5, 3),
                                         (1e-4, 1), (5e-6, 10)])
def test_grid_step_is_the_largest_divisor_of_the_sample_period(step_max, k):
    got = grid_step(step_max, FS)
    assert got.substeps == k
    assert got.step == pytest.approx(1 / (FS * k), rel=1e-15)
    assert got.step <= min(step_max, 1 / FS) * (1 + 1e-12)
    # the next larger divisor would exceed the requested step (or the sample period)
    assert k == 1 or 1 / (FS * (k - 1)) > step_max


def test_undamped_oscillator_limits_the_step_by_its_frequency():
    w = 2.0e5  # rad/s; eigenvalues +-i w
    lam = first_order_eigenvalues(np.eye(1), np.array([[w**2]]), np.zeros((1, 1)))
    np.testing.assert_allclose(np.sort(lam.imag), [-w, w], rtol=1e-12)
    got = explicit_step(lam, 1e-5, FS)
    # OSCILLATORY_LIMIT / w = 7.5 us -> 50 us / 7 = 7.14 us
    assert got.limited_by == "oscillatory eigenvalue" and got.substeps == 7
    assert got.oscillatory_lambda_h == pytest.approx(w / (FS * 7))
    assert got.oscillatory_lambda_h <= OSCILLATORY_LIMIT


def test_viscous_element_limits_the_step_on_the_real_axis():
    c, m = 3.0e5, 1.0  # eigenvalues 0 and -c/m (a mass on a damper: friction's stick band)
    lam = first_order_eigenvalues(np.eye(1) * m, np.zeros((1, 1)), np.array([[c]]))
    np.testing.assert_allclose(np.sort(lam.real), [-c / m, 0.0], atol=1e-6)
    got = explicit_step(lam, 1e-5, FS)
    assert got.limited_by == "real eigenvalue"
    assert got.substeps == 25 and got.step == pytest.approx(2e-6)  # 0.6 / 3e5 = 2 us
    assert got.real_lambda_h == pytest.approx(REAL_LIMIT)


def test_a_soft_system_keeps_the_requested_step():
    lam = first_order_eigenvalues(np.eye(1), np.array([[1e6]]), np.array([[10.0]]))
    got = explicit_step(lam, 1e-5, FS)
    assert got.limited_by == "solver.step" and got.substeps == 5


def rk4_amplification(z):
    """RK4's stability function R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24."""
    return 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24


def test_limits_sit_inside_rk4_stability_with_accuracy_to_spare():
    # real axis: stable for |z| < 2.785; at the limit one step decays within 0.11 % of
    # exp(z) (local error z^5/120 relative to exp(z))
    assert abs(rk4_amplification(-REAL_LIMIT) / np.exp(-REAL_LIMIT) - 1) < 1.1e-3
    # the friction-velocity-min corner of Table 1 at 10 us (|lambda h| = 4.06) is unstable
    assert abs(rk4_amplification(-4.06)) > 1
    # imaginary axis: stable for |z| < 2 sqrt(2); at the limit |R| loses < 6 % per step
    r = abs(rk4_amplification(1j * OSCILLATORY_LIMIT))
    assert 0.94 < r < 1.0
    assert abs(rk4_amplification(1j * 2.97)) > 1  # the stiff corner's mode at 10 us


def test_a_stiff_viscous_element_can_be_integrated_with_velocity_verlet():
    """The friction stick band at its Table 1 minimum (|lambda| = 4.1e5 1/s) would need a
    fixed RK4 step of 0.6 / 4.1e5 -> 1.43 us (4 right-hand sides per step); velocity Verlet
    takes 0.8 / 4.1e5 -> 1.92 us (50 us / 26) with one per step."""
    c, m = 4.1e5, 1.0
    assert c / m * 1e-5 > STIFF_REAL_LAMBDA_H
    lam = first_order_eigenvalues(np.eye(1) * m, np.zeros((1, 1)), np.array([[c]]))
    got = choose_integration(lam, 1e-5, FS, "RK44", 1e-9, stiff_method="VelocityVerlet")
    assert got.method == "VelocityVerlet" and not got.adaptive
    assert got.substeps == 26 and got.step == pytest.approx(1 / (26 * FS))
    assert got.limited_by == "real eigenvalue"
    assert 0.75 < got.real_lambda_h <= VERLET_REAL_LIMIT == 0.8
    rk4 = explicit_step(lam, 1e-5, FS)
    assert rk4.substeps == 35  # RK4 at 1.43 us: 4 x 35 / 26 = 5.4x the evaluations
    assert got.to_meta()["integrator"] == "VelocityVerlet"
    assert choose_integration(lam, 1e-5, FS, "RK44").method == "DOPRI5"  # the default
    with pytest.raises(ValueError, match="stiff method"):
        choose_integration(lam, 1e-5, FS, "RK44", stiff_method="ExplicitEuler")


def velocity_verlet_peak(c_h_over_m: float, steps: int = 2000, omega_h: float = 1e-3) -> float:
    """Largest displacement (m) of Exudyn's VelocityVerlet on ``m x'' + c x' + k x = f``
    (1 kg, 1 N switched on at t = 0; static displacement ``1 / k``) at a step with the given
    ``c h / m`` and ``omega h`` (``omega = sqrt(k / m)``; the default is k = 100 N/m)."""
    import exudyn as exu
    from exudyn.itemInterface import (
        CoordinateSpringDamper,
        LoadCoordinate,
        MarkerNodeCoordinate,
        Mass1D,
        Node1D,
        NodePointGround,
        SensorNode,
    )

    h = 1e-4
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    node = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    mbs.AddObject(Mass1D(mass=1.0, nodeNumber=node))
    markers = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=0))
               for n in (ground, node)]
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=markers, stiffness=(omega_h / h) ** 2,
                                         damping=c_h_over_m / h))
    mbs.AddLoad(LoadCoordinate(markerNumber=markers[1], load=1.0))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                      outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = steps * h
    ss.timeIntegration.numberOfSteps = steps
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = h
    mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.VelocityVerlet)
    x = np.asarray(mbs.GetSensorStoredData(sensor))[:, 1]
    return float(np.max(np.abs(x))) if np.all(np.isfinite(x)) else np.inf


def test_velocity_verlet_is_stable_on_a_damper_up_to_c_h_over_m_2():
    """What VERLET_REAL_LIMIT rests on: Exudyn's velocity Verlet treats a velocity-dependent
    force explicitly, so on a damper it is stable for ``c h / m <= 2`` (explicit Euler's
    bound) and not beyond. The creep under the 1 N load stays below its static 1 cm up to
    the bound, diverges past it. The limit 0.8 leaves a factor 2.5 for the normal force
    (and so the stick band's slope) to grow under load."""
    for r in (VERLET_REAL_LIMIT, 1.5, 1.99):
        assert velocity_verlet_peak(r) <= 0.01 + 1e-12, r
    assert velocity_verlet_peak(2.05, steps=1000) > 1.0


def test_velocity_verlet_is_stable_on_an_oscillator_up_to_omega_h_2():
    """What VERLET_OSCILLATORY_LIMIT rests on (half of the bound): undamped, a step load
    swings the mass between 0 and twice its static displacement; Stormer-Verlet keeps that
    swing (it conserves a modified energy: measured 2.000 static at omega h = 0.5 to 1.99) up
    to ``omega h = 2`` and diverges past it."""
    for wh in (VERLET_OSCILLATORY_LIMIT, 1.9):
        static = (1e-4 / wh) ** 2  # 1 / k
        assert velocity_verlet_peak(0.0, omega_h=wh) == pytest.approx(2 * static, rel=1e-5)
    static = (1e-4 / 2.05) ** 2
    assert velocity_verlet_peak(0.0, steps=1000, omega_h=2.05) > 1e3 * static


def test_a_stiff_viscous_element_is_integrated_adaptively_by_default():
    """The default stiff treatment: error-controlled DOPRI5 steps of at most the requested
    10 us instead of RK4's 1.43 us."""
    c, m = 4.1e5, 1.0
    lam = first_order_eigenvalues(np.eye(1) * m, np.zeros((1, 1)), np.array([[c]]))
    got = choose_integration(lam, 1e-5, FS, "RK44", 1e-9)
    assert got.adaptive and got.method == ADAPTIVE_METHOD == "DOPRI5"
    assert got.tolerance == 1e-9 and got.limited_by == "real eigenvalue"
    assert got.step == pytest.approx(1e-5) and got.substeps == 5
    assert got.real_lambda_h == pytest.approx(4.1)  # at the largest step it may take
    assert got.to_meta()["integrator"] == "DOPRI5 adaptive"
    with pytest.raises(ValueError, match="tolerance"):
        choose_integration(lam, 1e-5, FS, "RK44", 0.0)


@pytest.mark.parametrize("c, k", [(1.71e5, 0.0), (6.1e4, 0.0), (0.0, 2.0e5**2),
                                  (10.0, 1e6)])
def test_moderately_stiff_and_oscillatory_runs_keep_fixed_steps(c, k):
    """Over-damped elements within RK4's stability at the requested step (1.71e5 1/s: the
    all-min corner of Table 1, |lambda h| = 1.71, 3.33 us; 6.1e4 1/s: a slide-bearing
    contact at its softest and most damped, 8.33 us), an oscillatory limit, and a soft
    system keep the fixed-step method they asked for."""
    lam = first_order_eigenvalues(np.eye(1), np.array([[k]]), np.array([[c]]))
    got = choose_integration(lam, 1e-5, FS, "RK44")
    fixed = explicit_step(lam, 1e-5, FS)
    assert not got.adaptive and got.method == "RK44"
    assert (got.step, got.substeps, got.limited_by) == (fixed.step, fixed.substeps,
                                                        fixed.limited_by)
    assert c * 1e-5 <= STIFF_REAL_LAMBDA_H
