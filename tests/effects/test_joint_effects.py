"""Effects on the bolted beam (issue 14, item 3): every effect that fits one of its places
acts there through the hooks; the joint effects have the physics they claim (micro-slip
softens and damps with level, cubic stiffness hardens, clearance is a dead zone); the
generic ones (damping, added mass) change the matrices by what they add."""

import numpy as np
import pytest
import scipy.linalg as sl

from sensfw.excitation import LinearSweep
from sensfw.models.base import SolverSettings
from sensfw.models.bolted_beam import BoltedBeam
from sensfw.models.bolted_beam.assembly import solve_static
from sensfw.models.contact import numpy_ops
from sensfw.models.joint import LinearJoint
from sensfw.models.places import fitting_places
from sensfw.plugins import effects
from sensfw.signal import frf

OPS = numpy_ops()
GA = SolverSettings(method="GeneralizedAlpha", step=1 / 8192, auto_step=False)


def full(model, **values):
    return model.parameters().complete(values)


def own(p):
    """The base model's parameters of ``p``."""
    return {k: p[k] for k in BoltedBeam().parameters()}


def second_mode(model, p):
    """The second bending mode (a joint without slip stiffness adds a sliding mode at 0)."""
    f = model.eigenfrequencies(p, 3)
    return f[f > 1.0][1]


def test_every_effect_attaches_at_every_place_of_the_beam_it_fits():
    places = BoltedBeam().places()
    assert {pl.kind for pl in places.values()} == {"joint", "contact", "body"}
    tried = 0
    for name in effects.names():
        for place in fitting_places(places, effects.get(name)):
            model = BoltedBeam(effects=[{"name": name, "attach": place}])
            p = full(model)
            _, st, z0, _ = model.state(p)
            # a static state: the force elements balance the beams (N)
            assert np.max(np.abs(st.residual(z0))) < 1e-6, (name, place)
            tried += 1
    # damping at 4 places; clearance at the joint and the clamp; added mass, preload,
    # flexible mode, limit stop, cubic stiffness and dry friction at the 2 beams; micro-slip
    # and cubic stiffness at the joint; friction and contact hardening at the clamp
    assert tried == 4 + 2 + 6 * 2 + 2 + 2


def test_every_effect_vanishes_exactly_at_its_neutral_values_on_the_beam():
    """As on the shaft model (tests/effects/test_effects.py): at its neutral values every
    effect, at every place of the beam it fits, is the beam without it, bit for bit (a
    quarter-second sweep through the second mode at 10 N: the joint slips by micrometres, so
    a dead zone, a cubic term or sliders that were only nearly neutral would show)."""
    ex = LinearSweep(84.0, 96.0, 0.25, 1024.0, 10.0)
    base = BoltedBeam().simulate(BoltedBeam().parameters().nominal(), ex, GA)
    tried = 0
    for name in effects.names():
        cls = effects.get(name)
        for place in fitting_places(BoltedBeam().places(), cls):
            model = BoltedBeam(effects=[{"name": name, "attach": place}])
            sig = model.simulate(full(model, **cls.neutral), ex, GA)
            for ch in base.channels:
                assert np.array_equal(sig.channels[ch], base.channels[ch]), (name, place, ch)
            tried += 1
    assert tried == 4 + 2 + 6 * 2 + 2 + 2  # as in the test above


def test_the_joint_place_lists_its_interface_points():
    g = BoltedBeam().geometry
    joint = BoltedBeam().places()["joint"]
    assert [r0[0] for r0, _ in joint.points] == pytest.approx(list(g.interface_x()))
    assert joint.r0 == joint.points[-1][0]  # the free-side end, where bending slips most


def test_added_mass_adds_exactly_its_mass_at_the_point():
    base = BoltedBeam()
    mass = BoltedBeam(effects=[{"name": "added_mass", "attach": "beam2"}])
    p = full(mass, added_mass=0.01)
    M0, _, _ = base.linear_matrices(own(p))
    M1, _, _ = mass.linear_matrices(p)
    _, st, _, _ = mass.state(p)
    i = st.coordinate("beam2", (base.geometry.free_end, 0.0))
    dM = M1 - M0
    assert dM[i, i] == pytest.approx(0.01, rel=1e-9) and dM[i + 1, i + 1] == pytest.approx(
        0.01, rel=1e-9)
    dM[i, i] = dM[i + 1, i + 1] = 0.0
    assert np.max(np.abs(dM)) < 1e-12
    # 10 g at the free end, where the second mode moves most: the mode drops (Rayleigh)
    assert second_mode(mass, p) < second_mode(base, own(p)) - 1.0


def test_damping_at_the_joint_adds_a_dashpot_between_its_two_points():
    base = BoltedBeam()
    damp = BoltedBeam(effects=[{"name": "damping", "attach": "joint"}])
    p = full(damp, extra_damping=0.2)
    _, _, D0 = base.linear_matrices(own(p))
    _, _, D1 = damp.linear_matrices(p)
    _, st, _, _ = damp.state(p)
    x = base.geometry.joint_x
    i, j = st.coordinate("beam1", (x, 0.0)), st.coordinate("beam2", (x, 0.0))
    G = np.zeros((2, st.n))
    G[[0, 1], [j, j + 1]] = 1.0
    G[[0, 1], [i, i + 1]] = -1.0
    np.testing.assert_allclose(D1 - D0, 200.0 * G.T @ G, atol=1e-3)


def test_dry_friction_holds_the_point_by_its_pre_sliding_spring_while_it_sticks():
    """Stuck (the law the statics and the linearisation use), dry friction is its
    pre-sliding spring from the ground to the body point along the place's normal: the
    stiffness matrix gains exactly ``k`` on that coordinate and nothing else."""
    base = BoltedBeam()
    model = BoltedBeam(effects=[{"name": "dry_friction", "attach": "beam1"}])
    p = full(model, dry_friction_force=0.3, dry_friction_stiffness=50.0)
    _, K0, _ = base.linear_matrices(own(p))
    _, K1, _ = model.linear_matrices(p)
    _, st, _, _ = model.state(p)
    i = st.coordinate("beam1", (base.geometry.shaker_x, 0.0)) + 1  # transverse (normal)
    dK = K1 - K0
    assert dK[i, i] == pytest.approx(50.0e3, rel=1e-9)
    dK[i, i] = 0.0
    assert np.max(np.abs(dK)) < 1e-6 * 50.0e3


def test_dry_friction_needs_a_model_that_carries_sliders():
    """The shaft model's explicit integrator carries no slider states: its places do not
    offer ``add_jenkins``, so dry friction fits none of them, and asking for it says why."""
    from sensfw.errors import SensfwError
    from sensfw.models.shaft_assembly import ShaftAssembly

    cls = effects.get("dry_friction")
    assert fitting_places(ShaftAssembly().places(), cls) == []
    assert fitting_places(BoltedBeam().places(), cls) == ["beam1", "beam2"]
    for spec in ({"name": "dry_friction", "attach": "crankshaft"}, "dry_friction"):
        with pytest.raises(SensfwError, match=r"needs the hook\(s\) add_jenkins, which no "
                                              r"place of model 'shaft_assembly' offers"):
            ShaftAssembly(effects=[spec])


def test_cubic_stiffness_adds_a_cubic_term_to_the_joint_law_only():
    base = BoltedBeam().assembly(BoltedBeam().parameters().nominal())
    model = BoltedBeam(effects=["cubic_stiffness"])
    p = full(model, cubic_stiffness=1e9)
    asm = model.assembly(p)
    assert asm.laws["clamp"] == base.laws["clamp"]
    s = 1e-5  # m
    k3 = 1e9 / 1e-9  # N/mm^3 -> N/m^3
    got = asm.laws["joint"].tangential(OPS, s, 0.0)
    assert got == pytest.approx(base.laws["joint"].tangential(OPS, s, 0.0) - k3 * s**3)
    # no effect on the linearisation at rest
    assert second_mode(model, p) == pytest.approx(second_mode(BoltedBeam(), own(p)), rel=1e-9)


def test_clearance_at_the_joint_is_a_dead_zone_of_its_slip_law():
    model = BoltedBeam(effects=[{"name": "clearance", "attach": "joint"}])
    p = full(model, clearance_gap=5e-3)  # 5 um
    law = model.assembly(p).laws["joint"]
    k = p["joint_stiffness"] * 1e3
    assert law.tangential(OPS, 4e-6, 1.0) == 0.0
    assert law.tangential(OPS, 8e-6, 0.0) == pytest.approx(-k * 3e-6)
    assert law.tangential(OPS, -8e-6, 0.0) == pytest.approx(k * 3e-6)
    # at rest the joint carries no slip stiffness: the second mode is that of the beams
    # with a released interface (the same assembly with a zero tangential law)
    released = BoltedBeam()
    asm = released.assembly(own(p))
    asm.set_contact_law("joint", LinearJoint(0.0, 0.0, asm.laws["joint"].k_n))
    st = released.structure(own(p), asm)
    M, K, _ = st.linear_matrices(solve_static(st))
    w2 = sl.eigh(K, M, eigvals_only=True)
    free = np.sqrt(w2[w2 > (2 * np.pi) ** 2]) / (2 * np.pi)  # without the sliding mode
    assert second_mode(model, p) == pytest.approx(free[1], rel=1e-6)
    assert second_mode(model, p) < second_mode(BoltedBeam(), own(p)) - 1.0


def test_micro_slip_is_an_iwan_model_whose_elements_add_up_to_its_parameters():
    from sensfw.effects.joint import MicroSlip

    eff = MicroSlip()
    p = {"microslip_residual": 0.2, "microslip_force": 400.0, "microslip_exponent": -0.5}
    parts = [kf for _ in range(4) for kf in eff.jenkins(p, 1.25e8, 4)]
    assert sum(k for k, _ in parts) == pytest.approx(1e8)  # N/m: 80 % of the joint's
    assert sum(f for _, f in parts) == pytest.approx(400.0)
    slips = [f / k for k, f in eff.jenkins(p, 1.25e8, 4)]
    assert slips == sorted(slips) and slips[0] > 0
    model = BoltedBeam(effects=["micro_slip"])
    asm = model.assembly(full(model))
    jenkins = [ln for ln in asm.links if ln.jenkins is not None]
    assert len(jenkins) == 4 * eff.elements and not asm.added  # elements, no slider bodies


def test_jenkins_return_mapping_traces_the_masing_loop():
    """The slider update (backward-Euler return mapping) under an imposed slip ``a sin``:
    the element's force is bounded by its slip force, the loop it traces encloses ``4 F (a -
    F / k)`` per cycle once ``a > F / k`` (a spring in series with a Coulomb slider: Masing's
    rule; Segalman 2005, Eq. 4) and none below, where it is the spring alone."""
    from sensfw.models.bolted_beam.simulation import JenkinsSliders
    from sensfw.models.planar import Link

    k, force = 2.0e6, 30.0  # N/m, N: slips beyond phi = 15 um
    ln = Link("j", "a", (0.0, 0.0), "b", (0.0, 0.0), None, about_static=True,
              offset=(0.0, 0.0), jenkins=(k, force, (1.0, 0.0)))
    for a in (0.5 * force / k, 2.0 * force / k, 10.0 * force / k):
        sl_ = JenkinsSliders([ln], "python")
        sl_.attach(None, lambda body, r, axis: {"a": 0, "b": 1}[body])
        t = np.linspace(0.0, 3.0, 30001)
        s = a * np.sin(2 * np.pi * t)
        f = []
        for si in s:
            sl_.update(np.array([0.0, si]))
            f.append(k * (si - sl_.x[0]))  # the spring's force after the step
        f = np.array(f)
        assert np.max(np.abs(f)) <= force * (1 + 1e-12)
        last = t >= 2.0  # a settled cycle
        area = abs(np.trapezoid(f[last], s[last]))
        expect = 4 * force * (a - force / k) if a > force / k else 0.0
        assert area == pytest.approx(expect, rel=2e-3, abs=1e-9 * force * a)


def _sampled(seconds=0.5, level=10.0):
    from sensfw.excitation import SampledForce

    sweep = LinearSweep(88.0, 94.0, seconds, 1024.0, level)
    return SampledForce(samples=sweep.force(), fs=1024.0, amplitude=level)


def test_jenkins_sliders_are_the_same_with_symbolic_and_python_user_functions():
    """The slider positions reach the C++-evaluated symbolic laws through named variables
    set before each step, and the Python laws through an array: the two runs agree to the
    Newton tolerance (1e-6 relative; measured 5e-8), with a sampled excitation (whose own
    pre-step function must call the sliders' first), while the elements slip (the run
    differs from all stuck and from the same run at a tenth of the level scaled up)."""
    model = BoltedBeam(effects=["micro_slip"])
    p = full(model, joint_stiffness=1.2e5, microslip_residual=1 / 6, microslip_force=200.0)
    ex = _sampled()
    sym = model.simulate(p, ex, GA).channels["Laser"]
    py = model.simulate(p, ex, GA, user_functions="python").channels["Laser"]
    assert np.max(np.abs(sym - py)) < 1e-6 * np.max(np.abs(sym))
    stuck = model.simulate({**p, "microslip_force": 20000.0}, ex, GA).channels["Laser"]
    small = model.simulate(p, _sampled(level=1.0), GA).channels["Laser"]
    assert np.sqrt(np.mean((sym - stuck) ** 2)) > 0.05 * np.sqrt(np.mean(stuck**2))
    assert np.sqrt(np.mean((sym - 10 * small) ** 2)) > 0.05 * np.sqrt(np.mean(sym**2))


def test_stuck_jenkins_elements_are_their_springs(monkeypatch):
    """Elements that never reach their slip force are springs: the run equals the same
    model whose elements are replaced by their springs (the stuck law statics and
    linearisation use), to the Newton tolerance; and its second mode is the linear
    model's: the elements and what is left of the joint add up to the joint's stiffness."""
    from sensfw.models.bolted_beam.simulation import JenkinsSliders

    model = BoltedBeam(effects=["micro_slip"])
    p = full(model, joint_stiffness=1.2e5, microslip_residual=1 / 6,
             microslip_force=20000.0)
    assert second_mode(model, p) == pytest.approx(second_mode(BoltedBeam(), own(p)), rel=1e-9)
    ex = _sampled(level=0.1)  # the interface carries ~10 N: every element sticks
    run = model.simulate(p, ex, GA).channels["Laser"]
    monkeypatch.setattr(JenkinsSliders, "law", lambda self, i: self.links[i].law)
    springs = model.simulate(p, ex, GA).channels["Laser"]
    assert np.max(np.abs(run - springs)) < 1e-5 * np.max(np.abs(springs))


def resonance(model, p, amplitude):
    """Peak frequency (parabolic interpolation on the 1/4 Hz grid) and peak magnitude of
    the laser FRF through the second mode."""
    sig = model.simulate(p, LinearSweep(84.0, 96.0, 2.0, 1024.0, amplitude, tail=2.0), GA)
    f, H = frf(sig.force, sig.channels["Laser"], sig.fs, estimator="H1")
    sel = (f > 85) & (f < 95)
    f, m = f[sel], np.abs(H[sel])
    i = int(np.argmax(m))
    a, b, c = np.log(m[i - 1: i + 2])
    shift = 0.5 * (a - c) / (a - 2 * b + c)
    return f[i] + shift * (f[1] - f[0]), m[i]


@pytest.mark.slow
def test_micro_slip_softens_and_damps_the_joint_as_the_level_rises():
    model = BoltedBeam(effects=["micro_slip"])
    p = full(model, joint_stiffness=1.2e5, microslip_residual=1 / 6, microslip_force=500.0)
    low, high = resonance(model, p, 0.1), resonance(model, p, 10.0)
    # at 0.1 N every element sticks: the linear model, whose joint stiffness the residual
    # and the Iwan springs share (within the 1/4 Hz grid's interpolation error)
    stuck = BoltedBeam().eigenfrequencies(own(p), 2)[1]
    assert abs(low[0] - stuck) < 0.15, (low, stuck)
    assert high[0] < low[0] - 0.5, (low, high)  # softening
    assert high[1] < 0.7 * low[1], (low, high)  # more damping: a lower peak per N


@pytest.mark.slow
def test_cubic_stiffness_hardens_the_joint_as_the_level_rises():
    model = BoltedBeam(effects=["cubic_stiffness"])
    p = full(model, joint_stiffness=2e4, cubic_stiffness=1e9)
    low, high = resonance(model, p, 0.1), resonance(model, p, 10.0)
    assert abs(low[0] - second_mode(model, p)) < 0.15, low
    assert high[0] > low[0] + 0.5, (low, high)


@pytest.mark.slow
def test_dry_friction_at_the_drive_point_sticks_at_low_level_and_slides_at_high():
    """A pre-sliding spring of 30 N/mm at the shaker's point (the second mode 3 Hz above the
    beam's without it) that slides at 0.2 N (7 um): at 5 mN of drive the point sticks and
    the mode is the stuck model's eigenfrequency; at 20 N it slides, friction takes 1 % of
    the drive and the mode is the beam's without the spring (the same 1/4 Hz interpolation
    tolerance as above; a Coulomb force of 1 % of the drive damps, it does not shift)."""
    model = BoltedBeam(effects=[{"name": "dry_friction", "attach": "beam1"}])
    p = full(model, dry_friction_force=0.2, dry_friction_stiffness=30.0)
    stuck, free = second_mode(model, p), second_mode(BoltedBeam(), own(p))
    assert stuck > free + 2.0, (stuck, free)  # the spring is a lever on the mode
    low, high = resonance(model, p, 0.005), resonance(model, p, 20.0)
    assert abs(low[0] - stuck) < 0.15, (low, stuck)
    assert abs(high[0] - free) < 0.15, (high, free)


@pytest.mark.parametrize("n", [1, 3, 12])
def test_micro_slip_elements_are_the_slip_densitys_quantiles(n):
    """``elements`` (an option, default 3) sets how many quantiles of the density
    ``phi^chi`` the Iwan model has: the springs and forces still add up to the parameters,
    and the slip displacements are the mid-quantiles ``((i + 1/2) / n)^(1 / (1 + chi))`` of
    the density on ``[0, phi_max]`` (its CDF is ``(phi / phi_max)^(1 + chi)``), so the
    smallest slip falls as ``n`` grows (the low-force tail). The option is checked and
    written back to the spec only when it differs from the default (the runs of the
    three-element model keep their keys)."""
    from sensfw.effects.joint import MicroSlip
    from sensfw.errors import OptionError
    from sensfw.models.places import make_effect

    chi = -0.5
    p = {"microslip_residual": 0.2, "microslip_force": 400.0, "microslip_exponent": chi}
    eff = make_effect({"name": "micro_slip", "elements": n})
    parts = eff.jenkins(p, 1.25e8)
    assert len(parts) == n
    assert sum(k for k, _ in parts) == pytest.approx(1e8)
    assert sum(f for _, f in parts) == pytest.approx(400.0)
    slips = np.array([f / k for k, f in parts])
    q = ((np.arange(n) + 0.5) / n) ** (1 / (1 + chi))
    assert slips / slips[-1] == pytest.approx(q / q[-1])
    assert eff.spec() == ({"name": "micro_slip"} if n == 3 else
                          {"name": "micro_slip", "elements": n})
    assert MicroSlip().elements == 3
    with pytest.raises(OptionError, match="elements"):
        make_effect({"name": "micro_slip", "elements": 0})


@pytest.mark.parametrize("chi", [-0.9, -0.5, 1.0])
def test_micro_slip_log_spacing_keeps_the_density_at_its_bin_edges(chi):
    """``spacing = "log"``: the elements' bins are log-spaced over ``decades`` below the
    largest slip, the first bin taking the tail below. Each element carries its bin's share
    of the density ``phi^chi``, so the stiffness of the elements whose slips lie below an
    edge ``e`` is the density's CDF there, ``(e / phi_max)^(1 + chi)``, exactly (what the
    joint has lost once the slip amplitude passes ``e``); each slip is its bin's mean under
    the density (``int phi rho / int rho``, by quadrature here), so it lies inside its bin;
    springs and forces add up to the parameters as with quantiles."""
    from scipy.integrate import quad

    from sensfw.errors import OptionError
    from sensfw.models.places import make_effect

    n, decades = 8, 4.0
    p = {"microslip_residual": 0.2, "microslip_force": 400.0, "microslip_exponent": chi}
    eff = make_effect({"name": "micro_slip", "elements": n, "spacing": "log",
                       "decades": decades})
    parts = eff.jenkins(p, 1.25e8)
    k = np.array([kf[0] for kf in parts])
    assert k.sum() == pytest.approx(1e8) and sum(f for _, f in parts) == pytest.approx(400.0)
    slips = np.array([f / k for k, f in parts])
    edges = 10.0 ** (-decades * (1 - np.arange(1, n + 1) / n))  # upper edges / phi_max
    # the force sets the slips' scale: phi_max from the top bin's mean
    phi_max = slips[-1] / (quad(lambda x: x ** (chi + 1), edges[-2], 1)[0]
                           / quad(lambda x: x ** chi, edges[-2], 1)[0])
    assert np.cumsum(k) / k.sum() == pytest.approx(edges ** (1 + chi), rel=1e-9)
    lower = np.concatenate([[0.0], edges[:-1]])
    for i in range(1, n):  # the tail bin's mean is checked by the CDF and the total force
        mean = (quad(lambda x: x ** (chi + 1), lower[i], edges[i])[0]
                / quad(lambda x: x ** chi, lower[i], edges[i])[0])
        assert slips[i] / phi_max == pytest.approx(mean, rel=1e-6)
        assert lower[i] < slips[i] / phi_max < edges[i]
    assert eff.spec() == {"name": "micro_slip", "elements": n, "spacing": "log",
                          "decades": decades}
    with pytest.raises(OptionError, match="spacing"):
        make_effect({"name": "micro_slip", "spacing": "linear"})
    with pytest.raises(OptionError, match="decades"):
        make_effect({"name": "micro_slip", "spacing": "log", "decades": 0})
