"""A planar assembly of rigid bodies and point masses joined by force elements and contacts.

A model describes itself for one parameter set as a :class:`Mechanism`: its bodies, its force
elements (:class:`Link`), the laws of its contact places and the places themselves. Effects
change it through the hooks of :class:`~sensfw.models.places.Hooks`, which
:class:`Mechanism` implements. The same mechanism is then evaluated with numpy (forces,
static equilibrium, linearisation: :mod:`sensfw.models.planar.statics`) and built in Exudyn
(:mod:`sensfw.models.planar.exudyn`).

Coordinates: a rigid body has ``(x, y, theta)``, a point mass ``(x, y)``, each measured from
its reference position ``ref``; kinematics of body points use small rotations.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ...errors import SensfwError
from ..places import ContactLaw, ForceLaw, Place, Point

G = 9.81  # m/s^2, gravity along -y


@dataclass(frozen=True)
class Body:
    """A body: planar rigid body (``ndof = 3``: x, y, theta) or point mass (``ndof = 2``);
    ``ref`` is the reference position (m) of its centre of mass, where its coordinates are
    measured and ``inertia`` taken. Points of the body are given relative to its original
    centre of mass; ``shift`` is how far the centre of mass has moved from there since (a
    mass added off it: :meth:`Mechanism.add_mass`), so a point ``r`` lies at ``r - shift``
    from the coordinates' point (:meth:`local`)."""

    name: str
    ndof: int
    mass: float
    inertia: float = 0.0
    ref: Point = (0.0, 0.0)
    shift: Point = (0.0, 0.0)

    def local(self, r: Point) -> Point:
        """The body point ``r`` (relative to the original centre of mass) relative to the
        present one."""
        return (r[0] - self.shift[0], r[1] - self.shift[1])


@dataclass(frozen=True)
class Link:
    """A force element between a point of ``body0`` and a point of ``body1``.

    ``law(ops, u, v, contact)`` gets the displacement ``u = (ux, uy)`` and velocity ``v`` of
    the point on ``body1`` relative to the point on ``body0`` (global axes, SI) and the
    contact evaluator (:class:`Contacts`), and returns the force ``(fx, fy)`` on ``body1``
    (``body0`` gets the opposite). In Exudyn it is one ``ObjectConnectorCartesianSpringDamper``
    with a symbolic user function.
    """

    name: str
    body0: str
    r0: Point
    body1: str
    r1: Point
    law: Callable
    #: ``u`` measured from the static state instead of the reference configuration (an
    #: element centred where the structure rests, e.g. a limit stop with play on both sides):
    #: such a link carries no static force by construction, so the static state is solved
    #: without it and ``offset`` (its ``u`` there) is set by :meth:`Mechanism.anchor`
    about_static: bool = False
    offset: Point | None = None
    #: a Jenkins element ``(stiffness N/m, slip force N, direction)`` (see
    #: :meth:`~sensfw.models.places.Hooks.add_jenkins`): ``law`` is then its stuck spring,
    #: what statics and linearisation see; a model that integrates it builds the hysteretic
    #: element itself
    jenkins: tuple[float, float, Point] | None = None


def anchored(links: list[Link], displacement: Callable | None) -> list[Link]:
    """``links`` with the offset of each ``about_static`` one set to its relative
    displacement at the static state (``displacement(body, r) -> (ux, uy)`` of a body point
    there), or cleared with ``None``."""
    out = []
    for ln in links:
        if ln.about_static:
            off = None
            if displacement is not None:
                (ux0, uy0), (ux1, uy1) = (displacement(ln.body0, ln.r0),
                                          displacement(ln.body1, ln.r1))
                off = (float(ux1 - ux0), float(uy1 - uy0))
            ln = replace(ln, offset=off)
        out.append(ln)
    return out


class Contacts:
    """How the force elements evaluate the contact places they contain.

    A link's law calls :meth:`one_sided`, :meth:`two_sided` and :meth:`tangential` with the
    place's name; this evaluator applies the place's current :class:`ContactLaw` (the
    nonlinear model). :mod:`~sensfw.models.planar.statics` substitutes evaluators that record
    the static state or apply the linearised laws.
    """

    def __init__(self, ops, laws: Mapping[str, ContactLaw]):
        self.ops, self.laws = ops, laws

    def one_sided(self, place: str, delta, delta_dot):
        """Normal force of a unilateral contact for the penetration ``delta``."""
        return self.laws[place].normal(self.ops, delta, delta_dot)

    def two_sided(self, place: str, e, e_dot, gap: float):
        """Signed force on the moving part of a contact with play ``gap`` on each side of
        the relative coordinate ``e`` (a shaft in a bore): ``-sign(e) F(|e| - gap)``."""
        ops = self.ops
        sgn = ops.sign(e)
        return -sgn * self.laws[place].normal(ops, ops.abs(e) - gap, sgn * e_dot)

    def tangential(self, place: str, fn, v):
        """Tangential force for the normal force magnitude ``fn`` and the slip velocity
        ``v``; ``None`` for a frictionless contact."""
        return self.laws[place].tangential(self.ops, fn, v)


def plus(x, y):
    """``x + y`` where ``y`` may be ``None`` (nothing to add: no node in the expression)."""
    return x if y is None else x + y


class CoordinateIndex:
    """Where each body's coordinates start in the state vector of a list of bodies:
    ``offset[name]`` is the index of its x (then y, and theta for a rigid body)."""

    def __init__(self, bodies: list[Body]):
        self.bodies = {b.name: b for b in bodies}
        self.offset, n = {}, 0
        for b in bodies:
            self.offset[b.name] = n
            n += b.ndof
        self.n = n

    def masses(self) -> np.ndarray:
        out = []
        for b in self.bodies.values():
            out += [b.mass, b.mass] + ([b.inertia] if b.ndof == 3 else [])
        return np.array(out)

    def y_index(self) -> list[int]:
        return [self.offset[b] + 1 for b in self.bodies]

    def rotation_index(self) -> list[int]:
        return [self.offset[b] + 2 for b, body in self.bodies.items() if body.ndof == 3]


class State:
    """Small-rotation kinematics of body points and assembly of generalised forces."""

    def __init__(self, index: CoordinateIndex, ground: str, q, qd):
        self.index, self.ground, self.q, self.qd = index, ground, q, qd
        self.f = np.zeros(index.n)

    def point(self, body: str, r: Point):
        """Displacement and velocity (ux, uy, vx, vy) of the body point at ``r``."""
        if body == self.ground:
            return 0.0, 0.0, 0.0, 0.0
        i, q, qd = self.index.offset[body], self.q, self.qd
        b = self.index.bodies[body]
        if b.ndof == 2:
            return q[i], q[i + 1], qd[i], qd[i + 1]
        r = b.local(r)
        th, thd = q[i + 2], qd[i + 2]
        return q[i] - th * r[1], q[i + 1] + th * r[0], qd[i] - thd * r[1], qd[i + 1] + thd * r[0]

    def apply(self, body: str, r: Point, fx: float, fy: float) -> None:
        if body == self.ground:
            return
        i = self.index.offset[body]
        self.f[i] += fx
        self.f[i + 1] += fy
        b = self.index.bodies[body]
        if b.ndof == 3:
            r = b.local(r)
            self.f[i + 2] += r[0] * fy - r[1] * fx


class LinkHooks:
    """The :class:`~sensfw.models.places.Hooks` that act on an assembly's ``laws`` (by place)
    and ``links`` (force elements), shared by :class:`Mechanism` and the bolted beam's
    assembly; ``_check(body, r)`` raises when ``r`` is not a point of ``body``."""

    laws: dict
    links: list[Link]

    def _check(self, body: str, r: Point) -> None:
        raise NotImplementedError

    def contact_law(self, place: str) -> ContactLaw:
        try:
            return self.laws[place]
        except KeyError:
            raise SensfwError(f"place {place!r} has no law; places with laws: "
                              f"{', '.join(self.laws)}") from None

    def set_contact_law(self, place: str, law: ContactLaw) -> None:
        self.contact_law(place)
        self.laws[place] = law

    def add_force(self, name: str, body0: str, r0: Point, body1: str, r1: Point,
                  law: ForceLaw, about_static: bool = False) -> None:
        self._check(body0, r0)
        self._check(body1, r1)
        if any(ln.name == name for ln in self.links):
            raise SensfwError(f"a force element named {name!r} exists already")
        self.links.append(Link(name, body0, tuple(r0), body1, tuple(r1),
                               lambda ops, u, v, contact: law(ops, u, v),
                               about_static=about_static))


@dataclass
class Mechanism(LinkHooks):
    """One parameter set's assembly: bodies, links, contact laws by place, places.

    Implements :class:`~sensfw.models.places.Hooks` for effects. ``follows`` records, for
    bodies added by effects, the body point whose static displacement is their start value.
    """

    bodies: list[Body]
    links: list[Link]
    laws: dict[str, ContactLaw]
    places: dict[str, Place]
    ground: str = "H"
    follows: dict[str, tuple[str, Point]] = field(default_factory=dict)

    # ---- hooks for effects (and LinkHooks') -------------------------------------------------
    def add_jenkins(self, name: str, body0: str, r0: Point, body1: str, r1: Point,
                    direction: Point, stiffness: float, slip_force: float) -> None:
        raise SensfwError(f"{type(self).__name__} has no Jenkins elements (a spring in series "
                          f"with a Coulomb slider, {name!r}): only models whose integrator "
                          "tracks the slider's state offer them (bolted_beam)")

    def add_body(self, name: str, mass: float, follows: tuple[str, Point]) -> None:
        if any(b.name == name for b in self.bodies) or name == self.ground:
            raise SensfwError(f"a body named {name!r} exists already")
        body, r = follows
        b = self._body(body)
        r0 = b.local(r) if body != self.ground else r
        ref = b.ref if body != self.ground else (0.0, 0.0)
        self.bodies.append(Body(name, 2, float(mass), 0.0, (ref[0] + r0[0], ref[1] + r0[1])))
        self.follows[name] = (body, tuple(r))

    def add_mass(self, body: str, mass: float, at: Point) -> None:
        """A point mass rigidly at the body point ``at``. On a rigid body the centre of mass
        moves to the pair's, ``c' = (M c + m at) / (M + m)``, and the inertia about it is
        ``I + M |c - c'|^2 + m |at - c'|^2`` (parallel axes): the body's coordinates follow
        the new centre, so its mass matrix stays diagonal and its weight acts there. (Adding
        ``m`` and ``m |at|^2`` about the old centre instead lost the coupling ``m at``
        between translation and rotation: 0.1 kg at the shaft model's crankshaft moved its
        modes by 2-7 %.)"""
        b = self._body(body)
        if b.ndof != 3:
            new = replace(b, mass=b.mass + mass)
        else:
            m0, c = b.mass, b.shift
            total = m0 + mass
            c1 = ((m0 * c[0] + mass * at[0]) / total, (m0 * c[1] + mass * at[1]) / total)
            inertia = (b.inertia + m0 * ((c[0] - c1[0]) ** 2 + (c[1] - c1[1]) ** 2)
                       + mass * ((at[0] - c1[0]) ** 2 + (at[1] - c1[1]) ** 2))
            ref = (b.ref[0] + c1[0] - c[0], b.ref[1] + c1[1] - c[1])
            new = replace(b, mass=total, inertia=inertia, ref=ref, shift=c1)
        self.bodies = [new if x.name == body else x for x in self.bodies]

    def _check(self, body: str, r: Point) -> None:
        self._body(body)

    def _body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        if name == self.ground:
            return Body(name, 0, 0.0)
        raise SensfwError(f"no body {name!r}; bodies: {', '.join(b.name for b in self.bodies)}")

    # ---- evaluation -------------------------------------------------------------------------
    def coordinates(self) -> CoordinateIndex:
        return CoordinateIndex(self.bodies)

    def generalized_forces(self, q, qd, contact, ops, index: CoordinateIndex | None = None
                           ) -> np.ndarray:
        """Link and gravity forces on the coordinates (numpy, SI, no excitation)."""
        index = index or self.coordinates()
        st = State(index, self.ground, np.asarray(q, float), np.asarray(qd, float))
        for ln in self.links:
            if ln.about_static and ln.offset is None:
                continue  # solving the static state: the link carries no static force
            ux0, uy0, vx0, vy0 = st.point(ln.body0, ln.r0)
            ux1, uy1, vx1, vy1 = st.point(ln.body1, ln.r1)
            ox, oy = ln.offset or (0.0, 0.0)
            fx, fy = ln.law(ops, (ux1 - ux0 - ox, uy1 - uy0 - oy), (vx1 - vx0, vy1 - vy0),
                            contact)
            st.apply(ln.body1, ln.r1, fx, fy)
            st.apply(ln.body0, ln.r0, -fx, -fy)
        iy = index.y_index()
        st.f[iy] -= index.masses()[iy] * G
        return st.f

    def anchor(self, q0: np.ndarray | None) -> None:
        """Measure the links declared ``about_static`` from the static state ``q0``;
        ``None`` releases them (while the static state is solved they carry no force)."""
        if q0 is None:
            self.links = anchored(self.links, None)
            return
        st = State(self.coordinates(), self.ground, np.asarray(q0, float), np.zeros(len(q0)))
        self.links = anchored(self.links, lambda body, r: st.point(body, r)[:2])

    def follow(self, index: CoordinateIndex, q: np.ndarray) -> None:
        """Set the coordinates of bodies added by effects to the displacement of the point
        they follow (in place)."""
        for name, (body, r) in self.follows.items():
            st = State(index, self.ground, q, np.zeros_like(q))
            ux, uy, _, _ = st.point(body, r)
            i = index.offset[name]
            q[i:i + 2] = ux, uy
