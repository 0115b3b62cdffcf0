"""The time step of a fixed-step explicit integrator (RK4) for one run.

Two constraints fix the step of a run:

* **the output grid.** Exudyn records a sensor at the first step that reaches its write time,
  so a step that does not divide the sample period ``1/fs`` puts samples up to one step off
  the grid (measured: 3 us off at h = 3 us, fs = 20 kHz, a 0.09 rad phase error at 5 kHz).
  The step is therefore always ``1 / (fs k)`` for an integer number ``k`` of steps per sample.
* **the fastest eigenvalues of the run's own parameter set.** RK4 is stable for ``|lambda| h``
  below about 2.785 on the negative real axis and 2.83 on the imaginary axis, and accurate
  well below that. Regularised stick-slip friction (Eq. 3) is a viscous element of slope
  ``1.5 mu_s N / v_s`` in the stick band, and an over-damped contact (large ``c``, small
  ``k``) is another real eigenvalue ``c / m``; both grow by orders of magnitude across
  Table 1. At the Table 1 corner with the friction velocities at their minimum, the stick
  eigenvalue of the crankshaft is ``|lambda| h = 4.1`` at 10 us: RK4 chatters in the stick
  band (bounded by the friction limit, so it never diverges), and halving the step changed
  the FRF by 26 dB and the THD from 42 % to 7.5 %.

:func:`explicit_step` takes the largest ``h = 1/(fs k) <= step_max`` with
``|lambda| h <= REAL_LIMIT`` for real-axis (over-damped) eigenvalues and
``|lambda| h <= OSCILLATORY_LIMIT`` for oscillatory ones, ``lambda`` from the linearisation
at the static state. The limits come from ``bench/convergence.py`` on the 1 s chirp: the
real-axis limit must absorb the growth of the normal force when contacts start to impact
(2.4x at the all-min corner of Table 1, where halving a step with static ``|lambda| h``
0.86 still changed the FRF by 0.49 dB and at 0.57 by 0.06 dB); oscillatory contact modes
stiffen only weakly with load (``k_t ~ F^((b-1)/b)``) and converged at 1.1.

The limits are calibrated for RK44 (the default). They are conservative for DOPRI5 and RK67,
whose stability regions are larger, and not sufficient for ExplicitEuler or
ExplicitMidpoint, whose regions are smaller (Euler is unstable on the imaginary axis).

**Very stiff over-damped runs** (:func:`choose_integration`, issue 15). Where a real
eigenvalue lies beyond RK4's stability at the requested step itself
(``|lambda| h > STIFF_REAL_LAMBDA_H = 2.785``), the run uses the ``stiff_method``. That is the
stick band of the friction at small transition velocities: at the friction-velocity minimum
of Table 1 (``|lambda| h = 4.1`` at 10 us) the relative axial velocity of the shafts stays
inside ``|v| <= v_s`` 99.5-100 % of the time (measured on the 0.3 s chirp), so no step
schedule can skip the band: it sets the step of the whole run, and the cost is the work per
unit of ``|lambda| h``.

* ``"DOPRI5"`` (the default): Exudyn's DOPRI5 with error control (absolute ``tolerance``),
  steps of at most the requested one, resampled onto the output grid
  (:mod:`sensfw.models.integration`). Its steps sit at its own stability limit in the band
  (``|lambda| h ~ 3.3``, mean 8.0 us at the friction-velocity minimum, where RK4 needs
  ``|lambda| h <= 0.6`` for accuracy under load changes it cannot see, 1.47 us), and the
  controller reacts when the normal force grows. It evaluates the right-hand side 7 times
  per step (no first-same-as-last reuse in Exudyn; ODE23 and RK44 4, counted with a Python
  user function), so that run costs 2.3x the nominal one (``bench/model.py``). Nothing
  Exudyn offers does the same work for less (``bench/integrators.py``, 0.3 s chirp, against
  RK4 at half the linearised step): ODE23 gets under 2x only where it loses 0.37-1.28 dB
  below 200 Hz; RK4 near its stability limit (5.56 us, ``|lambda| h = 2.3``, 1.98x) is 0.31
  dB off on the v-min run and 12 dB on a DoE run at that minimum with the slide stiffness
  at its middle level (THD 43 %, contact impacts in the stick band); Newmark's method with
  ``beta = 1/12`` (Fox-Goodwin: trapezoidal for the damping, so the stick band is
  unconditionally stable, fourth-order period error) costs 1.3x at 6.25 us and is 0.08 dB
  off on the v-min run but 3.5 dB on that DoE run, where DOPRI5 is 0.17 dB; a step-reduction
  check does not tell its good runs from its bad ones (on the 27 DoE runs at the minimum,
  the 15 without a reduced step were up to 3.3 dB from DOPRI5, ``--doe``). RK67 is stable
  only at 6.25 us (2.6x); DVERK6 is not implemented in Exudyn 1.13. An implicit update of
  the stick band alone inside the explicit step would need a hook in Exudyn's solver loop,
  which it does not offer (a Python pre-step function per 10 us step costs more than the
  step).
* ``"VelocityVerlet"``: Exudyn's velocity Verlet at a fixed grid step with ``|lambda| h <=
  VERLET_REAL_LIMIT = 0.8`` (real) and ``<= VERLET_OSCILLATORY_LIMIT = 1`` (oscillatory).
  One right-hand side per step; on a damper ``m x'' + c x' = f`` it is stable up to ``c h /
  m = 2`` (it treats velocity-dependent forces explicitly, like explicit Euler;
  ``tests/models/test_stepsize.py``), so it buys ``|lambda| h`` at 0.5 evaluations per unit
  where RK4 pays 1.4 and DOPRI5 2.1; the limit leaves a factor 2.5 for the normal force to
  grow under load (2.4x at the all-min corner). The friction-velocity-minimum run costs
  1.33x the nominal one (1.92 us steps) and passes the convergence bar (1 s chirp: 0.16 dB
  and 0.2 % THD at half the step, 0.26 dB and 0.2 % from RK4 at 1.47 us; DOPRI5: 0.04 dB).
  The price is order: with velocity-dependent forces the method is first order (the error
  halves with the step on a one-DOF model; second order without damping), and where the
  stick band meets strongly nonlinear contact dynamics that shows. In the paper's DoE, on
  the 15 runs at the friction-velocity minimum with ``slide_stiffness >= 3.56e6 N/mm`` (not
  counting the 3 chaotic ones, README), its THD lies a median 5.9 % (up to 38 %, 8 runs
  beyond 5 %) from RK4 at ``|lambda| h <= 0.6``, DOPRI5's 0.6 % (up to 15 %, 2 runs); at
  half its step 1.9 % (up to 62 %, 5 runs). Hence not the default: a choice for fast screens
  and calibrations, whose cost it cuts (the paper study: 118 s instead of 153 s on 2 cores;
  the screen's ranking the same, the DoE's R2adj -0.03 for P2 and THD), not for the scores
  of strongly nonlinear runs. Exudyn marks its velocity Verlet as under development (it
  prints a warning).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

#: Integrators the limits hold for (RK4 and the higher-order methods, whose stability
#: regions contain RK4's); a study with ``auto_step`` and another method is refused.
CALIBRATED_METHODS = ("RK44", "RK67", "DOPRI5")
#: Largest ``|lambda| h`` for real-axis (over-damped: ``|Im| <= |Re|``) eigenvalues.
REAL_LIMIT = 0.6
#: Largest ``|lambda| h`` for oscillatory eigenvalues.
OSCILLATORY_LIMIT = 1.5
#: Integrate with the stiff method where a real eigenvalue lies beyond RK4's stability on the
#: negative real axis (|R(z)| = 1 at z = -2.785) at the requested step.
STIFF_REAL_LAMBDA_H = 2.785
#: The default stiff treatment: error-controlled DOPRI5 (see the module docstring).
STIFF_METHOD = "DOPRI5"
#: The fast stiff treatment, Exudyn's velocity Verlet (one right-hand side per step, stable
#: to |lambda| h = 2 on a damper), at |lambda| h <= 0.8 for real eigenvalues (a factor 2.5
#: for the growth of the friction's normal force under load) and <= 1.0 for oscillatory ones
#: (half of Stormer-Verlet's stability limit omega h = 2).
VERLET_REAL_LIMIT = 0.8
VERLET_OSCILLATORY_LIMIT = 1.0
#: Stiff treatments a solver may ask for: DOPRI5 with error control, or velocity Verlet at a
#: fixed step.
STIFF_METHODS = ("DOPRI5", "VelocityVerlet")
#: The adaptive stiff treatment (Exudyn's Dormand-Prince 5(4) pair) and its default absolute
#: tolerance: at 1e-9 the friction-velocity minimum was within 0.017 dB (FRF) and 0.01 %
#: (THD) of RK4 at 0.74 us on the 0.3 s chirp, at 1e-8 within 0.075 dB, and the step count is
#: set by stability there (43.5k steps at 1e-9, 42.8k at 1e-8, 47.3k at 1e-10 per 0.35 s).
ADAPTIVE_METHOD = "DOPRI5"
DEFAULT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class StepChoice:
    """The step of one run and why.

    ``step`` (s) is ``1 / (fs * substeps)``; ``limited_by`` is ``"solver.step"`` or the kind
    of eigenvalue that forced a smaller step; ``real_lambda_h`` and ``oscillatory_lambda_h``
    are the largest ``|lambda| h`` of each kind at the chosen step (0 when none is known).
    ``method`` is the Exudyn integrator; with ``adaptive`` its steps are error-controlled
    (``tolerance``) and at most ``step`` (the ``|lambda| h`` are then given at ``step``).
    """

    step: float
    substeps: int
    limited_by: str = "solver.step"
    real_lambda_h: float = 0.0
    oscillatory_lambda_h: float = 0.0
    method: str = "RK44"
    adaptive: bool = False  # error-controlled steps of at most ``step`` (then resampled)
    tolerance: float = 0.0  # absolute error tolerance of the adaptive steps

    def to_meta(self) -> dict:
        meta = {"step": self.step, "substeps": self.substeps,
                "step_limited_by": self.limited_by,
                "real_lambda_h": self.real_lambda_h,
                "oscillatory_lambda_h": self.oscillatory_lambda_h,
                "integrator": self.method}
        if self.adaptive:
            meta.update(integrator=f"{self.method} adaptive", tolerance=self.tolerance)
        return meta


def grid_step(step_max: float, fs: float) -> StepChoice:
    """The largest step ``<= step_max`` that divides the sample period ``1/fs``."""
    if not (step_max > 0 and fs > 0):
        raise ValueError(f"step {step_max!r} s and sample rate {fs!r} Hz must be positive")
    k = max(1, math.ceil(1.0 / (fs * step_max) * (1 - 1e-12)))
    return StepChoice(step=1.0 / (fs * k), substeps=k)


def first_order_eigenvalues(M: np.ndarray, K: np.ndarray, D: np.ndarray) -> np.ndarray:
    """Eigenvalues of ``M q'' + D q' + K q = 0`` written as a first-order system."""
    n = len(M)
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ D]])
    return np.linalg.eigvals(A)


def spectral_radii(eigenvalues: np.ndarray) -> tuple[float, float]:
    """Largest ``|lambda|`` (1/s) of the real-axis (over-damped, ``|Im| <= |Re|``) and of the
    oscillatory eigenvalues; 0 where there are none."""
    lam = np.asarray(eigenvalues, complex)
    lam = lam[np.isfinite(lam)]
    real = np.abs(lam.imag) <= np.abs(lam.real)
    return (float(np.max(np.abs(lam[real]), initial=0.0)),
            float(np.max(np.abs(lam[~real]), initial=0.0)))


def explicit_step(eigenvalues: np.ndarray, step_max: float, fs: float,
                  real_limit: float = REAL_LIMIT,
                  oscillatory_limit: float = OSCILLATORY_LIMIT) -> StepChoice:
    """The largest RK4 step ``1/(fs k) <= step_max`` that keeps ``|lambda| h`` of every
    eigenvalue within its limit (see the module docstring)."""
    rho_real, rho_osc = spectral_radii(eigenvalues)
    bounds = {"solver.step": step_max}
    if rho_real > 0:
        bounds["real eigenvalue"] = real_limit / rho_real
    if rho_osc > 0:
        bounds["oscillatory eigenvalue"] = oscillatory_limit / rho_osc
    reason = min(bounds, key=bounds.get)
    grid, requested = grid_step(bounds[reason], fs), grid_step(step_max, fs)
    if grid.substeps == requested.substeps:  # the eigenvalues allow the requested step
        reason = "solver.step"
    return StepChoice(step=grid.step, substeps=grid.substeps, limited_by=reason,
                      real_lambda_h=rho_real * grid.step,
                      oscillatory_lambda_h=rho_osc * grid.step)


def choose_integration(eigenvalues: np.ndarray, step_max: float, fs: float,
                       method: str = "RK44", tolerance: float = DEFAULT_TOLERANCE,
                       stiff_method: str = STIFF_METHOD,
                       stiff_lambda_h: float = STIFF_REAL_LAMBDA_H) -> StepChoice:
    """Fixed steps of ``method`` at :func:`explicit_step`, or, where a real-axis
    (over-damped) eigenvalue has ``|lambda| h > stiff_lambda_h`` at the requested step, the
    ``stiff_method``: adaptive DOPRI5 steps (at most the requested grid step, absolute
    ``tolerance``), or fixed velocity Verlet steps within ``VERLET_REAL_LIMIT`` and
    ``VERLET_OSCILLATORY_LIMIT``; see the module docstring."""
    if stiff_method not in STIFF_METHODS:
        raise ValueError(f"stiff method {stiff_method!r} is not one of {STIFF_METHODS}")
    fixed = replace(explicit_step(eigenvalues, step_max, fs), method=method)
    requested = grid_step(step_max, fs)
    rho_real, rho_osc = spectral_radii(eigenvalues)
    if not rho_real * requested.step > stiff_lambda_h:
        return fixed
    if stiff_method == "VelocityVerlet":
        verlet = explicit_step(eigenvalues, step_max, fs, VERLET_REAL_LIMIT,
                               VERLET_OSCILLATORY_LIMIT)
        return replace(verlet, method="VelocityVerlet")
    if not tolerance > 0:
        raise ValueError(f"tolerance {tolerance!r} must be positive")
    return replace(requested, limited_by="real eigenvalue",
                   real_lambda_h=rho_real * requested.step,
                   oscillatory_lambda_h=rho_osc * requested.step, method=ADAPTIVE_METHOD,
                   adaptive=True, tolerance=tolerance)
