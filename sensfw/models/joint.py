"""Force laws of joint places (:class:`~sensfw.models.places.JointLaw`): a bolted interface
that stays closed and may slip tangentially.

The base law is linear (:class:`LinearJoint`): the stuck interface's tangential stiffness and
damping, and a stiff normal contact. Effects (:mod:`sensfw.effects.joint`) wrap it (cubic
stiffness, a dead zone) or add force elements at the joint's points (micro-slip friction).
Laws take and return expressions built from ``+ - * /`` and ``ops`` (numpy or Exudyn
symbolic, :mod:`sensfw.models.contact`), in SI units.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LinearJoint:
    """``F_t = -k_t s - c_t s_dot`` along the tangent and ``F_n = -k_n g - c_n g_dot`` along
    the normal (N/m, N s/m, for the whole joint)."""

    k_t: float
    c_t: float
    k_n: float
    c_n: float = 0.0

    def tangential(self, ops, s, s_dot):
        return -self.k_t * s - self.c_t * s_dot

    def normal(self, ops, g, g_dot):
        return -self.k_n * g - self.c_n * g_dot
