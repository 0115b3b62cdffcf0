"""Effects that add force elements, bodies or mass: damping, preload, added mass and an
elastic mode the rigid model lacks."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from ..params import Parameter
from ..plugins import effects
from .base import Effect


@effects.register("damping")
class Damping(Effect):
    """Viscous damping across a contact or a joint (or from a body to the ground), in both
    in-plane directions: joint or structural damping the penalty contacts do not give."""

    name = "damping"
    fits = ("contact", "body", "joint")
    preferred_places = ("bearing_l3",)
    signatures = ("lower and wider peaks", "no new harmonics", "no frequency shift")
    signature_classes = frozenset({"amplitude_independent"})

    neutral: ClassVar[dict[str, float]] = {"extra_damping": 0.0}

    def parameters(self):
        return [Parameter("extra_damping", "N*s/mm", 0.05, 0.0, 0.5,
                          "viscous damping across the place", "Effect: damping")]

    def apply(self, place, hooks, p):
        c = p["extra_damping"] * 1e3

        def law(ops, u, v):
            return -c * v[0], -c * v[1]

        hooks.add_force(f"damping@{place.name}", place.body0 or hooks.ground, place.r0,
                        place.body1, place.r1, law)


@effects.register("preload")
class Preload(Effect):
    """A constant force on a body along its axis (a seal, a pedal-side spring): it
    stiffens the contact path it pushes into."""

    name = "preload"
    fits = ("body",)
    preferred_places = ("crankshaft",)
    signatures = ("resonances of the loaded contact path shift up", "harmonic content "
                  "changes (mostly falls)", "a static (DC) shift")
    signature_classes = frozenset({"even_harmonics", "amplitude_independent"})

    neutral: ClassVar[dict[str, float]] = {"preload_force": 0.0}

    def parameters(self):
        return [Parameter("preload_force", "N", 5.0, 0.0, 20.0, "axial force on the body",
                          "Effect: preload")]

    def apply(self, place, hooks, p):
        fx, fy = (p["preload_force"] * t for t in place.tangent)

        def law(ops, u, v):
            return fx, fy

        hooks.add_force(f"preload@{place.name}", hooks.ground, place.r1, place.body1,
                        place.r1, law)


@effects.register("added_mass")
class AddedMass(Effect):
    """Mass at a body's reference point (accelerometer, shaker armature, fixture), lumped
    into the body: its mass grows by ``m`` and its inertia by ``m r^2`` (the small shift of
    the centre of mass is neglected)."""

    name = "added_mass"
    fits = ("body",)
    preferred_places = ("crankshaft",)
    signatures = ("the resonances the body takes part in shift down", "no new harmonics")
    signature_classes = frozenset({"amplitude_independent"})

    neutral: ClassVar[dict[str, float]] = {"added_mass": 0.0}

    def parameters(self):
        return [Parameter("added_mass", "kg", 0.02, 0.0, 0.1, "mass at the body's point",
                          "Effect: added_mass")]

    def apply(self, place, hooks, p):
        hooks.add_mass(place.body1, p["added_mass"], place.r1)


@effects.register("flexible_mode")
class FlexibleMode(Effect):
    """An elastic mode the rigid model lacks (the paper's Fig. 12a): a modal mass at a
    body's point, coupled in both in-plane directions by a spring-damper tuned to the
    mode's frequency and modal damping ratio. With no modal mass the mode is absent."""

    name = "flexible_mode"
    fits = ("body",)
    preferred_places = ("crankshaft",)
    signatures = ("a new resonance peak", "no new harmonics")
    signature_classes = frozenset({"new_peak", "amplitude_independent"})
    neutral: ClassVar[dict[str, float]] = {"flex_mass": 0.0}

    def parameters(self):
        return [Parameter("flex_frequency", "Hz", 2500.0, 600.0, 4500.0, "modal frequency",
                          "Effect: flexible_mode"),
                Parameter("flex_damping", "", 0.02, 0.003, 0.08, "modal damping ratio",
                          "Effect: flexible_mode"),
                Parameter("flex_mass", "kg", 0.03, 0.0, 0.06, "modal mass",
                          "Effect: flexible_mode")]

    def apply(self, place, hooks, p):
        m = p["flex_mass"]
        if m <= 0:  # neutral: no mode
            return
        w = 2 * math.pi * p["flex_frequency"]
        k = m * w * w
        c = 2 * p["flex_damping"] * m * w
        body = f"mode@{place.name}"
        hooks.add_body(body, m, follows=(place.body1, place.r1))

        def law(ops, u, v):
            return -k * u[0] - c * v[0], -k * u[1] - c * v[1]

        hooks.add_force(f"flexible_mode@{place.name}", place.body1, place.r1, body,
                        (0.0, 0.0), law)

    def probes(self, comparisons):
        """A measured resonance the model does not have is where the missing mode is (the
        coupled peak sits above the uncoupled frequency); without one, three frequencies
        spread over the range."""
        lo, hi = 600.0, 4500.0
        out = []
        for c in comparisons[:1]:
            for r in c.resonances:
                f = r.get("measured_hz")
                if r.get("model_hz") is None and f and lo <= f <= hi:
                    zeta = float(np.clip(r.get("measured_damping") or 0.02, 0.003, 0.08))
                    out += [{"flex_frequency": float(np.clip(f * s, lo, hi)),
                             "flex_damping": zeta, "flex_mass": 0.03} for s in (0.85, 1.0)]
        if not out:
            out = [{"flex_frequency": f, "flex_damping": 0.02, "flex_mass": 0.03}
                   for f in (800.0, 1300.0, 2100.0, 3400.0)]
        return out[:4]
