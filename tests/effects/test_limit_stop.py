"""The limit stop (a clearance to a stop at a body place) and the cubic spring at a body: their
force laws are the textbook piecewise-linear and Duffing stiffnesses about the body's static
state, checked against the analytic laws with the shaft model's own numpy forces; they carry no
static load, so the static state and the linearised model are those without them."""

import numpy as np
import pytest

from sensfw.excitation import LinearSweep
from sensfw.models.base import SolverSettings
from sensfw.models.bolted_beam import BoltedBeam
from sensfw.models.planar import statics
from sensfw.models.shaft_assembly import ShaftAssembly

K_STOP, GAP = 1e3, 4e-5  # N/mm, mm
STOP = {"stop_stiffness": K_STOP, "stop_gap": GAP}
GA = SolverSettings(method="GeneralizedAlpha", step=1 / 8192, auto_step=False)


def full(model, **values):
    p = model.parameters().nominal()
    p.update(values)
    return model.parameters().complete(p)


@pytest.fixture(scope="module")
def shaft():
    plain = ShaftAssembly()
    model = ShaftAssembly(effects=[{"name": "limit_stop", "attach": "crankshaft"}])
    return plain, model, full(model, **STOP)


def test_the_stop_carries_no_static_load(shaft):
    """The stop is centred where the crankshaft rests: the static state and the linearised
    matrices are the model's without it, to round-off."""
    plain, model, p = shaft
    q_plain = plain.equilibrium(full(plain))
    q_stop = model.equilibrium(p)
    np.testing.assert_array_equal(q_stop, q_plain)
    for a, b in zip(model.linear_matrices(p), plain.linear_matrices(full(plain)),
                    strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("d_um", [-0.2, -0.05, -0.03, 0.0, 0.03, 0.05, 0.2])
def test_the_stop_force_is_the_piecewise_linear_clearance_law(shaft, d_um):
    """Move the crankshaft by ``d`` along its transverse axis (a translation: its end point
    moves by ``d``) from the static state: the stop adds ``-k (|d| - gap) sign(d)`` once
    ``|d|`` exceeds the gap and nothing inside it (Worden & Tomlinson 2001)."""
    plain, model, p = shaft
    q0 = model.equilibrium(p)
    mech, ref = model.mechanism(p), plain.mechanism(full(plain))
    mech.anchor(q0)
    index = mech.coordinates()
    iy = index.offset["C"] + 1
    d = d_um * 1e-6
    q = q0.copy()
    q[iy] += d
    zero = np.zeros(len(q))
    added = statics.forces(mech, q, zero) - statics.forces(ref, q, zero)
    k, gap = K_STOP * 1e3, GAP * 1e-3
    expected = -k * (abs(d) - gap) * np.sign(d) if abs(d) > gap else 0.0
    assert added[iy] == pytest.approx(expected, rel=1e-9, abs=1e-12)
    # a force at the end point: its moment about the body's reference point
    g = model.geometry
    assert added[iy + 1] == pytest.approx(g.x_force * expected, rel=1e-9, abs=1e-12)
    others = np.delete(added, [iy, iy + 1])
    assert np.max(np.abs(others)) == 0.0


def test_the_stop_acts_on_the_beam_too():
    """At a body of the bolted beam (no static load: its static state is the reference
    one, where the stop is centred) a crossed stop changes the response of the second
    bending mode: a sweep through it at 10 N (tip motion of tens of micrometres) against a
    gap of 1 nm."""
    ex = LinearSweep(84.0, 110.0, 0.5, 2048.0, 10.0)
    beam = BoltedBeam()
    base = beam.simulate(beam.parameters().nominal(), ex, GA)
    model = BoltedBeam(effects=[{"name": "limit_stop", "attach": "beam2"}])
    p = full(model, stop_stiffness=1e4, stop_gap=1e-6)
    _, st, z0, _ = model.state(p)
    assert np.max(np.abs(z0)) == 0.0 and np.max(np.abs(st.residual(z0))) < 1e-9
    tight = model.simulate(p, ex, GA)
    for ch in base.channels:
        assert np.all(np.isfinite(tight.channels[ch]))
        assert not np.allclose(tight.channels[ch], base.channels[ch], rtol=1e-3), ch


@pytest.mark.parametrize("d_um", [-0.2, -0.03, 0.05, 0.3])
def test_a_cubic_spring_at_a_body_is_the_duffing_law_about_the_rest_position(d_um):
    """``cubic_stiffness`` at a body: like the stop, measured from the static state (no
    static load, the model's static state), and its force is ``-k3 d^3`` (Kerschen et al.
    2006, the Duffing oscillator) at the body point, with its moment."""
    k3 = 3e10  # N/mm^3
    plain = ShaftAssembly()
    model = ShaftAssembly(effects=[{"name": "cubic_stiffness", "attach": "crankshaft"}])
    p = full(model, cubic_stiffness=k3)
    q0 = model.equilibrium(p)
    np.testing.assert_array_equal(q0, plain.equilibrium(full(plain)))
    mech, ref = model.mechanism(p), plain.mechanism(full(plain))
    mech.anchor(q0)
    iy = mech.coordinates().offset["C"] + 1
    d = d_um * 1e-6
    q = q0.copy()
    q[iy] += d
    zero = np.zeros(len(q))
    added = statics.forces(mech, q, zero) - statics.forces(ref, q, zero)
    expected = -k3 * 1e9 * d**3  # N/mm^3 -> N/m^3
    assert added[iy] == pytest.approx(expected, rel=1e-9)
    assert added[iy + 1] == pytest.approx(model.geometry.x_force * expected, rel=1e-9)
    assert np.max(np.abs(np.delete(added, [iy, iy + 1]))) == 0.0
