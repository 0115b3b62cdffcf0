"""Newton at the bolted beam's fixed step (issue 27, item 1, "the hang").

Every model's run of the UNESP-BERT random 0.05 V record hung until its 300 s timeout: Newton's
absolute tolerance was 1e-6 N per N of peak drive (1.4e-7 N there), below the round-off floor
of the residual that the stiffest connector sets (the joint at 1e7 N/mm, where ``sensfw
calibrate`` put it), so no step converged, and Exudyn's adaptive step halved the step down to
1e-8 s without a word. The drive here is the suite's own: seeded noise of 0.5 mV RMS (the
0.05 V record has 0.53 mV) through the calibrated gain.
"""

import math

import numpy as np
import pytest

from sensfw.errors import DivergenceError
from sensfw.excitation import RandomForce
from sensfw.models.base import SolverSettings
from sensfw.models.bolted_beam import BoltedBeam, Geometry, simulation
from sensfw.models.drive import GAIN
from sensfw.runs import RunSpec
from sensfw.runs.executor import run_processes
from sensfw.runs.spec import simulate_with_halving

#: the linear model ``sensfw calibrate`` made of the 0.05 V sweep (tests/measure/test_bert_loop.py)
LINEAR = {"excitation_gain": 55.70350233912158, "clamp_stiffness": 39876.46024473123,
          "joint_stiffness": 1.0e7, "damping_ratio": 0.01544341637800723}
#: the runs' timeout only bounds the test: the run that hung before the fix takes seconds
GA = SolverSettings(method="GeneralizedAlpha", step=1 / 8192, auto_step=False, timeout=60.0)


def noise(rms: float, duration: float = 0.25) -> RandomForce:
    """Seeded white noise of ``rms`` volts over 1-120 Hz (the rig's random drive)."""
    return RandomForce(f0=1.0, f1=120.0, duration=duration, fs=1024.0,
                       amplitude=math.sqrt(2) * rms, signal_unit="V", seed=27)


def test_the_residual_floor_is_the_joint_stiffness_times_the_rounding_of_its_positions():
    """The cause, in numbers: Exudyn evaluates a connector from its markers' positions, so
    each of the joint's four interface points (k/4 each, at x_i = 235-265 mm) is known to
    ``eps x_i`` on both of its coordinates: a force error up to ``2 (k/4) eps x_i`` on each of
    its two points' axial coordinates, an L2 norm of ``2 (k/4) eps sqrt(2 sum x_i^2)``
    (7.85e-7 N at 1e7 N/mm), the clamp and the normal contacts adding nothing visible (their
    positions are ~0). The tolerance the model used, 1e-6 N per N of peak drive, lies far
    below it for the suite's noise (and for the rig's 0.05 V record, 1.4e-7 N)."""
    model = BoltedBeam()
    _, st, z0, _ = model.state({k: v for k, v in LINEAR.items() if k != GAIN})
    floor = simulation.residual_floor(st, z0)
    x = np.array(Geometry().interface_x())
    k = LINEAR["joint_stiffness"] * 1e3 / len(x)  # N/m per interface point
    eps = np.finfo(float).eps
    assert floor == pytest.approx(2 * k * eps * np.sqrt(2 * np.sum(x**2)), rel=1e-2)

    # the rule the model had, 1e-6 N per N of peak drive: 8e-8 N, a tenth of the floor
    peak = LINEAR[GAIN] * np.max(np.abs(noise(0.5e-3).force()))  # N
    assert simulation.NEWTON_ABSOLUTE * peak < floor / 5


def test_a_tiny_random_drive_runs_with_the_stiffest_joint_and_stays_linear():
    """The suite's drive that hung (0.25 s of signal: two minutes of the old crawl, past the
    runs' 60 s timeout) runs at its step, none retried smaller, with modified Newton, and the
    response is linear in the drive: the laser signal at 0.5 mV RMS times ten is the one at
    5 mV RMS within 1e-4 of its RMS, with one Jacobian and one Newton iteration per step.
    Bound: Newton stops at most at its tolerance, 2 x 7.9e-7 N here, an error force at most
    6e-5 of the drive's RMS (0.028 N) at each step; measured 1e-9 (one modified Newton
    iteration solves the linear model's step to the round-off floor)."""
    specs = {rms: RunSpec.create(BoltedBeam(), LINEAR, noise(rms), GA,
                                 {"name": "bolted_beam", "options": {}})
             for rms in (0.5e-3, 5e-3)}
    results = {}
    # one worker process, each run killed after GA.timeout
    run_processes(list(specs.values()), lambda s, r: results.update({s.key(): r}), workers=1)
    runs = {}
    for rms, spec in specs.items():
        res = results[spec.key()]
        assert res.ok, res.error
        assert res.signals.meta["step_halvings"] == 0
        assert res.signals.meta["newton"] == "modified"
        assert res.signals.meta["step"] == 1 / 8192
        assert res.signals.meta["steps"] == 0.25 * 8192  # no step retried smaller
        # a linear system: modified Newton keeps its first Jacobian and solves each step in
        # one iteration (the counts the runs report, bench/beam_newton.py)
        assert res.signals.meta["newton_jacobians"] == 1
        assert res.signals.meta["newton_iterations"] == 0.25 * 8192
        runs[rms] = res.signals.channels["Laser"]
    small, large = 10 * runs[0.5e-3], runs[5e-3]
    assert np.sqrt(np.mean(large**2)) > 1e-5  # m/s: a response, not numerical noise
    rel = np.sqrt(np.mean((small - large) ** 2)) / np.sqrt(np.mean(large**2))
    assert rel < 1e-4, rel


def test_a_step_newton_cannot_solve_is_a_divergence_at_once_retried_at_half_the_step(
        monkeypatch):
    """With tolerances no step can meet, the run stops at its first step once Exudyn has
    retried it at 1/64 of the step (not at 1e-8 s steps for minutes), with Newton's residual
    and the time in the error, as a divergence: the runs retry it at half the step
    (``[solver] halvings = 1``) and report both steps."""
    monkeypatch.setattr(simulation, "NEWTON_FLOOR", 0.0)
    monkeypatch.setattr(simulation, "NEWTON_ABSOLUTE", 0.0)
    monkeypatch.setattr(simulation, "NEWTON_TOLERANCE", 1e-12)
    with pytest.raises(DivergenceError) as err:
        simulate_with_halving(BoltedBeam(), dict(LINEAR), noise(0.5e-3, 0.05), GA)
    msg = str(err.value)
    assert "Newton did not converge at t = 0 s" in msg, msg
    h = 1 / 16384  # the halved run's step
    assert f"(the step {h:.4g} s reduced to {h / 2**simulation.STEP_REDUCTIONS:.4g} s)" in msg
    assert "at step 0.00012207, 6.10352e-05 s" in msg, msg
    assert err.value.step == pytest.approx(h)
