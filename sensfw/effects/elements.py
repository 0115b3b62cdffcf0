"""Effects that add force elements, bodies or mass: damping, preload, added mass, an
elastic mode the rigid model lacks, a limit stop with play and dry friction against the
ground."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from ..models.contact import clearance_force
from ..params import MM, Parameter
from ..plugins import effects
from .base import Effect, add_spring_along_normal, decade_probes


@effects.register("damping")
class Damping(Effect):
    """Viscous damping across a contact or a joint (or from a body to the ground), in both
    in-plane directions: joint or structural damping the penalty contacts do not give."""

    name = "damping"
    fits = ("contact", "body", "joint")
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
    """Mass at a body's point (accelerometer, shaker armature, fixture), rigidly on the
    body: the body's centre of mass, mass and inertia become the pair's
    (:meth:`sensfw.models.planar.mechanism.Mechanism.add_mass`). Revision 1: it added ``m``
    and ``m r^2`` about the old centre, which lost the coupling between translation and
    rotation (the shaft model's modes 2-7 % off at 0.1 kg)."""

    name = "added_mass"
    revision = 1
    fits = ("body",)
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
        """A measured resonance the model does not have is where the missing mode is:
        probes at the peak and 15 % below it, though the mode's own frequency may lie on
        either side of its coupled peak (an oscillator attached to a structure is pushed
        away from the structure's nearest mode: ``bench/recovery.py`` seeds 2050 and 2042
        have modes of 798 and 3691 Hz whose new peaks are at 753 and 2747 Hz); the
        linearised fit and the calibration take it from there. Without such a peak, four
        frequencies spread over the range."""
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


@effects.register("limit_stop")
class LimitStop(Effect):
    """A clearance to a stop: the body point may move ``stop_gap`` either way along the
    place's normal from where it rests, then meets a linear stop of stiffness
    ``stop_stiffness`` (a shaft in an oversized catcher bore, a loose part in its pocket, a
    travel limiter). The textbook clearance nonlinearity, a piecewise-linear stiffness
    (Worden & Tomlinson 2001; Kerschen et al. 2006): linear while the
    motion stays inside the gap, stiffer once it crosses it, so resonances move up with
    level and odd harmonics grow. The stop is centred on the static state (the body rests
    in the middle of its play), so it carries no static load and no preload hides it,
    unlike :class:`~sensfw.effects.contact.Clearance` at the shaft model's gravity-loaded
    contacts. No stiffness: no stop."""

    name = "limit_stop"
    fits = ("body",)
    signatures = ("resonances that move up with level once the motion crosses the gap",
                  "odd harmonics that grow with level", "nothing below the gap")
    signature_classes = frozenset({"hardening"})

    neutral: ClassVar[dict[str, float]] = {"stop_stiffness": 0.0}

    def parameters(self):
        # ranges for the shaft model's bodies: the crankshaft's end moves 0.06-0.4 um at
        # 0.03-0.3 N, and a stop of 1e3 N/mm crossed there lifts its 1.5 kHz mode by ~2 %
        return [Parameter("stop_stiffness", "N/mm", 1e3, 0.0, 1e4, "stiffness of the stop",
                          "Effect: limit_stop"),
                Parameter("stop_gap", "mm", 4e-5, 1e-6, 5e-4,
                          "play on each side of the rest position", "Effect: limit_stop")]

    def apply(self, place, hooks, p):
        k, gap = p["stop_stiffness"] / MM, p["stop_gap"] * MM
        if k <= 0:  # neutral: no stop
            return
        add_spring_along_normal(
            hooks, place, f"limit_stop@{place.name}",
            lambda ops, e, e_dot: clearance_force(ops, e, e_dot, gap, k, 1.0, 0.0, 1.0))

    def probes(self, comparisons):
        """A twentieth of the largest stiffness at three gaps a factor 4 apart: a stop
        explains a hardening only where the motion crosses its gap, which a single gap can
        miss; and a crossed stop is a strong nonlinearity (at the shaft model's crankshaft
        2e3 N/mm lifts the 1.5 kHz mode by 5-9 % and breaks its single-mode fit), so the
        probes are soft."""
        return [{"stop_stiffness": 5e2, "stop_gap": g} for g in (1e-5, 4e-5, 1.6e-4)]


@effects.register("dry_friction")
class DryFriction(Effect):
    """Dry (Coulomb) friction of a body point against the ground along the place's normal:
    a Jenkins element, a spring of the pre-sliding stiffness in series with a Coulomb slider
    (Iwan 1966; Al-Bender & Swevers 2008 for pre-sliding). While the point sticks, the
    spring holds it; once its force reaches ``dry_friction_force`` the point slides against
    that constant force (the slider is return-mapped by the model's integrator, exact
    Coulomb friction with no regularising velocity: ``hooks.add_jenkins``). Something that
    rubs where it should not: a shaker's armature in its guidance, a stinger's fixture, a
    support or a cable.

    At a drive point it takes a fixed force off the excitation, so the response per unit
    drive is lowest at the lowest level, and the stiffness it adds while stuck is lost as it
    slips: resonances move down with level, and its loss per cycle, ``4 F (a - F / k)`` for a
    motion of amplitude ``a > F / k`` (Masing), is a damping that peaks near the level where
    it breaks free and falls as ``1 / a`` above it. No force: no friction."""

    name = "dry_friction"
    fits = ("body",)
    needs = ("add_jenkins",)
    signatures = ("the response per unit drive is lowest at the lowest level",
                  "resonances move down as the point breaks free",
                  "damping that peaks near the level where it starts to slide", "odd harmonics")
    signature_classes = frozenset({"softening"})
    neutral: ClassVar[dict[str, float]] = {"dry_friction_force": 0.0}

    def parameters(self):
        # a shaker's drive force on the UNESP-BERT beam is 3-17 N (55 N/V, 0.05-0.30 V): a
        # guidance friction of a few per cent of it is tenths of a newton; pre-sliding
        # displacements F / k are microns to tens of microns
        return [Parameter("dry_friction_force", "N", 0.2, 0.0, 2.0,
                          "force at which the point slides (friction coefficient x normal "
                          "load of what rubs)", "Effect: dry_friction"),
                Parameter("dry_friction_stiffness", "N/mm", 10.0, 1.0, 1000.0,
                          "pre-sliding stiffness: the slip force over the displacement "
                          "before sliding", "Effect: dry_friction")]

    def probes(self, comparisons):
        """The slip force at 0.02, 0.2 and 2 N (its axis starts at the neutral 0), the
        pre-sliding stiffness nominal."""
        return decade_probes(self, "dry_friction_force")

    def apply(self, place, hooks, p):
        force = p["dry_friction_force"]
        if force <= 0:  # neutral: no friction
            return
        hooks.add_jenkins(f"dry_friction@{place.name}", place.body0 or hooks.ground,
                          place.r0, place.body1, place.r1, place.normal,
                          p["dry_friction_stiffness"] / MM, force)
