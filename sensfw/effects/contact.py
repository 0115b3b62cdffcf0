"""Effects that change the law of a contact: clearance (play), friction, contact hardening.

Each wraps or replaces the :class:`~sensfw.models.places.ContactLaw` of the place it attaches
to, so it works on any model's contact places.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..errors import SensfwError
from ..models.contact import Friction as FrictionLaw
from ..models.places import ContactLaw
from ..models.planar import plus
from ..params import Parameter
from ..plugins import effects
from .base import Effect

MM = 1e-3


@dataclass(frozen=True)
class WithPlay:
    """A contact law with extra play: the contact closes ``gap`` (m) later."""

    base: ContactLaw
    gap: float

    def normal(self, ops, delta, delta_dot):
        return self.base.normal(ops, delta - self.gap, delta_dot)

    def tangential(self, ops, fn, v):
        return self.base.tangential(ops, fn, v)

    def linearized(self, delta0: float) -> tuple[float, float, float]:
        return self.base.linearized(delta0 - self.gap)


@dataclass(frozen=True)
class WithFriction:
    """A contact law with (extra) regularised stick-slip friction driven by its normal
    force."""

    base: ContactLaw
    friction: FrictionLaw

    def normal(self, ops, delta, delta_dot):
        return self.base.normal(ops, delta, delta_dot)

    def tangential(self, ops, fn, v):
        return plus(self.friction.force(ops, fn, v), self.base.tangential(ops, fn, v))

    def linearized(self, delta0: float) -> tuple[float, float, float]:
        return self.base.linearized(delta0)


@effects.register("clearance")
class Clearance(Effect):
    """Play at a contact (the shaft model's clutch has none in its bore): the parts rattle
    once the excitation lifts them off their seat. At a joint, a dead zone of the slip law
    (:class:`~sensfw.effects.joint.WithDeadZone`): the interface carries no tangential
    force until it has slipped by the gap (a bolt bearing on its hole after its
    clearance)."""

    name = "clearance"
    fits = ("contact", "joint")
    preferred_places = ("clutch_drive",)
    signatures = ("harmonics (even and odd) that grow with excitation level",
                  "resonances that move with level: down while the contact opens, up once "
                  "the motion exceeds the gap")
    signature_classes = frozenset({"hardening", "softening", "even_harmonics"})

    def parameters(self):
        return [Parameter("clearance_gap", "mm", 3e-3, 5e-4, 1e-2, "play at the contact",
                          "Effect: clearance")]

    def apply(self, place, hooks, p):
        law, gap = hooks.contact_law(place.name), p["clearance_gap"] * MM
        if place.kind == "joint":
            from .joint import WithDeadZone

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
    preferred_places = ("clutch_drive",)
    signatures = ("odd harmonics", "amplitude-dependent damping: peaks flatten and widen "
                  "with level", "resonances soften with level")
    signature_classes = frozenset({"softening"})

    def parameters(self):
        return [Parameter("friction_mu", "", 0.15, 0.02, 0.4, "static friction coefficient",
                          "Effect: friction"),
                Parameter("friction_velocity", "mm/s", 0.5, 0.05, 5.0,
                          "friction transition velocity", "Effect: friction")]

    def apply(self, place, hooks, p):
        mu, v = p["friction_mu"], p["friction_velocity"] * MM
        law = FrictionLaw(mu, 0.6 * mu, 0.1 * v, v)
        hooks.set_contact_law(place.name, WithFriction(hooks.contact_law(place.name), law))


@effects.register("contact_hardening")
class ContactHardening(Effect):
    """A stiffer-growing force exponent at a penalty contact (e.g. Hertz point contact 1.5
    instead of line contact 10/9 at a roller bearing). The coefficient is rescaled so the
    force at a penetration of 0.1 um is unchanged: the exponent changes the curvature of the
    law, not its level."""

    name = "contact_hardening"
    fits = ("contact",)
    preferred_places = ("bearing_l1",)
    signatures = ("harmonics that grow with excitation level",
                  "resonances of the modes the contact carries shift up with level")
    signature_classes = frozenset({"hardening"})
    reference_penetration = 1e-7  # m

    def parameters(self):
        return [Parameter("hardening_exponent", "", 1.4, 1.12, 2.0,
                          "force exponent of the contact", "Effect: contact_hardening")]

    def apply(self, place, hooks, p):
        law = hooks.contact_law(place.name)
        if not all(hasattr(law, a) for a in ("k", "b")):
            raise SensfwError(f"contact_hardening needs a power law k delta^b at "
                              f"{place.name!r}; its law is {type(law).__name__}")
        b = p["hardening_exponent"]
        k = law.k * self.reference_penetration ** (law.b - b)
        hooks.set_contact_law(place.name, replace(law, k=k, b=b))
