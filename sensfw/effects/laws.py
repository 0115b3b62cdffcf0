"""Laws that wrap the law of a place: what the effects put in place of a contact's or a
joint's own law (:class:`~sensfw.models.places.ContactLaw`,
:class:`~sensfw.models.places.JointLaw`). Each keeps the law it wraps in ``base`` and
changes one part of it; all are plain data, so a wrapped law is hashable and printable.

* contacts: :class:`WithPlay` (clearance), :class:`WithFriction` (stick-slip friction);
* joints: :class:`WithResidual` (what micro-slip leaves of the joint's stiffness),
  :class:`WithCubic` (cubic stiffness), :class:`WithDeadZone` (clearance of the slip).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..models.contact import FrictionLaw, numpy_ops
from ..models.places import ContactLaw, JointLaw
from ..models.planar import plus


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


@dataclass(frozen=True)
class WithResidual:
    """A joint law whose tangential force is scaled by ``residual`` (what remains of the
    joint's own stiffness and damping where micro-slip's elements took the rest)."""

    base: JointLaw
    residual: float

    def tangential(self, ops, s, s_dot):
        return self.residual * self.base.tangential(ops, s, s_dot)

    def normal(self, ops, g, g_dot):
        return self.base.normal(ops, g, g_dot)


def tangential_stiffness(law: JointLaw, h: float = 1e-9) -> float:
    """``-dF_t/ds`` of a joint law at zero slip (N/m; central difference)."""
    ops = numpy_ops()
    return float(-(law.tangential(ops, h, 0.0) - law.tangential(ops, -h, 0.0)) / (2 * h))


@dataclass(frozen=True)
class WithCubic:
    """A joint law with a cubic term ``-k3 s^3`` in its tangential force (hardening)."""

    base: JointLaw
    k3: float

    def tangential(self, ops, s, s_dot):
        return self.base.tangential(ops, s, s_dot) - self.k3 * s * s * s

    def normal(self, ops, g, g_dot):
        return self.base.normal(ops, g, g_dot)


@dataclass(frozen=True)
class WithDeadZone:
    """A joint law with a dead zone: no tangential force within ``+-gap`` of slip (a bolt
    that must cross its hole's clearance before it bears)."""

    base: JointLaw
    gap: float

    def tangential(self, ops, s, s_dot):
        engaged = s - ops.max(ops.min(s, self.gap), -self.gap)
        rate = ops.where(ops.abs(s) > self.gap, s_dot, 0.0)
        return self.base.tangential(ops, engaged, rate)

    def normal(self, ops, g, g_dot):
        return self.base.normal(ops, g, g_dot)
