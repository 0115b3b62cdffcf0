"""Places of a model, and the hooks through which a physical effect acts there.

A model declares its *places* (:class:`Place`): the contacts, joints and bodies where physics
can be missing. Each has a *kind* and the geometry an effect needs (the two bodies and points
it connects, its normal and tangent). An effect (:mod:`sensfw.effects`) lists the kinds of
place it fits and implements its physics through the :class:`Hooks` the model offers while it
assembles itself: read or replace the contact law of a contact, add a force element, add a
body, add mass to a body. The model never looks at effect names, so a third-party effect can
do all that a built-in does.

Place kinds used by the shipped models:

``"contact"``
    a unilateral (or two-sided, with play) penalty contact with a :class:`ContactLaw`:
    normal force from penetration and its rate, tangential force from the normal force and
    the slip velocity;
``"body"``
    a body, with a reference point (``r1`` on ``body1``) and its axes;
``"joint"``
    a bilateral interface between two bodies that stays closed (a bolted lap joint, with
    ``body0``/``r0`` and ``body1``/``r1`` the same material point on either side of it), with
    a :class:`JointLaw`: the force along ``tangent`` from the interface *slip* (displacement,
    not only its rate: micro-slip, stiffness and dead zones need it) and the force along
    ``normal`` from the relative normal displacement. The joint's effects (micro-slip
    friction, cubic stiffness, clearance) wrap or replace it, or add force elements and
    bodies at its points (a Jenkins slider).

Every place offers the hooks ``contact_law``/``set_contact_law`` (contacts and joints),
``add_force``, ``add_body`` and ``add_mass``. A hook that needs the model's integrator to
carry a state of its own, ``add_jenkins`` (a slider position updated after every step), is
listed in the place's ``offers`` where the model has it; an effect that ``needs`` it fits
only such places.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from ..errors import OptionError, UnknownPluginError
from ..options import describe

Expr = Any  # an exudyn.symbolic.Real expression, or a float/array for numpy evaluation
Point = tuple[float, float]

#: ``law(ops, u, v) -> (fx, fy)``: force on ``body1`` of a force element for the displacement
#: ``u`` and velocity ``v`` of its point on ``body1`` relative to its point on ``body0``
#: (global axes, SI, relative to the reference configuration); ``body0`` gets the opposite.
ForceLaw = Callable[[Any, tuple, tuple], tuple]


@dataclass(frozen=True)
class Place:
    """A named place of a model where an effect can act.

    For a contact or a joint, ``body0``/``r0`` and ``body1``/``r1`` are the two bodies and the
    points (body coordinates, m) it connects, ``normal`` the unit direction along which the
    contact pushes ``body1`` away from ``body0`` when closed (global, reference
    configuration) and ``tangent`` the sliding direction (a joint may list all its
    interface point pairs in ``points``). For a body, ``body1``/``r1`` is the
    body and its reference point (e.g. where a sensor or the shaker sits), ``normal`` and
    ``tangent`` its transverse and axial axes; ``body0`` is the ground.
    """

    name: str
    kind: str
    description: str = ""
    body0: str = ""
    r0: Point = (0.0, 0.0)
    body1: str = ""
    r1: Point = (0.0, 0.0)
    normal: Point = (0.0, 1.0)
    tangent: Point = (1.0, 0.0)
    #: for a joint whose interface the model represents by several point pairs: every
    #: ``(r0, r1)`` pair (``r0``/``r1`` is one of them); the model shares the joint's law
    #: among them, and an effect that adds elements along the interface may do the same
    points: tuple[tuple[Point, Point], ...] = ()
    #: optional hooks the model offers here beyond the standard ones (``"add_jenkins"``)
    offers: frozenset[str] = frozenset()


@runtime_checkable
class ContactLaw(Protocol):
    """The force law of a contact place (SI units).

    ``normal(ops, delta, delta_dot)`` is the compressive normal force for the penetration
    ``delta`` (m, positive when closed) and its rate; ``tangential(ops, fn, v)`` is the force
    along the tangent on ``body1`` for the normal force magnitude ``fn`` and the slip velocity
    ``v`` of ``body1`` relative to ``body0``, or ``None`` for a frictionless contact.
    ``linearized(delta0)`` gives ``(force, stiffness, damping)`` at a static penetration (the
    linear model's tangent spring). ``ops`` supplies ``max, min, pow, where, abs, sign, sin,
    exp`` for symbolic (Exudyn, evaluated in C++) or numpy evaluation
    (:mod:`sensfw.models.contact`).
    """

    def normal(self, ops, delta: Expr, delta_dot: Expr) -> Expr: ...

    def tangential(self, ops, fn: Expr, v: Expr) -> Expr | None: ...

    def linearized(self, delta0: float) -> tuple[float, float, float]: ...


@runtime_checkable
class JointLaw(Protocol):
    """The force law of a joint place (SI units), for the whole joint.

    ``tangential(ops, s, s_dot)`` is the force on ``body1`` along the place's ``tangent``
    for the slip ``s`` (m) of ``body1`` relative to ``body0`` along it and its rate;
    ``normal(ops, g, g_dot)`` the force on ``body1`` along ``normal`` for the relative
    normal displacement ``g`` (positive: ``body1`` moves along ``normal``). A linear joint is
    ``-k s - c s_dot``. A model whose interface has several points shares the law among them
    (each point carries its share of the force for its own slip), so the law describes the
    joint as if all its points slipped together. ``ops`` as for :class:`ContactLaw`.
    """

    def tangential(self, ops, s: Expr, s_dot: Expr) -> Expr: ...

    def normal(self, ops, g: Expr, g_dot: Expr) -> Expr: ...


class Hooks(Protocol):
    """What a model offers an effect at its places while it assembles itself.

    ``ground`` names the fixed body. Coordinates are body coordinates (m); forces in N.
    """

    ground: str

    def contact_law(self, place: str) -> ContactLaw | JointLaw:
        """The current law of contact (or joint) ``place``."""
        ...

    def set_contact_law(self, place: str, law: ContactLaw | JointLaw) -> None:
        """Replace the law of ``place`` (wrap the current one to modify it)."""
        ...

    def add_force(self, name: str, body0: str, r0: Point, body1: str, r1: Point,
                  law: ForceLaw, about_static: bool = False) -> None:
        """Add a force element between a point of ``body0`` and a point of ``body1``;
        ``about_static``: its ``u`` is measured from the static state, where it must carry
        no force (the static state is solved without it)."""
        ...

    def add_jenkins(self, name: str, body0: str, r0: Point, body1: str, r1: Point,
                    direction: Point, stiffness: float, slip_force: float) -> None:
        """Add a Jenkins element along ``direction`` between a point of ``body0`` and a point
        of ``body1``: a spring ``stiffness`` (N/m) in series with a Coulomb slider that slips
        at ``slip_force`` (N), stuck at the static state. Its slider position is a state the
        integrator updates after every step (no regularisation). Optional: offered where a
        place lists it in ``offers``; models that cannot raise
        :class:`~sensfw.errors.SensfwError`."""
        ...

    def add_body(self, name: str, mass: float, follows: tuple[str, Point]) -> None:
        """Add a point mass that starts where the point ``follows = (body, r)`` is."""
        ...

    def add_mass(self, body: str, mass: float, at: Point) -> None:
        """Lump ``mass`` (kg) at the point ``at`` into ``body`` (mass and rotary inertia)."""
        ...


class EffectLike(Protocol):
    """What the model needs to know of an effect (:class:`sensfw.effects.Effect`)."""

    name: str
    fits: tuple[str, ...]
    #: optional hooks the effect uses (:attr:`Place.offers`)
    needs: tuple[str, ...]
    attach: str | None

    def parameters(self) -> list: ...

    def apply(self, place: Place, hooks: Hooks, p: Mapping[str, float]) -> None: ...


def fitting_places(places: Mapping[str, Place], effect: EffectLike | type) -> list[str]:
    """Names of the places of kinds ``effect`` fits that offer the optional hooks it
    ``needs``, in the model's order."""
    needs = set(getattr(effect, "needs", ()))
    return [n for n, pl in places.items() if pl.kind in effect.fits and needs <= pl.offers]


def make_effect(spec) -> EffectLike:
    """An effect from its spec: a registered name, ``{"name": ..., "attach": ...}``, or an
    effect object (returned as it is). Effects are found through the registry
    (:data:`sensfw.plugins.effects`), so models never import them; their options are checked
    by the contract of every plugin kind (:func:`sensfw.options.make`)."""
    from ..options import make
    from ..plugins import effects

    if not isinstance(spec, (str, Mapping)):
        return spec
    spec = {"name": spec} if isinstance(spec, str) else dict(spec)
    name = spec.pop("name", None)
    if not isinstance(name, str):
        raise OptionError(f"effect {spec!r} has no name (a registered effect)", option="name")
    return make(effects, name, spec)


def _resolve(places: Mapping[str, Place], effects: Sequence[EffectLike], model: str,
             preferred: Mapping[str, Sequence[str]], index: Sequence[int] | None = None
             ) -> tuple[list, list[tuple[str, str]]]:
    """``(attached, problems)``: each effect that fits with its place, and every problem as
    ``(path, message)`` with the path of the effect (``effects[1].attach``; ``index``: the
    position of each effect in the model's list, default its position in ``effects``)."""
    out, owners, problems = [], {}, []
    for k, eff in enumerate(effects):
        i = k if index is None else index[k]
        fits = fitting_places(places, eff)
        needs = tuple(getattr(eff, "needs", ()))
        if not fits:
            kinds = sorted({pl.kind for pl in places.values()})
            if any(pl.kind in eff.fits for pl in places.values()):
                problems.append((f"effects[{i}].name", f"effect {eff.name!r} needs the hook(s) "
                                 f"{', '.join(needs)}, which no place of model {model!r} "
                                 "offers"))
            else:
                problems.append((f"effects[{i}].name", f"effect {eff.name!r} fits places of "
                                 f"kind {', '.join(eff.fits)}; model {model!r} has places of "
                                 f"kind {', '.join(kinds) or '(none)'}"))
            continue
        name = eff.attach
        if name is None:
            first = [n for n in preferred.get(eff.name, ()) if n in fits]
            if first:
                name = first[0]
            elif len(fits) == 1:
                name = fits[0]
            else:
                problems.append((f"effects[{i}].attach", f"effect {eff.name!r}: say where "
                                 f"(attach = ...); it fits {', '.join(fits)} of model "
                                 f"{model!r}"))
                continue
        elif name not in fits:
            if name not in places:
                what = f"model {model!r} has no place {name!r}"
            elif places[name].kind not in eff.fits:
                what = f"{name!r} is a {places[name].kind}"
            else:
                what = f"{name!r} does not offer {', '.join(needs)}"
            problems.append((f"effects[{i}].attach", f"effect {eff.name!r} cannot attach to "
                             f"{name!r} ({what}); it fits {', '.join(fits)}"))
            continue
        eff.attach = name
        clash = [p.name for p in eff.parameters() if p.name in owners]
        if clash:
            problems.append((f"effects[{i}]", f"effects {owners[clash[0]]!r} and "
                             f"{eff.name!r}@{name} both add parameter {clash[0]!r}"))
            continue
        owners.update({p.name: f"{eff.name}@{name}" for p in eff.parameters()})
        out.append((eff, places[name]))
    return out, problems


def resolve_places(places: Mapping[str, Place], effects: Sequence[EffectLike],
                   model: str, preferred: Mapping[str, Sequence[str]] | None = None
                   ) -> list[tuple[EffectLike, Place]]:
    """Each effect with the place it attaches to (its ``attach`` is set to that place).

    ``attach`` must name a place of a kind the effect fits. Without ``attach``, the places
    the model prefers for that effect (``preferred[effect.name]``, see
    :attr:`sensfw.models.Model.preferred_places`) come first, then the only fitting place;
    otherwise the error lists the choices. Two effects that add the same parameter are
    refused. :class:`~sensfw.errors.OptionError` names every problem at its path
    (``effects[1].attach``).
    """
    attached, problems = _resolve(places, effects, model, preferred or {})
    if problems:
        raise OptionError(describe(problems), option=problems[0][0], problems=problems)
    return attached


def attach_effects(places: Mapping[str, Place], specs: Sequence, model: str,
                   preferred: Mapping[str, Sequence[str]] | None = None
                   ) -> tuple[tuple[EffectLike, ...], tuple[tuple[EffectLike, Place], ...]]:
    """``(effects, attached)``: the effects of ``specs`` (:func:`make_effect`) and each with
    its place (:func:`resolve_places`); every problem of every spec is reported at once, at
    its path (``effects[1].name``, ``effects[0].attach``), as one
    :class:`~sensfw.errors.OptionError`."""
    made, problems = [], []
    for i, spec in enumerate(specs):
        try:
            made.append((i, make_effect(spec)))
        except UnknownPluginError as err:
            problems.append((f"effects[{i}].name", str(err)))
        except OptionError as err:
            problems += [(f"effects[{i}].{p}" if p else f"effects[{i}]", m)
                         for p, m in err.problems]
    attached, found = _resolve(places, [e for _, e in made], model, preferred or {},
                               index=[i for i, _ in made])
    problems += found
    if problems:
        problems.sort(key=lambda pm: int(pm[0].split("[", 1)[1].split("]", 1)[0]))
        raise OptionError(describe(problems), option=problems[0][0], problems=problems)
    return tuple(e for _, e in made), tuple(attached)
