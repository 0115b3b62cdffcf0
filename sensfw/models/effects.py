"""Physical effects that can be added to the shaft assembly (plugin group ``sensfw.effects``).

An effect declares where it can attach, the parameters it adds (with bounds, in the paper's
units) and the signatures it leaves in measurements, so that :mod:`sensfw.measure.diagnose`
can explain why it is a candidate. Adding an effect with its parameters at their neutral
values is not always the model without it; calibration finds the values.

Effects change the model in one of three ways: they add parameters that the model's contact
laws read (``clearance``, ``friction``, ``contact_hardening``), add force elements
(``preload``, ``damping``, ``flexible_mode``) or bodies (``flexible_mode``), or change a
body's mass (``added_mass``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import ClassVar

import numpy as np

from ..errors import SensfwError
from ..params import Parameter
from ..plugins import effects

MM = 1e-3


class Effect:
    """Base class: no bodies, no links, no parameters."""

    name: str = "effect"
    attach_points: tuple[str, ...] = ()
    signatures: tuple[str, ...] = ()
    description: str = ""
    #: calibration design: values per parameter (default 5 for one parameter, 3 for two)
    design_levels: ClassVar[dict[str, int]] = {}

    def __init__(self, attach: str | None = None):
        attach = attach or self.attach_points[0]
        if attach not in self.attach_points:
            raise SensfwError(f"effect {self.name!r} cannot attach to {attach!r}; it can "
                              f"attach to {', '.join(self.attach_points)}")
        self.attach = attach

    def parameters(self) -> list[Parameter]:
        return []

    def bodies(self, model, p: Mapping[str, float], bodies: list) -> list:
        return bodies

    def links(self, model, p: Mapping[str, float], links: list) -> list:
        return links

    def initial_guess(self, layout, guess: np.ndarray) -> None:
        """Start values of added coordinates for the static equilibrium (default 0)."""

    def seeds(self, comparisons) -> list[dict[str, float]]:
        """Parameter values suggested by the evidence of a model/measurement comparison
        (added to the calibration design); none by default."""
        return []

    def spec(self) -> dict:
        return {"name": self.name, "attach": self.attach}


def make_effect(spec) -> Effect:
    """An effect from its spec: a name, ``{"name": ..., "attach": ...}`` or an Effect."""
    if isinstance(spec, Effect):
        return spec
    if isinstance(spec, str):
        spec = {"name": spec}
    spec = dict(spec)
    return effects.get(spec.pop("name"))(**spec)


@effects.register("clearance")
class Clearance(Effect):
    """Radial play of the clutch in the driveshaft bore (the base model has none): the clutch
    rattles once the excitation lifts it off its seat."""

    name = "clearance"

    attach_points = ("clutch_drive",)
    signatures = ("harmonics (even and odd) that grow with excitation level",
                  "amplitude-dependent softening of the resonances it touches")

    def parameters(self):
        return [Parameter("clearance_gap", "mm", 3e-3, 5e-4, 1e-2, "radial play of the clutch",
                          "Effect: clearance")]


@effects.register("friction")
class Friction(Effect):
    """Axial stick-slip of the clutch in its bore, driven by the guidance normal force
    (dynamic coefficient 60 % of the static one, stiction transition at 10 % of the
    friction transition velocity)."""

    name = "friction"

    attach_points = ("clutch_drive",)
    signatures = ("odd harmonics", "amplitude-dependent damping: peaks flatten and widen "
                  "with level", "little frequency shift")

    def parameters(self):
        return [Parameter("friction_mu", "", 0.15, 0.02, 0.4, "static friction coefficient",
                          "Effect: friction"),
                Parameter("friction_velocity", "mm/s", 0.5, 0.05, 5.0,
                          "friction transition velocity", "Effect: friction")]


@effects.register("contact_hardening")
class ContactHardening(Effect):
    """Stiffening force exponent of the roller bearings L1/L3 (Hertz point contact 1.5
    instead of line contact 10/9). The coefficient is rescaled so the force at a
    penetration of 0.1 um is unchanged, so the exponent changes the curvature of the law,
    not its level."""

    name = "contact_hardening"

    attach_points = ("bearings",)
    signatures = ("harmonics that grow with excitation level",
                  "resonances of the bearing modes shift up with level")
    reference_penetration = 1e-4  # mm

    def parameters(self):
        return [Parameter("hardening_exponent", "", 1.4, 1.12, 2.0,
                          "force exponent of the L1/L3 radial contacts",
                          "Effect: contact_hardening")]


@effects.register("preload")
class Preload(Effect):
    """An extra axial force pushing the crankshaft onto its bushing flange (a seal or a
    pedal-side spring): stiffens the axial contact path."""

    name = "preload"

    attach_points = ("crankshaft",)
    signatures = ("axial resonances shift up", "harmonic content falls")

    def parameters(self):
        return [Parameter("preload_force", "N", 5.0, 0.5, 20.0, "axial force on the crankshaft",
                          "Effect: preload")]

    def links(self, model, p, links):
        from .shaft_assembly import HOUSING, Link

        force = p["preload_force"]

        def law(ops, u, v, contact):
            return force, 0.0

        return [*links, Link("crank_preload", HOUSING, (0.0, 0.0), "C", (0.0, 0.0), law)]


@effects.register("damping")
class Damping(Effect):
    """Viscous damping between the driveshaft and the housing (joint or structural damping
    the penalty contacts do not give)."""

    name = "damping"

    attach_points = ("driveshaft",)
    signatures = ("lower and wider peaks", "no new harmonics", "no frequency shift")

    def parameters(self):
        return [Parameter("extra_damping", "N*s/mm", 0.05, 0.005, 0.5,
                          "viscous damping D-housing at L3", "Effect: damping")]

    def links(self, model, p, links):
        from .shaft_assembly import HOUSING, Link

        c = p["extra_damping"] * 1e3
        x = model.geometry.x_l3

        def law(ops, u, v, contact):
            return -c * v[0], -c * v[1]

        return [*links, Link("extra_damping", HOUSING, (x, 0.0), "D", (x, 0.0), law)]


@effects.register("added_mass")
class AddedMass(Effect):
    """Mass at the crankshaft end (accelerometer, shaker armature, fixture), lumped into the
    crankshaft: its mass grows by ``m`` and its inertia by ``m x^2`` (``x`` the distance of the
    shaker point from the centre of mass; the small shift of the centre of mass is
    neglected)."""

    name = "added_mass"

    attach_points = ("crankshaft",)
    signatures = ("every crankshaft resonance shifts down", "no new harmonics")

    def parameters(self):
        return [Parameter("added_mass", "kg", 0.02, 0.002, 0.1, "mass at the crankshaft end",
                          "Effect: added_mass")]

    def bodies(self, model, p, bodies):
        m = p.get("added_mass", 0.02)
        x = model.geometry.x_force
        return [replace(b, mass=b.mass + m, inertia=b.inertia + m * x * x) if b.name == "C"
                else b for b in bodies]


@effects.register("flexible_mode")
class FlexibleMode(Effect):
    """An elastic mode the rigid model lacks (the paper's Fig. 12a): a modal mass on the
    crankshaft end, coupled radially and axially by a spring-damper tuned to the mode's
    frequency and modal damping ratio."""

    name = "flexible_mode"

    attach_points = ("crankshaft",)
    signatures = ("a new resonance peak", "no new harmonics")
    modal_mass = 0.03  # kg
    design_levels: ClassVar[dict[str, int]] = {"flex_frequency": 7, "flex_damping": 2}

    def parameters(self):
        return [Parameter("flex_frequency", "Hz", 2500.0, 600.0, 4500.0, "modal frequency",
                          "Effect: flexible_mode"),
                Parameter("flex_damping", "", 0.02, 0.003, 0.08, "modal damping ratio",
                          "Effect: flexible_mode")]

    def bodies(self, model, p, bodies):
        from .shaft_assembly import Body

        x = model.geometry.x_force
        return [*bodies, Body("F", 2, self.modal_mass, 0.0, (x, 0.0))]

    def links(self, model, p, links):
        from .shaft_assembly import Link

        w = 2 * math.pi * p["flex_frequency"]
        k = self.modal_mass * w * w
        c = 2 * p["flex_damping"] * self.modal_mass * w
        x = model.geometry.x_force

        def law(ops, u, v, contact):
            return -k * u[0] - c * v[0], -k * u[1] - c * v[1]

        return [*links, Link("flexible_mode", "C", (x, 0.0), "F", (0.0, 0.0), law)]

    def initial_guess(self, layout, guess):
        i, j = layout.offset["F"], layout.offset["C"]
        guess[i:i + 2] = guess[j:j + 2]

    def seeds(self, comparisons):
        """A measured resonance the model does not have is where the missing mode is."""
        out = []
        lo, hi = 600.0, 4500.0
        for c in comparisons[:1]:
            for r in c.resonances:
                f = r.get("measured_hz")
                if r.get("model_hz") is None and f and lo <= f <= hi:
                    zeta = float(np.clip(r.get("measured_damping") or 0.02, 0.003, 0.08))
                    # the coupled peak sits above the uncoupled modal frequency
                    out += [{"flex_frequency": float(np.clip(f * s, lo, hi)),
                             "flex_damping": zeta} for s in (0.8, 0.9, 1.0)]
        return out[:6]
