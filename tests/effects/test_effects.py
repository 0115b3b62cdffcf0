"""Effects are physics at a named place of any model (issue 12, item 1): each built-in acts
at every place it fits through the model's hooks, with the physics it claims; the model holds
no effect names; a third-party effect registered by entry point does what a built-in does."""

import ast
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from sensfw.effects import Effect
from sensfw.errors import SensfwError
from sensfw.excitation import Chirp
from sensfw.models.bolted_beam import BoltedBeam
from sensfw.models.contact import numpy_ops
from sensfw.models.places import fitting_places
from sensfw.models.planar import statics
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly
from sensfw.plugins import effects

NOMINAL = PARAMETERS.nominal()
OPS = numpy_ops()
ROOT = Path(__file__).resolve().parents[2]


def full(model, **values):
    p = model.parameters().nominal()
    p.update(values)
    return model.parameters().complete(p)


def test_every_effect_attaches_at_every_place_it_fits_and_has_a_static_state():
    places = ShaftAssembly().places()
    kinds = {pl.kind for pl in places.values()}
    assert kinds == {"contact", "body"}
    tried = 0
    for name in effects.names():
        cls = effects.get(name)
        fits = fitting_places(places, cls)
        if not fits:  # a joint effect, or one that needs sliders: it fits the beam
            assert fitting_places(BoltedBeam().places(), cls), name
            continue
        for place in fits:
            model = ShaftAssembly(effects=[{"name": name, "attach": place}])
            p = full(model)
            q0 = model.equilibrium(p)
            worst = np.max(np.abs(model.generalized_forces(q0, np.zeros(len(q0)), p)))
            assert worst < 1e-6, (name, place, worst)
            tried += 1
    # clearance, friction, hardening and damping at 8 contacts; damping, preload, mass,
    # mode, limit stop and cubic stiffness at 3 bodies
    assert tried == 4 * 8 + 6 * 3


def test_attach_names_a_real_place_of_a_fitting_kind():
    with pytest.raises(SensfwError, match=r"no place 'moon'.*fits driveshaft, crankshaft"):
        ShaftAssembly(effects=[{"name": "added_mass", "attach": "moon"}])
    with pytest.raises(SensfwError, match=r"'flange' is a contact"):
        ShaftAssembly(effects=[{"name": "added_mass", "attach": "flange"}])
    with pytest.raises(SensfwError, match=r"both add parameter 'added_mass'"):
        ShaftAssembly(effects=[{"name": "added_mass", "attach": "crankshaft"},
                               {"name": "added_mass", "attach": "clutch"}])
    # without attach: the effect's preferred place
    assert ShaftAssembly(effects=["clearance"]).effects[0].attach == "clutch_drive"


def _strings_outside_preferred_places(tree: ast.AST) -> set[str]:
    """String constants of a module, except in a ``preferred_places`` declaration."""
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == "preferred_places" for t in targets):
                skip.update(id(n) for n in ast.walk(node))
    return {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
            and isinstance(n.value, str) and id(n) not in skip}


def test_the_model_holds_no_effect_names():
    """The models must not look effects or their parameters up by name: the one place a
    model names an effect is its ``preferred_places`` declaration (where such an effect
    goes when it names no place), which the effects read through the model."""
    words = set()
    for name in effects.names():
        words.add(name)
        words.update(p.name for p in effects.get(name)().parameters())
    for path in (ROOT / "sensfw" / "models").rglob("*.py"):
        text = path.read_text()
        named = words & _strings_outside_preferred_places(ast.parse(text))
        assert not named, (path.name, named)
        for w in ("clearance_gap", "friction_mu", "hardening_increase", "preload_force",
                  "extra_damping", "flex_frequency"):
            assert w not in text, (path.name, w)
    # and no effect names a model's place (a place named like a kind is left out: "joint")
    places = {n for m in (ShaftAssembly(), BoltedBeam()) for n, pl in m.places().items()
              if n != pl.kind}
    for path in (ROOT / "sensfw" / "effects").rglob("*.py"):
        tree = ast.parse(path.read_text())
        named = places & {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)}
        assert not named, (path.name, named)


def test_contact_hardening_changes_only_its_contact_and_keeps_the_force_at_0_1_um():
    base, hard = ShaftAssembly(), ShaftAssembly(effects=[
        {"name": "contact_hardening", "attach": "bearing_l3"}])
    p = full(hard, hardening_increase=1.7 - 10 / 9)  # L3 is a line contact, b = 10/9
    law0 = base.mechanism(p).laws
    law1 = hard.mechanism(p).laws
    changed = [k for k in law0 if law0[k] != law1[k]]
    assert changed == ["bearing_l3"]
    d_ref = 1e-7
    f0 = law0["bearing_l3"].normal(OPS, d_ref, 0.0)
    assert law1["bearing_l3"].normal(OPS, d_ref, 0.0) == pytest.approx(f0, rel=1e-12)
    # doubling the penetration multiplies the elastic force by 2^b
    ratio = law1["bearing_l3"].normal(OPS, 4e-6, 0.0) / law1["bearing_l3"].normal(OPS, 2e-6, 0.0)
    assert ratio == pytest.approx(2**1.7, rel=1e-12)


def test_added_mass_and_damping_change_the_matrices_by_what_they_add():
    m0 = ShaftAssembly()
    mass = ShaftAssembly(effects=[{"name": "added_mass", "attach": "crankshaft"}])
    p = full(mass, added_mass=0.05)
    M0, _, _ = m0.linear_matrices(NOMINAL)
    M1, _, _ = mass.linear_matrices(p)
    x = m0.geometry.x_force
    # C's coordinates are 3..5, now of the centre of mass of C and the point mass together:
    # m on x and y, and on the rotation the pair's inertia about their common centre, which
    # lies m x / (M + m) along: M (m x / (M + m))^2 + m (M x / (M + m))^2 = m x^2 M / (M + m)
    # (parallel axes); the mass matrix stays diagonal in these coordinates
    M, m = M0[3, 3], 0.05
    np.testing.assert_allclose(np.diag(M1 - M0),
                               [0, 0, 0, m, m, m * x * x * M / (M + m), 0, 0], atol=1e-15)
    np.testing.assert_allclose(M1 - np.diag(np.diag(M1)), 0.0, atol=0)
    damp = ShaftAssembly(effects=[{"name": "damping", "attach": "slide_bearing_1"}])
    p = full(damp, extra_damping=0.2)
    q0 = damp.equilibrium(p)
    _, _, D1 = damp.linear_matrices(p, q0)
    _, _, D0 = m0.linear_matrices(NOMINAL, q0)
    # a damper c = 200 N s/m between D and C at (x, -r): dD = c G^T G with G the difference of
    # the two points' velocity Jacobians
    xs, r = m0.geometry.x_sb[0], -m0.geometry.r_sb
    J = np.zeros((2, 8))
    J[:, 0:3] = -np.array([[1, 0, -r], [0, 1, xs]])
    J[:, 3:6] = np.array([[1, 0, -r], [0, 1, xs]])
    np.testing.assert_allclose(D1 - D0, 200.0 * J.T @ J, atol=1e-3, rtol=1e-6)


def test_clearance_lets_the_clutch_move_by_its_gap():
    base = ShaftAssembly()
    play = ShaftAssembly(effects=[{"name": "clearance", "attach": "clutch_drive"}])
    p = full(play, clearance_gap=4e-3)
    q_base, q_play = base.equilibrium(p), play.equilibrium(p)
    # the ramp's reaction (the clutch spring pushes K onto C's inclined face) lifts the clutch
    # K (coordinates 6, 7) against the top of the bore: with play it sits one gap higher
    # relative to D's bore point, its contact deflection nearly unchanged (same loads)
    dy = (q_play[7] - q_play[1]) - (q_base[7] - q_base[1])
    assert dy == pytest.approx(4e-6, rel=0.02)


def test_flexible_mode_adds_a_mode_near_its_frequency():
    mode = ShaftAssembly(effects=[{"name": "flexible_mode", "attach": "driveshaft"}])
    p = full(mode, flex_frequency=3000.0, flex_damping=0.01)
    M, K, _ = mode.linear_matrices(p)
    assert M.shape == (10, 10)  # two more coordinates
    w = np.sqrt(np.abs(np.linalg.eigvals(np.linalg.solve(M, K)))) / (2 * np.pi)
    # the modal mass (0.03 kg) is light against the driveshaft (0.5 kg): the coupled mode
    # sits within a few per cent of the uncoupled 3 kHz
    assert np.min(np.abs(w / 3000.0 - 1)) < 0.05, np.sort(w)


THIRD_PARTY = '''
from dataclasses import replace

from sensfw.effects import Effect
from sensfw.params import Parameter


class PowerLaw(Effect):
    """A third-party re-implementation of contact_hardening through the public hooks."""

    name = "power_law"
    fits = ("contact",)

    def parameters(self):
        return [Parameter("power_increase", "", 0.3, 0.0, 0.9)]

    def apply(self, place, hooks, p):
        law = hooks.contact_law(place.name)
        b = law.b + p["power_increase"]
        hooks.set_contact_law(place.name, replace(law, k=law.k * 1e-7 ** (law.b - b), b=b))
'''


@pytest.fixture
def third_party(tmp_path, monkeypatch):
    """A package ``tp_effects`` with an entry point in ``sensfw.effects``, as pip would
    install it (a dist-info folder on sys.path)."""
    (tmp_path / "tp_effects.py").write_text(textwrap.dedent(THIRD_PARTY))
    info = tmp_path / "tp_effects-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: tp-effects\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[sensfw.effects]\npower_law = tp_effects:PowerLaw\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(effects, "_entry_points_loaded", False)
    yield
    effects._items.pop("power_law", None)
    effects._origin.pop("power_law", None)
    sys.modules.pop("tp_effects", None)


def test_third_party_effect_by_entry_point_acts_exactly_as_the_builtin(third_party):
    assert effects.origin("power_law") == "entry point tp_effects:PowerLaw"
    assert issubclass(effects.get("power_law"), Effect)
    ours = ShaftAssembly(effects=[{"name": "contact_hardening", "attach": "clutch_crank"}])
    theirs = ShaftAssembly(effects=[{"name": "power_law", "attach": "clutch_crank"}])
    p1 = full(ours, hardening_increase=0.6)
    p2 = full(theirs, power_increase=0.6)
    assert ours.mechanism(p1).laws == theirs.mechanism(p2).laws
    # the same simulation, bit for bit
    chirp = Chirp(50, 5000, 0.02, 20000, 0.2)
    a = ours.simulate(p1, chirp)
    b = theirs.simulate(p2, chirp)
    for ch in a.channels:
        assert np.array_equal(a.channels[ch], b.channels[ch]), ch


def test_a_third_party_model_can_offer_places_and_take_builtin_effects():
    """The hooks are a contract: a tiny model built on the planar mechanism takes a
    built-in effect without knowing it."""
    from sensfw.models.contact import PenaltyLaw
    from sensfw.models.places import Place, resolve_places
    from sensfw.models.planar import Body, Link, Mechanism

    place = Place("seat", "contact", "", "H", (0.0, 0.0), "M", (0.0, 0.0))

    def law(ops, u, v, contact):
        return 0.0, contact.one_sided("seat", -u[1], -v[1])

    def mech():
        return Mechanism(bodies=[Body("M", 2, 1.0)], links=[Link("seat", "H", (0, 0), "M",
                                                                   (0, 0), law)],
                         laws={"seat": PenaltyLaw(k=1e6, b=1.0, c=0.0, dmax=1e-6)},
                         places={"seat": place})

    (eff, pl), = resolve_places({"seat": place}, [effects.get("clearance")()], "tiny")
    m0, m1 = mech(), mech()
    eff.apply(pl, m1, {"clearance_gap": 0.01})
    # weight 9.81 N on a linear seat 1e6 N/m: 9.81 um deflection, plus the 10 um gap
    # start lightly in contact (a contact that is open at the start gives no gradient)
    q0 = statics.equilibrium(m0, np.array([0.0, -1e-6]))
    q1 = statics.equilibrium(m1, np.array([0.0, -1e-5]))
    assert q0[1] == pytest.approx(-9.81e-6, rel=1e-9)
    assert q1[1] - q0[1] == pytest.approx(-1e-5, rel=1e-9)


def test_every_effect_vanishes_exactly_at_its_neutral_values():
    """Diagnosis starts each candidate at its neutral values, from the calibrated model
    without it: there the effect must be the model without it, bit for bit, so that a
    calibrated candidate can only end better than the hypothesis it extends."""
    chirp = Chirp(50, 5000, 0.02, 20000, 0.2)
    base = ShaftAssembly().simulate(NOMINAL, chirp)
    shaft = ShaftAssembly().places()
    for name in effects.names():
        cls = effects.get(name)
        assert cls.neutral, f"{name} declares no neutral values"
        if not fitting_places(shaft, cls):  # fits the beam: tests/effects/test_joint_effects
            continue
        model = ShaftAssembly(effects=[name])
        p = full(model, **cls.neutral)
        sig = model.simulate(p, chirp)
        for ch in base.channels:
            assert np.array_equal(sig.channels[ch], base.channels[ch]), (name, ch)


def test_neutral_values_and_probes_lie_within_the_bounds():
    """Calibration axes span the parameters' bounds and diagnosis starts at the neutral
    values: they must be on those axes, and so must the probes, each of which must move the
    effect away from neutral."""
    for name in effects.names():
        eff = effects.get(name)()
        bounds = {p.name: (p.min, p.max) for p in eff.parameters()}
        assert set(eff.neutral) <= set(bounds), name
        for k, v in eff.neutral.items():
            assert bounds[k][0] <= v <= bounds[k][1], (name, k, v)
        probes = eff.probes([])
        assert probes, name
        for probe in probes:
            for k, v in probe.items():
                assert bounds[k][0] <= v <= bounds[k][1], (name, k, v)
            assert any(probe.get(k, v) != v for k, v in eff.neutral.items()), (name, probe)
