"""Effects that change the law of a contact: clearance (play), friction, contact hardening.

Each wraps or replaces the :class:`~sensfw.models.places.ContactLaw` of the place it attaches
to, so it works on any model's contact places.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

from ..errors import SensfwError
from ..models.contact import FrictionLaw
from ..params import MM, Parameter
from ..plugins import effects
from .base import Effect
from .laws import WithDeadZone, WithFriction, WithPlay


@effects.register("clearance")
class Clearance(Effect):
    """Play at a contact (the shaft model's clutch has none in its bore): the parts rattle
    once the excitation lifts them off their seat. Where a static load keeps the contact
    closed (every contact of the shaft model below about 0.5 N), the play is never crossed;
    :class:`~sensfw.effects.elements.LimitStop` is play about the rest position. At a
    joint, a dead zone of the slip law (:class:`~sensfw.effects.laws.WithDeadZone`): the
    interface carries no tangential force until it has slipped by the gap (a bolt bearing
    on its hole after its clearance)."""

    name = "clearance"
    fits = ("contact", "joint")
    signatures = ("harmonics (even and odd) that grow with excitation level",
                  "resonances that move with level: down while the contact opens, up once "
                  "the motion exceeds the gap")
    # and where the measured levels all lie on one side of crossing the play, what it
    # changes does not change with level (a contact that never closes is a stiffness
    # missing, a linear difference): bench/recovery.py seed 2039 (a gap of 8.8 um at the
    # clutch's drive side, 0.03-0.2 N) shows amplitude independence and no other class
    signature_classes = frozenset({"hardening", "softening", "even_harmonics",
                                   "amplitude_independent"})

    neutral: ClassVar[dict[str, float]] = {"clearance_gap": 0.0}

    def parameters(self):
        return [Parameter("clearance_gap", "mm", 3e-3, 0.0, 1e-2, "play at the contact",
                          "Effect: clearance")]

    def apply(self, place, hooks, p):
        law, gap = hooks.contact_law(place.name), p["clearance_gap"] * MM
        if place.kind == "joint":
            if gap > 0:  # neutral: a dead zone of no width is the joint's own law
                hooks.set_contact_law(place.name, WithDeadZone(law, gap))
        else:
            hooks.set_contact_law(place.name, WithPlay(law, gap))


@effects.register("friction")
class Friction(Effect):
    """Stick-slip along a contact's tangent, driven by its normal force (dynamic
    coefficient 60 % of the static one, stiction transition at 10 % of the friction
    transition velocity; Eq. 3)."""

    name = "friction"
    fits = ("contact",)
    signatures = ("odd harmonics", "amplitude-dependent damping: peaks flatten and widen "
                  "with level", "resonances soften with level", "below the slip velocity "
                  "the regularised law is a viscous coupling: added damping and stiffness "
                  "that do not change with level")
    # measured on the shaft model at the clutch (tests/measure/test_signatures.py): the
    # 1.5 kHz mode sits 2.0 % above the model's with 4.6x its damping at 0.01-0.03 N (stuck,
    # viscous: amplitude independent) and falls to +0.8 % at 0.1 N (slipping: softening)
    signature_classes = frozenset({"softening", "amplitude_independent"})

    neutral: ClassVar[dict[str, float]] = {"friction_mu": 0.0}

    def parameters(self):
        return [Parameter("friction_mu", "", 0.15, 0.0, 0.4, "static friction coefficient",
                          "Effect: friction"),
                Parameter("friction_velocity", "mm/s", 0.5, 0.05, 5.0,
                          "friction transition velocity", "Effect: friction")]

    def apply(self, place, hooks, p):
        mu, v = p["friction_mu"], p["friction_velocity"] * MM
        law = FrictionLaw(mu, 0.6 * mu, 0.1 * v, v)
        hooks.set_contact_law(place.name, WithFriction(hooks.contact_law(place.name), law))


@effects.register("contact_hardening")
class ContactHardening(Effect):
    """A stiffer-growing force law at a penalty contact: its exponent ``b`` rises by
    ``hardening_increase`` (e.g. Hertz point contact 1.5 instead of line contact 10/9 at a
    roller bearing: +0.39). The coefficient is rescaled so the force at a penetration of
    0.1 um is unchanged: the exponent changes the curvature of the law, not its level."""

    name = "contact_hardening"
    fits = ("contact",)
    signatures = ("at a preloaded contact (one the static load keeps closed, as every "
                  "contact of the shaft model): the modes the contact carries shift at every "
                  "level (its tangent stiffness at the operating point changes) and even "
                  "harmonics grow (the power law is asymmetric about that point)",
                  "at a contact the motion closes from zero load: resonances that move up "
                  "with level")
    # measured on the shaft model (tests/measure/test_signatures.py): exponent 2 at the
    # gravity-loaded roller bearing L1 gives a constant +1.4 % shift of the 1.5 kHz mode and
    # H2/H1 13 dB above the model's at 0.03-0.1 N, no hardening; the textbook hardening needs
    # a contact that opens and closes, which no place of that model offers below ~1 N, or
    # one closed from zero load: cubic_stiffness at a body (a Duffing spring about the rest
    # position) hardens and does nothing else there
    signature_classes = frozenset({"hardening", "amplitude_independent", "even_harmonics"})
    reference_penetration = 1e-7  # m

    neutral: ClassVar[dict[str, float]] = {"hardening_increase": 0.0}

    def parameters(self):
        return [Parameter("hardening_increase", "", 0.3, 0.0, 0.9,
                          "increase of the contact's force exponent",
                          "Effect: contact_hardening")]

    def apply(self, place, hooks, p):
        law = hooks.contact_law(place.name)
        if not all(hasattr(law, a) for a in ("k", "b")):
            raise SensfwError(f"contact_hardening needs a power law k delta^b at "
                              f"{place.name!r}; its law is {type(law).__name__}")
        b = law.b + p["hardening_increase"]
        k = law.k * self.reference_penetration ** (law.b - b)
        hooks.set_contact_law(place.name, replace(law, k=k, b=b))
