"""``added_mass`` on a rigid body against an independent lumping: the same mass as a body
of its own, tied to the place by a 2-D spring stiff enough (a 100 kHz connection mode) to
move with it, on the linearised shaft model's matrices."""

import math

import numpy as np
import pytest

from sensfw.effects import Effect
from sensfw.models.shaft_assembly.model import ShaftAssembly
from sensfw.params import Parameter

TIE_HZ = 1.0e5


class TiedPointMass(Effect):
    """A point mass of its own at the place, tied by a stiff isotropic spring."""

    name = "tied_point_mass_test"
    fits = ("body",)

    def parameters(self):
        return [Parameter("pm_mass", "kg", 0.1, 0.0, 0.2, "point mass")]

    def apply(self, place, hooks, p):
        m = p["pm_mass"]
        k = m * (2 * math.pi * TIE_HZ) ** 2
        hooks.add_body("pm", m, follows=(place.body1, place.r1))
        hooks.add_force("pm_tie", place.body1, place.r1, "pm", (0.0, 0.0),
                        lambda ops, u, v: (-k * u[0], -k * u[1]))


def modes(model, values):
    M, K, _ = model.linear_matrices(model.parameters().complete(values))
    w2 = np.linalg.eigvals(np.linalg.solve(M, 0.5 * (K + K.T)))
    return np.sort(np.sqrt(np.abs(w2.real)) / 2 / np.pi)


@pytest.mark.parametrize("place", ["crankshaft", "driveshaft"])
def test_an_added_mass_moves_the_modes_as_a_tied_point_mass_does(place):
    """0.1 kg (the parameter's maximum), 80 mm from the crankshaft's centre or 45 mm from
    the driveshaft's: the first five modes within 0.1 % of the tied mass's (its tie's own
    flexibility shifts a mode by about (f / 100 kHz)^2 of its share: 0.1 % at 3.3 kHz at
    most). Adding m and m r^2 about the old centre, as before, put the crankshaft's second
    mode at 1164 Hz against 1134 (2.6 %) and the driveshaft's fifth 5.7 % high: the
    coupling m r between translation and rotation was lost."""
    am = modes(ShaftAssembly(linearised=True,
                             effects=[{"name": "added_mass", "attach": place}]),
               {"added_mass": 0.1})
    tied = modes(ShaftAssembly(linearised=True, effects=[TiedPointMass(attach=place)]),
                 {"pm_mass": 0.1})
    bare = modes(ShaftAssembly(linearised=True), {})
    np.testing.assert_allclose(am[:5], tied[:5], rtol=1e-3)
    assert np.max(np.abs(am[:5] / bare[:5] - 1)) > 0.01  # the mass does move them
