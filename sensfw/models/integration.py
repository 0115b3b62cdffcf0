"""Time integration of an assembled Exudyn system onto the output sample grid.

A run is integrated in one of two ways, chosen per run by
:func:`sensfw.models.stepsize.choose_integration`:

* **fixed steps** (RK4 by default) of ``1 / (fs k)``, so that every sample time is a step end
  and Exudyn's sensors record exactly on the grid;
* **adaptive steps** (Exudyn's DOPRI5, embedded 5(4) pair with error control, Hairer, Norsett
  & Wanner, *Solving ODEs I*, Sect. II.5) for runs whose fixed step would be set by an
  over-damped eigenvalue: the stick band of regularised friction (Eq. 3) is a viscous element
  of slope ``1.5 mu_s N / v_s`` that RK4 must resolve for the whole run although it only
  carries the quasi-static creep between the shafts. The error-controlled step sits at
  DOPRI5's stability limit there instead of inside RK4's accuracy margin.

Adaptive steps do not land on the sample times, and Exudyn writes a sensor at the first step
that reaches its write time, without interpolation (``CSolverBase::WriteSensorsToFile``): the
samples would jitter by up to a step, which phase-modulates the signal and spreads its energy
into spurious orders (measured on the linearised model, a pure chirp: THD 0.65 % against the
0.002 % floor of the fixed-step run). So every accepted step is recorded and
:func:`resample` puts the values onto the grid with a not-a-knot cubic spline (error
``O(h^4)``; on the same chirp THD 0.0020 %, the fixed-step floor). DOPRI5's last stage is
evaluated at the new state (first-same-as-last), so the accelerations Exudyn records at a step
end are those of the accepted solution, not of an intermediate stage.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .stepsize import StepChoice


@dataclass(frozen=True)
class IntegrationStats:
    """What the integrator did: accepted and rejected steps and the mean accepted step (s)."""

    steps: int
    rejected: int
    mean_step: float

    def to_meta(self) -> dict:
        return {"steps": self.steps, "rejected_steps": self.rejected,
                "mean_step": self.mean_step}


def simulation_settings(choice: StepChoice, t_end: float, fs: float):
    """Exudyn ``SimulationSettings`` for one run of length ``t_end`` (s) sampled at ``fs``."""
    import exudyn as exu

    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.endTime = t_end
    ti.verboseMode = 0
    # accelerations are taken from the last stage (RK4: at t + h; DOPRI5: the new state)
    ti.explicit.computeEndOfStepAccelerations = False
    ti.discontinuous.useRecommendedStepSize = False
    ss.solution.file.write = False
    if choice.adaptive:
        # the largest step is choice.step; the controller takes smaller ones where needed
        ti.numberOfSteps = max(1, round(t_end / choice.step))
        ti.automaticStepSize = True
        # Exudyn scales the tolerance as atol + max(y_new, y_old) rtol with signed values,
        # so a relative part would shrink for negative coordinates: absolute only (SI: m,
        # m/s, rad, rad/s, all of them small here)
        ti.absoluteTolerance = choice.tolerance
        ti.relativeTolerance = 0.0
        ti.initialStepSize = choice.step
        ss.solution.sensors.writePeriod = 0.0  # every accepted step (resampled afterwards)
    else:
        ti.numberOfSteps = round(t_end * fs) * choice.substeps
        ti.automaticStepSize = False  # fixed steps on the output grid
        ss.solution.sensors.writePeriod = 1.0 / fs
    return ss


def solve(mbs, sensors: Mapping[str, tuple[object, int]], choice: StepChoice, n_out: int,
          fs: float) -> tuple[dict[str, np.ndarray], IntegrationStats]:
    """Integrate ``mbs`` over ``n_out / fs`` seconds and return the sensor channels on the
    sample grid ``k / fs``, ``k = 0 .. n_out - 1``, with the integrator's statistics.

    ``sensors`` maps a channel name to ``(sensor number, component)`` of a sensor created
    with ``storeInternal=True``. Raises ``exudyn.SolverError`` (or returns fewer samples)
    when Exudyn fails; the caller turns that into its own error.
    """
    import exudyn as exu

    t_end = n_out / fs
    ss = simulation_settings(choice, t_end, fs)
    ok = mbs.SolveDynamic(ss, solverType=getattr(exu.DynamicSolverType, choice.method))
    if ok is False:
        raise exu.SolverError("Exudyn solver did not finish")
    it = mbs.sys["dynamicSolver"].it
    # the step index is one past the last step taken (it starts at 1)
    steps = max(int(it.currentStepIndex) - 1, 1)
    stats = IntegrationStats(steps=steps, rejected=int(it.rejectedAutomaticStepSizeSteps),
                             mean_step=t_end / steps)
    channels = {}
    for name, (s, comp) in sensors.items():
        data = np.asarray(mbs.GetSensorStoredData(s))
        if choice.adaptive:
            channels[name] = resample(data[:, 0], data[:, 1 + comp], fs, n_out)
        else:
            channels[name] = np.ascontiguousarray(data[:n_out, 1 + comp])
    return channels, stats


def resample(t: np.ndarray, x: np.ndarray, fs: float, n: int) -> np.ndarray:
    """Values ``x`` recorded at increasing step times ``t`` (s), interpolated onto the grid
    ``k / fs``, ``k = 0 .. n - 1``, by a not-a-knot cubic spline (``scipy.interpolate``).

    Exact for cubic polynomials; for a sinusoid of angular frequency ``w`` sampled at steps up
    to ``h`` the error is about ``(5/384) (w h)^4`` of its amplitude (1e-4 at ``w h = 0.3``,
    a 10 kHz harmonic at 5 us steps). Repeated times (a step recorded twice at the end) keep
    their last value. Returns fewer than ``n`` values (for the caller's divergence check)
    when the record stops before the last sample time or holds non-finite values.
    """
    from scipy.interpolate import CubicSpline

    t = np.asarray(t, float)
    x = np.asarray(x, float)
    keep = np.append(np.diff(t) > 0, True)  # the last of equal times
    t, x = t[keep], x[keep]
    if len(t) < 4 or not np.all(np.isfinite(x)):
        return x[:0]
    grid = np.arange(n) / fs
    grid = grid[grid <= t[-1] * (1 + 1e-12)]
    return CubicSpline(t, x)(grid)
