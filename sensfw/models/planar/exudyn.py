"""A :class:`~sensfw.models.planar.mechanism.Mechanism` built and solved in Exudyn.

Every body becomes ``ObjectRigidBody2D`` or ``ObjectMassPoint2D``; every link one
``ObjectConnectorCartesianSpringDamper`` between two body-position markers whose force is a
*symbolic* user function (Exudyn evaluates it in C++ inside its explicit integrator, with no
Python in the time loop); loads are ``LoadForceVector`` with a symbolic load function of
time. ``user_functions="python"`` builds the same system with Python callbacks (for the
benchmark that measures what the symbolic ones save).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .mechanism import G, Mechanism

#: (name, body, local point, component 0 = x / 1 = y) of an acceleration sensor
SensorSpec = tuple[str, str, tuple[float, float], int]
#: (body, local point, ``force(ops, t) -> (fx, fy)``) of a time-dependent load
LoadSpec = tuple[str, tuple[float, float], Callable]


@dataclass
class Built:
    """An assembled Exudyn system and the handles a caller needs."""

    SC: object
    mbs: object
    sensors: dict[str, tuple[object, int]]
    q0: np.ndarray
    keep: list = field(default_factory=list)  # symbolic expression trees must outlive mbs
    #: the pre-step function the system already has (a later one must call it first)
    prestep: Callable | None = None


def build(mech: Mechanism, q0: np.ndarray, contact, ops, loads: Sequence[LoadSpec] = (),
          sensors: Sequence[SensorSpec] = (), user_functions: str = "symbolic") -> Built:
    """Assemble ``mech`` in Exudyn at the state ``q0`` (not yet solved); ``contact`` is the
    contact evaluator the links call (nonlinear or linearised laws)."""
    import exudyn as exu
    from exudyn import itemInterface as ei

    index = mech.coordinates()
    mech.anchor(q0)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    bodies = {mech.ground: mbs.AddObject(ei.ObjectGround())}
    reference = {mech.ground: (0.0, 0.0)}
    for b in index.bodies.values():
        i = index.offset[b.name]
        q_init = list(q0[i:i + b.ndof])
        if b.ndof == 3:
            node = mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=[*b.ref, 0.0],
                                                  initialCoordinates=q_init))
            bodies[b.name] = mbs.AddObject(ei.ObjectRigidBody2D(
                nodeNumber=node, mass=b.mass, inertia=b.inertia))
        else:
            node = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=list(b.ref),
                                              initialCoordinates=q_init))
            bodies[b.name] = mbs.AddObject(ei.ObjectMassPoint2D(nodeNumber=node,
                                                                mass=b.mass))
        reference[b.name] = b.ref

    def local(body, r):  # a body point relative to its present centre of mass
        return index.bodies[body].local(r) if body in index.bodies else r

    def marker(body, r):
        x, y = local(body, r)
        return mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=bodies[body],
                                                   localPosition=[x, y, 0.0]))

    keep: list = []
    for ln in mech.links:
        m0, m1 = marker(ln.body0, ln.r0), marker(ln.body1, ln.r1)
        # reference offset between the two points, removed inside the law
        # (and, for a link centred on the static state, its displacement there)
        r0, r1 = local(ln.body0, ln.r0), local(ln.body1, ln.r1)
        off = [reference[ln.body1][i] + r1[i] - reference[ln.body0][i] - r0[i]
               + (ln.offset[i] if ln.offset else 0.0) for i in (0, 1)]
        co = mbs.AddObject(ei.ObjectConnectorCartesianSpringDamper(
            markerNumbers=[m0, m1], stiffness=[0, 0, 0], damping=[0, 0, 0],
            offset=[0, 0, 0], name=ln.name))
        uf = link_function(ln, off, ops, contact, user_functions)
        keep.append(user_function(mbs, co, uf, "springForceUserFunction", user_functions))
    for b in index.bodies:
        mb = mbs.AddMarker(ei.MarkerBodyMass(bodyNumber=bodies[b]))
        mbs.AddLoad(ei.LoadMassProportional(markerNumber=mb, loadVector=[0, -G, 0]))
    for body, r, force in loads:
        load = mbs.AddLoad(ei.LoadForceVector(markerNumber=marker(body, r),
                                              loadVector=[0, 0, 0]))

        keep.append(user_function(mbs, load, load_function(force, ops, user_functions),
                                   "loadVectorUserFunction", user_functions))
    handles = {}
    for name, body, pos, comp in sensors:
        x, y = local(body, pos)
        s = mbs.AddSensor(ei.SensorBody(
            bodyNumber=bodies[body], localPosition=[x, y, 0], storeInternal=True,
            outputVariableType=exu.OutputVariableType.Acceleration))
        handles[name] = (s, comp)
    mbs.Assemble()
    return Built(SC=SC, mbs=mbs, sensors=handles, q0=q0, keep=keep)


def solve(built: Built, fs: float, n_out: int, choice) -> tuple[dict[str, np.ndarray],
                                                                  object]:
    """Integrate as ``choice`` (a :class:`~sensfw.models.stepsize.StepChoice`: fixed steps on
    the output grid, or error-controlled adaptive steps resampled onto it; see
    :func:`sensfw.models.integration.solve`) and return every sensor's ``n_out`` samples at
    ``fs`` with the integrator's statistics; raises ``exudyn.SolverError`` when the solver
    fails. Always resets the system."""
    from .. import integration

    try:
        return integration.solve(built.mbs, built.sensors, choice, n_out, fs)
    finally:
        built.mbs.Reset()
        built.SC.Reset()


def link_function(ln, off: list[float], ops, contact, kind: str):
    """The CartesianSpringDamper user function of one link (reference offset removed)."""

    def force(mbs, t, itemNumber, u, v, k, d, offset):
        # a zero offset is not subtracted: every node of a symbolic tree costs at every call
        fx, fy = ln.law(ops, tuple(u[i] - off[i] if off[i] else u[i] for i in (0, 1)),
                        (v[0], v[1]), contact)
        # Exudyn applies the returned force to marker 0 and its negative to marker 1
        return vector([-fx, -fy, 0.0], kind)

    return force


def load_function(force, ops, kind: str):
    """The LoadForceVector user function of a time-dependent load."""

    def load(mbs, t, loadVector):
        fx, fy = force(ops, t)
        return vector([fx, fy, 0.0], kind)

    return load


def vector(values: list, kind: str) -> list:
    """A user function's return vector: floats for Python, ``symbolic.Real`` otherwise."""
    if kind == "python":
        return [float(v) for v in values]
    import exudyn as exu

    real = exu.symbolic.Real
    return [v if isinstance(v, real) else real(float(v)) for v in values]


def user_function(mbs, item, function, name: str, kind: str):
    """Attach ``function`` as user function ``name`` of ``item``: recorded into an Exudyn
    symbolic (C++ evaluated) function, or as a plain Python callback. Returns the object that
    must be kept alive as long as ``mbs`` lives."""
    if kind == "python":
        setter = mbs.SetObjectParameter if "Object" in str(type(item)) else mbs.SetLoadParameter
        setter(item, name, function)
        return function
    from exudyn.utilities import CreateSymbolicUserFunction

    symbolic = CreateSymbolicUserFunction(mbs, function, name, item)
    if name == "loadVectorUserFunction":
        mbs.SetLoadParameter(item, name, symbolic)
    else:
        mbs.SetObjectParameter(item, name, symbolic)
    return symbolic
