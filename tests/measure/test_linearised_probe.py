"""The screen's linearised joint fit (sensfw/measure/screening.py): a probe's change of
the residuals, measured from the effect's absence, scaled by ``c``, is the effect at ``c``
times its strength with its other parameters where the probe had them."""

from types import SimpleNamespace

import numpy as np
import pytest

from sensfw.effects.elements import FlexibleMode
from sensfw.measure.screening import _linearised, _scaled_probe


def flexible_mode_hypothesis() -> SimpleNamespace:
    eff = FlexibleMode()
    axes = [SimpleNamespace(name=p.name, low=p.min, high=p.max) for p in eff.parameters()]
    return SimpleNamespace(effect=eff, coords=SimpleNamespace(axes=axes))


def residuals(p: dict) -> np.ndarray:
    """A toy residual linear in the mode's mass (the strength: zero mass, no mode) and
    sharply peaked in its frequency, like a lightly damped mode against band levels."""
    f = np.linspace(600.0, 1000.0, 41)
    peak = 1.0 / (1.0 + ((f - p["flex_frequency"]) / (2 * p["flex_damping"] *
                                                       p["flex_frequency"])) ** 2)
    return 100.0 * p["flex_mass"] * peak


def test_the_scaled_probe_is_on_the_line_the_probe_measured():
    h = flexible_mode_hypothesis()
    probe = {"flex_frequency": 805.6, "flex_damping": 0.0123, "flex_mass": 0.03}
    target = residuals({**probe, "flex_mass": 0.04})  # the same mode, heavier
    w0 = -target  # H0 (no mode) misses it all
    d = residuals(probe)  # the probe's change from the effect's absence
    lin, _, c = _linearised(w0, None, d, np.zeros(0))
    assert c == pytest.approx(4 / 3) and lin == pytest.approx(0.0, abs=1e-9)
    point = _scaled_probe(h, probe, c)
    # frequency and damping stay where the probe measured; the mass scales from zero
    assert point["flex_frequency"] == 805.6 and point["flex_damping"] == 0.0123
    assert point["flex_mass"] == pytest.approx(0.04)
    # so running the point gives what the linearised fit predicted (chi2 0); moving the
    # frequency along with the mass (from its nominal 2500 Hz, as the screen once did)
    # puts the peak elsewhere
    r = w0 + residuals(point)
    assert float(r @ r) == pytest.approx(0.0, abs=1e-12)
    nominal = {p.name: p.nominal for p in h.effect.parameters()}
    moved = {k: nominal[k] + c * (probe[k] - nominal[k]) for k in ("flex_frequency",
                                                                    "flex_damping")}
    r_old = w0 + residuals({**point, **moved})
    assert float(r_old @ r_old) > 0.5 * float(w0 @ w0)
