"""Integration onto the output grid (sensfw.models.integration): the resampling of adaptive
steps, checked on polynomials, on a sinusoid against the spline's error bound, and on a pure
chirp through a linear Exudyn oscillator, whose response must stay free of distortion."""

import numpy as np
import pytest

from sensfw.excitation import Chirp
from sensfw.models import integration
from sensfw.models.stepsize import StepChoice
from sensfw.signal import thd

FS = 20000.0


def irregular_steps(t_end, h_max, seed=0):
    """Step ends of an adaptive integrator: 0.3 to 1 times ``h_max``, ending at ``t_end``."""
    rng = np.random.default_rng(seed)
    h = rng.uniform(0.3, 1.0, int(2 * t_end / h_max) + 10) * h_max
    t = np.concatenate([[0.0], np.cumsum(h)])
    return np.append(t[t < t_end], t_end)


def test_resample_is_exact_for_cubics_and_keeps_the_last_of_repeated_times():
    t = irregular_steps(0.01, 8e-6)
    t = np.insert(t, 5, t[5])  # a time recorded twice (Exudyn's last step can be)

    def cubic(s):
        return 1.0 + 3e2 * s - 4e4 * s**2 + 2e6 * s**3

    x = cubic(t)
    x[5] = np.nan  # the earlier of the two equal times is dropped
    got = integration.resample(t, x, FS, 200)
    # a not-a-knot cubic spline reproduces a cubic exactly (up to rounding)
    np.testing.assert_allclose(got, cubic(np.arange(200) / FS), rtol=1e-12, atol=1e-12)


def test_resample_error_of_a_sinusoid_is_within_the_spline_bound():
    h_max, f = 8e-6, 10e3  # the friction-velocity minimum's mean step; a 10 kHz harmonic
    t = irregular_steps(0.02, h_max, seed=1)
    w = 2 * np.pi * f
    got = integration.resample(t, np.sin(w * t), FS, 400)
    err = np.max(np.abs(got - np.sin(w * np.arange(400) / FS)))
    # cubic spline interpolation error <= (5/384) h^4 max|x''''| for the largest step h
    assert err <= 5 / 384 * (w * h_max) ** 4
    assert err < 1e-4  # measured 4.9e-5 of the amplitude (-86 dB)


def test_resample_reports_a_short_or_non_finite_record():
    t = irregular_steps(0.005, 8e-6)
    assert len(integration.resample(t, np.ones_like(t), FS, 200)) == 101  # stops at 5 ms
    x = np.ones_like(t)
    x[7] = np.inf
    assert len(integration.resample(t, x, FS, 100)) == 0


def oscillator(excitation, f_n=2000.0, zeta=0.02):
    """A linear 1-DOF oscillator in Exudyn (native spring-damper) driven by the chirp."""
    import exudyn as exu
    from exudyn import itemInterface as ei

    k = (2 * np.pi * f_n) ** 2  # unit mass
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ei.ObjectGround())
    node = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=[0, 0]))
    body = mbs.AddObject(ei.ObjectMassPoint2D(nodeNumber=node, mass=1.0))
    m0 = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground))
    m1 = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=body))
    mbs.AddObject(ei.ObjectConnectorCartesianSpringDamper(
        markerNumbers=[m0, m1], stiffness=[k, k, 0], damping=[2 * zeta * k**0.5] * 2 + [0]))
    load = mbs.AddLoad(ei.LoadForceVector(markerNumber=m1, loadVector=[0, 0, 0]))
    mbs.SetLoadParameter(load, "loadVectorUserFunction", lambda mbs, t, load: [
        float(excitation.force(np.array([t]))[0]), 0.0, 0.0])
    s = mbs.AddSensor(ei.SensorBody(bodyNumber=body, storeInternal=True,
                                    outputVariableType=exu.OutputVariableType.Acceleration))
    mbs.Assemble()
    return SC, mbs, {"a": (s, 0)}


def test_adaptive_steps_resampled_keep_a_pure_chirp_through_a_linear_model_clean():
    """A linear model answers a pure chirp without harmonics, so its THD is the analysis'
    own floor. Adaptive steps land between the samples; Exudyn records a sensor at the first
    step past each sample time, which jitters the samples by up to a step and shows up as
    distortion (measured 1.34 % here, 545x the floor). Resampled by the spline, the response
    is the fixed-step one (waveform 6e-5, THD within 4 % of the floor)."""
    import exudyn as exu

    exu.config.printToConsole = False
    ex = Chirp(50, 5000, 0.2, FS, 1.0)
    n = ex.n_samples
    fixed = StepChoice(step=5e-6, substeps=10)
    # steps up to one sample period, so that they fall between the sample times
    adaptive = StepChoice(step=1 / FS, substeps=1, method="DOPRI5", adaptive=True,
                          tolerance=1e-10)
    _sc, mbs, sensors = oscillator(ex)  # the container must outlive mbs
    ref, _ = integration.solve(mbs, sensors, fixed, n, FS)
    _sc, mbs, sensors = oscillator(ex)  # the container must outlive mbs
    got, stats = integration.solve(mbs, sensors, adaptive, n, FS)
    record = np.asarray(mbs.GetSensorStoredData(sensors["a"][0]))
    assert stats.rejected > 0 and len(record) == stats.steps + 1  # every step recorded
    off_grid = np.abs(record[:, 0] * FS - np.round(record[:, 0] * FS)) > 1e-6
    assert np.mean(off_grid) > 0.9  # the steps fall between the sample times
    t = ex.time()
    floor = thd(ref["a"], FS, ex.f_inst(t))
    rel = np.sqrt(np.mean((got["a"] - ref["a"]) ** 2) / np.mean(ref["a"] ** 2))
    assert rel < 2e-4
    assert thd(got["a"], FS, ex.f_inst(t)) == pytest.approx(floor, rel=0.1)
    # what the resampling avoids: the value of the first step at or after each sample time
    idx = np.minimum(np.searchsorted(record[:, 0], t - 1e-12), len(record) - 1)
    assert thd(record[idx, 1], FS, ex.f_inst(t)) > 100 * floor
