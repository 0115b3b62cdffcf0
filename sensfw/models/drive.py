"""How an excitation drives an Exudyn model.

An excitation with a closed form (the log chirp, a linear sweep) becomes a symbolic
expression of time that Exudyn evaluates in C++ at every stage of its integrator. A sampled
excitation (a measured force or voltage, random noise, a stepped sine) has no closed form:
its record is interpolated band-limited (polyphase, :func:`scipy.signal.resample_poly`) to
half the solver's step, and a pre-step function sets named symbolic variables at every step
so that the load is the quadratic ``F0 + b tau + c tau^2`` (``tau = t - T0``) through the
values at the step's start, middle and end: exact at every stage time of RK4 (``0, h/2,
h``), so the only error is the band-limited interpolation's (measured in
``tests/models/test_drive.py``).

A voltage record drives a model through a gain (N/V), the study parameter
``excitation_gain`` (:func:`apply_gain`), calibrated like any other parameter.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping

import numpy as np

from ..errors import ParameterError
from ..excitation import Excitation

#: the parameter that turns a voltage record into a force (N/V)
GAIN = "excitation_gain"
_names = itertools.count()


def apply_gain(excitation: Excitation, params: Mapping[str, float]
               ) -> tuple[Excitation, dict[str, float]]:
    """The excitation a model sees and the model's own parameters: ``excitation_gain``
    (N/V) scales a voltage record into a force and is removed from the parameters."""
    params = dict(params)
    gain = params.pop(GAIN, None)
    if gain is None:
        if excitation.unit != "N":
            raise ParameterError(f"the excitation is a {excitation.unit} record: it needs the "
                                 f"parameter {GAIN!r} (N per {excitation.unit})")
        return excitation, params
    if excitation.unit == "N":
        raise ParameterError(f"{GAIN!r} is given but the excitation is already a force (N)")
    return excitation.scaled(gain), params


class LoadSignal:
    """The excitation as a function of time inside an Exudyn model with step ``step``.

    :meth:`value` gives the expression a load user function returns; :meth:`install`
    attaches the pre-step function that feeds sampled records (nothing for closed forms).
    """

    def __init__(self, excitation: Excitation, step: float):
        self.excitation, self.step = excitation, float(step)
        self.closed_form = excitation.closed_form
        self._table: np.ndarray | None = None
        self._vars: tuple | None = None

    def table(self) -> np.ndarray:
        """The record at twice the step rate (band-limited): values at every half step."""
        if self._table is None:
            from scipy.signal import resample_poly

            ex = self.excitation
            k = max(1, round(2.0 / (ex.fs * self.step)))
            self._table = np.concatenate([resample_poly(ex.force(), k, 1), [0.0, 0.0, 0.0]])
        return self._table

    def value(self, ops, t):
        """The force at time ``t``: the closed form, or the per-step interpolation (a
        symbolic expression of two named variables; with numpy ops, the table itself)."""
        if self.closed_form:
            return self.excitation.force_expression(ops, t)
        if not hasattr(t, "Evaluate"):  # Python user functions: interpolate directly
            tab = self.table()
            return float(np.interp(t, np.arange(len(tab)) * (self.step / 2), tab))
        import exudyn as exu

        if self._vars is None:
            n = next(_names)
            self._vars = tuple(exu.symbolic.Real(f"sensfw_drive_{name}_{n}", 0.0)
                               for name in ("F0", "b", "c", "T0"))
        f0, b, c, t0 = self._vars
        tau = t - t0
        return f0 + (b + c * tau) * tau

    def _at(self, t: float) -> float:
        """The table (half-step spacing) at time ``t``, linearly between its samples (exact
        on the samples, which is where a fixed step puts every stage of RK4)."""
        tab, dt = self.table(), self.step / 2
        x = t / dt
        i = min(max(int(x), 0), len(tab) - 2)
        f = min(max(x - i, 0.0), 1.0)
        return float(tab[i] + f * (tab[i + 1] - tab[i]))

    def install(self, mbs, before: Callable | None = None) -> list:
        """Attach the pre-step function that sets the variables (sampled records only),
        calling ``before`` (a pre-step function the system has already) first; returns what
        must stay alive with ``mbs``."""
        if self.closed_form or self._vars is None:
            return []
        import exudyn as exu

        f0, b, c, t0 = self._vars
        start_of_step = exu.ConfigurationType.StartOfStep
        step = self.step
        # the coefficients of a full step from every half-step time of the table; a full
        # step between them (Exudyn's retries at a fraction of the step shift the steps after
        # them) interpolates them linearly, as it would its three values; a shorter step
        # interpolates its values as it comes
        tab = self.table()
        y0, ym, y1 = tab[:-2], tab[1:-1], tab[2:]
        grid_b = (4.0 * ym - 3.0 * y0 - y1) / step
        grid_c = 2.0 * (y1 - 2.0 * ym + y0) / (step * step)
        last, half = len(grid_b) - 2, step / 2
        # Python floats: indexing a list is several times faster than a numpy array's scalar
        # (the pre-step runs at every step), and the arithmetic is the same IEEE doubles'
        y0, grid_b, grid_c = y0.tolist(), grid_b.tolist(), grid_c.tolist()

        def prestep(mbs, t):
            if before is not None:
                before(mbs, t)
            # Exudyn calls it before each step with the step's END time; the step starts at
            # the start-of-step configuration's time (adaptive steps vary, checked in
            # tests/models/test_drive.py)
            ta = mbs.systemData.GetTime(start_of_step)
            h = t - ta if t > ta else step
            x = ta / half
            j = int(x)
            if abs(h - step) < 1e-6 * step and j <= last:
                f = x - j
                f0.SetValue(y0[j] + f * (y0[j + 1] - y0[j]))
                b.SetValue(grid_b[j] + f * (grid_b[j + 1] - grid_b[j]))
                c.SetValue(grid_c[j] + f * (grid_c[j + 1] - grid_c[j]))
            else:
                v0, vm, v1 = self._at(ta), self._at(ta + h / 2), self._at(ta + h)
                f0.SetValue(v0)
                b.SetValue((4.0 * vm - 3.0 * v0 - v1) / h)
                c.SetValue(2.0 * (v1 - 2.0 * vm + v0) / (h * h))
            t0.SetValue(ta)
            return True

        mbs.SetPreStepUserFunction(prestep)
        return [prestep, self._vars]
