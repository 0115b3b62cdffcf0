"""The screen's first look from the nominal base values (sensfw/measure/screening.py).

A missing effect pulls H0's optimum away from the base parameters' true values: without an
added mass, a one-mode model matches the measured resonance by a softer spring. From
there the true added mass lowers the resonance further and looks worse than nothing,
while from the nominal spring (the engineer's prior, near the truth) it explains the
record. The toy is that one-mode model's band levels (a lightly damped resonance), so
every number below follows from its frequency response."""

import math

import numpy as np
import pytest

from sensfw.measure.calibration import Axis, Coordinates, Fit, Trial
from sensfw.measure.hypotheses import Hypothesis
from sensfw.measure.screening import screen
from sensfw.plugins import effects

F = np.linspace(120.0, 200.0, 41)  # Hz
MASS, DAMPING, SIGMA = 0.1, 2.0, 0.1  # kg, N s/m, dB (each entry's standard error)
TRUTH = {"stiffness": 1.05e5, "added_mass": 0.06, "extra_damping": 0.0}


def levels(p: dict) -> np.ndarray:
    w = 2 * np.pi * F
    m = MASS + p.get("added_mass", 0.0)
    c = DAMPING * (1.0 + 10.0 * p.get("extra_damping", 0.0))
    return 20 * np.log10(1.0 / np.abs(p["stiffness"] - m * w**2 + 1j * c * w))


DATA = levels(TRUTH)


def residual(p: dict) -> np.ndarray:
    return (levels(p) - DATA) / SIGMA


class _Residuals:
    """One level of the toy's weighted residuals, counting the simulations."""

    def __init__(self, known: list[Trial] | None = None):
        self.n_simulations, self.labels, self.failures = 0, [], {}
        self.known = known or []  # H0's trials so far

    def level_slices(self):
        return [slice(0, F.size)]

    def trials(self, effects=None, levels=None, extra=None):
        return list(self.known) if effects is None else []

    def evaluate(self, specs, points, label, levels=None):
        self.n_simulations += len(points)
        self.labels += [label] * len(points)
        return [residual(p) for p in points]


def h0_at_its_optimum(base: Coordinates) -> Hypothesis:
    """H0 calibrated: the spring alone, at its least-squares optimum on a fine grid, and
    its Jacobian (coded) there."""
    axis = base.axes[0]
    z = np.linspace(-1, 1, 4001)
    chi2 = [float(residual({"stiffness": axis.decode(v)}) @ residual(
        {"stiffness": axis.decode(v)})) for v in z]
    z0 = z[int(np.argmin(chi2))]
    k0 = axis.decode(z0)
    dz = 1e-4
    jac = (residual({"stiffness": axis.decode(z0 + dz)}) -
           residual({"stiffness": axis.decode(z0 - dz)}))[:, None] / (2 * dz)
    h0 = Hypothesis(None, "", base)
    h0.fit = Fit(base, Trial({"stiffness": k0}, residual({"stiffness": k0})), jac)
    return h0


def candidate(name: str, base: Coordinates) -> Hypothesis:
    eff = effects.get(name)(attach="crankshaft")
    return Hypothesis(eff, "crankshaft", base + Coordinates.of(None, eff.parameters()))


@pytest.fixture()
def race():
    base = Coordinates([Axis.of("stiffness", 5e4, 2e5, 1e5, "N/m")])
    h0 = h0_at_its_optimum(base)
    return base, h0, [candidate("damping", base), candidate("added_mass", base)]


def run(h0, hyps, known=None, **kw):
    res = _Residuals(known)
    ranked = screen(res, h0, hyps, None, 0, calibrate_on=None, budget=0,
                    log=lambda s: None, **kw)
    return res, [h.name for h in ranked]


def test_h0_compensates_the_missing_mass_with_a_softer_spring(race):
    base, h0, _ = race
    # the resonance sqrt(k / m): matched without the mass at k = 1.05e5 * 0.1 / 0.16
    assert h0.fit.values["stiffness"] == pytest.approx(1.05e5 * MASS / (MASS + 0.06),
                                                       rel=0.02)
    assert abs(h0.fit.z[0] - base.code({"stiffness": 1e5})[0]) > 0.25


def test_from_h0s_optimum_the_true_mass_runs_worse_than_nothing(race):
    _, h0, hyps = race
    res, _ = run(h0, hyps, from_nominal=math.inf)
    mass = hyps[1]
    assert "H0 at the nominal values" not in res.labels
    assert res.n_simulations == len(hyps)
    # the probe's run (0.05 kg on the softened spring): the resonance moves further off
    assert mass.screen["observed"] > 2 * h0.fit.chi2
    # only the linearised joint fit (spring and mass together, to first order) hints at it
    assert mass.screen["score"] < mass.screen["observed"]
    assert mass.screen["looked_from"] == "H0"


def test_from_the_nominal_values_the_true_mass_runs_near_the_truth(race):
    _, h0, hyps = race
    _, _ = run(h0, hyps, from_nominal=math.inf)
    from_h0 = hyps[1].screen["score"]
    res, order = run(h0, hyps)
    mass, damping = hyps[1], hyps[0]
    assert order[0] == "added_mass@crankshaft"
    assert mass.screen["looked_from"] == "nominal"
    # the probe's run itself on the nominal spring (5 % from the true one, the mass 0.05
    # kg for 0.06): a fifth of H0's chi2 at most, and a better score than the prediction
    # from H0's optimum
    assert mass.screen["observed"] < h0.fit.chi2 / 5
    assert mass.screen["score"] < from_h0
    # a damping does not match a mass from there either: its look stays H0's
    assert damping.screen["looked_from"] == "H0"
    # one H0 run at the nominal values, one more first look per candidate
    assert res.labels.count("H0 at the nominal values") == 1
    assert res.n_simulations == 1 + 2 * len(hyps)
    assert "_origin" not in mass.screen and "_start" not in mass.screen  # scratch dropped


def test_no_look_from_the_nominal_values_where_h0_stayed_near_them(race):
    base, h0, hyps = race
    far = abs(h0.fit.z[0] - base.code({"stiffness": 1e5})[0])
    res, _ = run(h0, hyps, from_nominal=far + 0.01)
    assert res.n_simulations == len(hyps)


def test_the_nominal_models_run_among_h0s_trials_is_not_run_again(race):
    _, h0, hyps = race
    nominal = {"stiffness": 1e5}
    res, order = run(h0, hyps, known=[Trial(nominal, residual(nominal))])
    assert "H0 at the nominal values" not in res.labels
    assert res.n_simulations == 2 * len(hyps)
    assert order[0] == "added_mass@crankshaft" and hyps[1].screen["looked_from"] == "nominal"
