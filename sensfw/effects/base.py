"""The effect contract: physics added at a named place of any model (plugin group
``sensfw.effects``).

An effect lists the kinds of place it fits (``fits``), the parameters it adds (with bounds,
in the paper's units) and what it leaves in a measurement (``signatures`` in words for the
reports, ``signature_classes`` for :mod:`sensfw.measure` to decide which candidates a
measurement allows). :meth:`Effect.apply` implements the physics through the hooks the model
offers at that place (:class:`sensfw.models.places.Hooks`): replace or wrap the place's
contact law, add a force element, add a body, add mass. Every place of a fitting kind is a
valid attach point, so diagnosis can try each.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import ClassVar

from pydantic import Field

from ..models.places import Hooks, Place, make_effect  # noqa: F401  (re-exported)
from ..options import PluginOptions, Str, option_defaults, options_model
from ..params import Parameter

#: Amplitude-dependence classes of a nonlinear structure's response (Kerschen, Worden,
#: Vakakis & Golinval 2006, Sect. 3; Worden & Tomlinson 2001, Ch. 2-3), as the measurement
#: loop classifies them from several excitation levels.
SIGNATURE_CLASSES = {
    "amplitude_independent": "resonances and damping do not change with level (added mass, "
                             "an extra mode, linear damping)",
    "softening": "resonances move down and damping grows with level (micro-slip friction, "
                 "contacts that open)",
    "hardening": "resonances move up with level (contact hardening, clearance above its gap)",
    "even_harmonics": "even harmonics or a DC shift (asymmetric contact, preload)",
    "new_peak": "a resonance the model lacks (an extra mode)",
}


class Effect(ABC):
    """Base class of effects. ``attach`` names the place (``None``: the place the model
    prefers for this effect, :attr:`sensfw.models.Model.preferred_places`, or its only
    fitting place)."""

    name: ClassVar[str] = "effect"
    #: kinds of place (:class:`~sensfw.models.places.Place`) the effect fits
    fits: ClassVar[tuple[str, ...]] = ()
    #: optional hooks the effect uses, which only some places offer (``"add_jenkins"``:
    #: :attr:`~sensfw.models.places.Place.offers`)
    needs: ClassVar[tuple[str, ...]] = ()
    signatures: ClassVar[tuple[str, ...]] = ()
    signature_classes: ClassVar[frozenset[str]] = frozenset()
    #: parameter values at which the effect vanishes exactly (the model without it): a
    #: calibration that starts there can only end better than the model without the effect
    neutral: ClassVar[dict[str, float]] = {}
    #: raised when the effect's physics changes: it enters the runs' hash
    #: (:meth:`sensfw.models.Model.effect_options`), so a run store never hands back a run
    #: of the former physics
    revision: ClassVar[int] = 0

    class Options(PluginOptions):
        """An effect's one option, where it attaches (:mod:`sensfw.options`)."""

        attach: Str | None = Field(
            None, description="a place of the model (`sensfw places MODEL`) or none (the "
                              "place the model prefers for the effect)")

    def __init__(self, attach: str | None = None):
        self.attach = attach

    def parameters(self) -> list[Parameter]:
        """The parameters the effect adds (paper units, with bounds)."""
        return []

    @abstractmethod
    def apply(self, place: Place, hooks: Hooks, p: Mapping[str, float]) -> None:
        """Add the effect's physics at ``place`` through ``hooks`` for parameter values
        ``p`` (the model's and the effect's, paper units)."""

    def probes(self, comparisons) -> list[dict[str, float]]:
        """Points at which diagnosis first tries the effect. By default its first parameter
        (the strength: a mass, a force, a coefficient) at a quarter, half and all of the way
        from its neutral value to its maximum, the others at their nominal values: an effect
        explains a discrepancy only at about the right strength, and a weak probe can look
        worse than no effect at all. Effects whose response is multimodal in a parameter (a
        mode's frequency) override this, guided by the evidence of the model/measurement
        ``comparisons``."""
        params = self.parameters()
        nominal = {p.name: p.nominal for p in params}
        lead = params[0]
        start = self.neutral.get(lead.name, lead.min)
        return [{**nominal, lead.name: start + f * (lead.max - start)} for f in (0.25, 0.5, 1.0)]

    def spec(self) -> dict:
        """Name, place and every declared option the instance holds at other than its
        default (they enter the runs' hash: an effect at another option is another run)."""
        out = {"name": self.name}
        if self.attach is not None:
            out["attach"] = self.attach
        defaults = option_defaults(type(self))
        for k in options_model(type(self)).model_fields:
            if k != "attach" and hasattr(self, k):
                v = getattr(self, k)
                if k not in defaults or v != defaults[k]:
                    out[k] = v
        return out

    def __repr__(self) -> str:
        return f"{type(self).__name__}(attach={self.attach!r})"


def decade_probes(effect: Effect, name: str, fractions=(0.01, 0.1, 1.0)
                  ) -> list[dict[str, float]]:
    """Probes for an effect whose strength ``name`` spans decades (its axis starts at the
    neutral 0, so the default quarter/half/full steps would all be strong): the strength at
    ``fractions`` of its maximum (1 %, 10 % and all of it), the other parameters at their
    nominal values."""
    params = effect.parameters()
    nominal = {p.name: p.nominal for p in params}
    top = next(p.max for p in params if p.name == name)
    return [{**nominal, name: top * f} for f in fractions]


def add_spring_along_normal(hooks, place, name: str, force) -> None:
    """A force element at a body ``place``, along its normal, measured from the static state
    (it carries no static load): ``force(ops, e, e_dot)`` of the displacement ``e`` (m) and
    velocity ``e_dot`` of the body point along the normal from where it rests (N)."""
    nx, ny = place.normal

    def law(ops, u, v):
        f = force(ops, u[0] * nx + u[1] * ny, v[0] * nx + v[1] * ny)
        return f * nx, f * ny

    hooks.add_force(name, place.body0 or hooks.ground, place.r0, place.body1, place.r1, law,
                    about_static=True)
