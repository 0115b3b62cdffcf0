"""A reduced beam assembly (:class:`~.assembly.Structure`) built and solved in Exudyn.

The reduced beams are one ``ObjectGenericODE2`` whose nodes are a ``NodePoint2D`` per
boundary point (its coordinates are the point's physical displacement) and one
``NodeGenericODE2`` with the fixed-interface modal coordinates; its mass, stiffness and
damping matrices are the Craig-Bampton ones. Bodies added by effects are
``ObjectMassPoint2D``. Every force element is an ``ObjectConnectorCartesianSpringDamper``
between ``MarkerNodePosition`` markers (ground points: ``MarkerBodyPosition`` on the
ground) with a *symbolic* user function, as in the planar models
(:mod:`sensfw.models.planar.exudyn`); the excitation is a ``LoadForceVector`` with a symbolic
load function; sensors are ``SensorNode`` (acceleration or velocity) of the points.

Time integration: Exudyn's implicit generalised-alpha (Chung & Hulbert 1993) at a fixed
step, or an explicit Runge-Kutta method (see :class:`~.model.BoltedBeam` for why implicit).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from ...errors import SensfwError
from ..planar.exudyn import Built, link_function, load_function, user_function
from .assembly import Structure

IMPLICIT = ("GeneralizedAlpha", "TrapezoidalIndex2")
#: relative residual at which Newton stops (see :func:`solve`)
NEWTON_TOLERANCE = 1e-6
#: absolute residual (N, RMS per coordinate) at which Newton stops, per N of the largest
#: excitation force (see :func:`solve`)
NEWTON_ABSOLUTE = 1e-6
#: modified Newton for bodies that effects add (``newton="patient"``): the Jacobian
#: (differentiated numerically, the cost of a step) is renewed only when an iteration
#: contracts the residual by less than 0.9 (Exudyn's default 0.5). Measured when micro_slip's
#: Jenkins elements were light slider bodies with regularised friction (before
#: :class:`JenkinsSliders`; 2 s sweep through the second mode at 3 / 15 N): 1.86x / 1.92x
#: faster than full Newton with signals as far apart as full Newton from itself at half the
#: step; Exudyn's default contractivity ended such runs at stick-slip transitions.
PATIENT = {"modifiedNewtonContractivity": 0.9, "maxModifiedNewtonIterations": 12,
           "maxModifiedNewtonRestartIterations": 30}

#: (name, body, x, quantity "Acceleration" | "Velocity", component) of a sensor
SensorSpec = tuple[str, str, float, str, int]


def build(structure: Structure, z0: np.ndarray, D: np.ndarray, contact, ops,
          loads: Sequence[tuple[str, float, Callable]] = (),
          sensors: Sequence[SensorSpec] = (), user_functions: str = "symbolic") -> Built:
    """Assemble the reduced beams, force elements, loads ``(body, x, force(ops, t))`` and
    sensors at the state ``z0`` (not yet solved). ``D`` is the damping matrix of the
    structure's coordinates."""
    import exudyn as exu
    from exudyn import itemInterface as ei

    a = structure.assembly
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ei.ObjectGround())
    nodes: dict[str, object] = {}
    point_nodes = []
    for k, (body, x) in enumerate(structure.points):
        i = 2 * k
        nd = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=[x, 0.0],
                                        initialCoordinates=list(z0[i:i + 2])))
        point_nodes.append(nd)
        nodes[f"{body}@{x!r}"] = nd
    node_list = list(point_nodes)
    nm = structure.n_struct - structure.red.nb
    if nm:
        nb = structure.red.nb
        node_list.append(mbs.AddNode(ei.NodeGenericODE2(
            numberOfODE2Coordinates=nm, referenceCoordinates=[0.0] * nm,
            initialCoordinates=list(z0[nb:nb + nm]), initialCoordinates_t=[0.0] * nm)))
    ns = structure.n_struct
    mbs.AddObject(ei.ObjectGenericODE2(
        nodeNumbers=node_list, massMatrix=structure.red.M, stiffnessMatrix=structure.red.K,
        dampingMatrix=D[:ns, :ns]))
    for b in structure.bodies:
        j = structure.body_index[b]
        ref = structure.reference(b, (0.0, 0.0))
        nd = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=list(ref),
                                        initialCoordinates=list(z0[j:j + 2])))
        mbs.AddObject(ei.ObjectMassPoint2D(nodeNumber=nd, mass=a.added[b][0]))
        nodes[b] = nd

    def marker(body, r):
        if body == a.ground:
            return mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground,
                                                       localPosition=[r[0], r[1], 0.0]))
        key = body if body in structure.body_index else f"{body}@{round(float(r[0]), 9)!r}"
        return mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=nodes[key]))

    keep: list = []
    jenkins = [ln for ln in a.links if ln.jenkins is not None]
    sliders = JenkinsSliders(jenkins, user_functions) if jenkins else None
    for ln in a.links:
        if ln.jenkins is not None:
            ln = replace(ln, law=sliders.law(jenkins.index(ln)))
        m0, m1 = marker(ln.body0, ln.r0), marker(ln.body1, ln.r1)
        # reference offset between the two points, removed inside the law
        p0 = (0.0, 0.0) if ln.body0 == a.ground else structure.reference(ln.body0, ln.r0)
        p1 = structure.reference(ln.body1, ln.r1)
        if ln.body0 == a.ground:
            p0 = (float(ln.r0[0]), float(ln.r0[1]))
        if ln.about_static and ln.offset is None:
            raise SensfwError(f"force element {ln.name!r} is measured from the static state, "
                              "which was not solved for this structure")
        o = ln.offset or (0.0, 0.0)  # a link centred on the static state: its u there
        off = [p1[0] - p0[0] + o[0], p1[1] - p0[1] + o[1]]
        co = mbs.AddObject(ei.ObjectConnectorCartesianSpringDamper(
            markerNumbers=[m0, m1], stiffness=[0, 0, 0], damping=[0, 0, 0],
            offset=[0, 0, 0], name=ln.name))
        keep.append(user_function(mbs, co, link_function(ln, off, ops, contact,
                                                         user_functions),
                                  "springForceUserFunction", user_functions))
    for body, x, force in loads:
        load = mbs.AddLoad(ei.LoadForceVector(markerNumber=marker(body, (x, 0.0)),
                                              loadVector=[0, 0, 0]))
        keep.append(user_function(mbs, load, load_function(force, ops, user_functions),
                                  "loadVectorUserFunction", user_functions))
    handles = {}
    for name, body, x, quantity, comp in sensors:
        s = mbs.AddSensor(ei.SensorNode(
            nodeNumber=nodes[f"{body}@{round(float(x), 9)!r}"], storeInternal=True,
            outputVariableType=getattr(exu.OutputVariableType, quantity)))
        handles[name] = (s, comp)
    mbs.Assemble()
    built = Built(SC=SC, mbs=mbs, sensors=handles, q0=z0, keep=keep)
    if sliders is not None:
        def coordinate_index(body, r, axis):
            if body == a.ground:
                return None
            key = body if body in structure.body_index else f"{body}@{round(float(r[0]), 9)!r}"
            return mbs.GetNodeODE2Index(nodes[key]) + axis

        sliders.attach(mbs, coordinate_index)
        built.prestep = sliders.prestep()
        mbs.SetPreStepUserFunction(built.prestep)
        keep += [sliders, built.prestep]
    return built


class JenkinsSliders:
    """The slider positions of an assembly's Jenkins elements
    (:meth:`~.assembly.BeamAssembly.add_jenkins`), integrated by return mapping (Simo &
    Hughes 1998, Sect. 1.4, the elastic predictor / plastic corrector of 1D plasticity).

    Each element is a force element whose law is ``F(s) = clip(k (s - x), -F_s, F_s)`` of
    its slip ``s`` along its direction (from the static state), with the slider position
    ``x`` frozen during a step: inside the implicit step this is exactly the return-mapped
    force of the step's end state (backward Euler of the slider, no regularisation, no slider
    body), and after the step has converged (Exudyn's pre-step function of the next one)
    ``x <- s - F(s) / k``. ``x`` is a named symbolic variable for symbolic user functions
    (set between steps, read in C++) or an array entry for Python ones. All elements start
    stuck at the static state (``x = 0``).
    """

    def __init__(self, links, kind: str):
        import exudyn as exu

        self.links = list(links)
        n = len(self.links)
        self.k = np.array([ln.jenkins[0] for ln in self.links])
        self.force = np.array([ln.jenkins[1] for ln in self.links])
        self.x = np.zeros(n)
        serial = next(_serial)
        self.vars = ([exu.symbolic.Real(f"sensfw_jenkins_{serial}_{i}", 0.0) for i in range(n)]
                     if kind == "symbolic" else None)
        self.index0 = self.index1 = self.rest = None

    def law(self, i: int):
        """The force law of element ``i`` (a :class:`~sensfw.models.planar.Link` law)."""
        k, force = float(self.k[i]), float(self.force[i])
        d = self.links[i].jenkins[2]
        var = self.vars[i] if self.vars is not None else None
        x = self.x

        def jenkins(ops, u, v, contact):
            s = u[0] * d[0] + u[1] * d[1]
            slip = var if var is not None else float(x[i])
            f = ops.max(ops.min(k * (s - slip), force), -force)
            return -f * d[0], -f * d[1]

        return jenkins

    def attach(self, mbs, coordinate_index) -> None:
        """Read the elements' slips from the system's coordinates (after ``Assemble``):
        ``coordinate_index(body, r, axis)`` is the global ODE2 index of a point's coordinate
        (``None`` on the ground)."""
        def idx(body, r, ln):
            axis = 0 if ln.jenkins[2] == (1.0, 0.0) else 1
            i = coordinate_index(body, r, axis)
            return -1 if i is None else i

        self.index0 = np.array([idx(ln.body0, ln.r0, ln) for ln in self.links])
        self.index1 = np.array([idx(ln.body1, ln.r1, ln) for ln in self.links])
        self.rest = np.array([(ln.offset or (0.0, 0.0))[0 if ln.jenkins[2] == (1.0, 0.0)
                                                         else 1] for ln in self.links])

    def update(self, q: np.ndarray) -> None:
        """The return mapping at the converged state ``q`` (global ODE2 coordinates)."""
        qe = np.append(np.asarray(q, float), 0.0)  # index -1: the ground
        s = qe[self.index1] - qe[self.index0] - self.rest
        f = np.clip(self.k * (s - self.x), -self.force, self.force)
        self.x[:] = s - f / self.k
        if self.vars is not None:
            for var, value in zip(self.vars, self.x, strict=True):
                var.SetValue(float(value))

    def prestep(self):
        """Exudyn's pre-step function: the return mapping of the last converged step."""
        def prestep(mbs, t):
            self.update(mbs.systemData.GetODE2Coordinates())
            return True

        return prestep


_serial = itertools.count()


def solve(built: Built, fs: float, n_out: int, substeps: int, method: str,
          spectral_radius: float = 0.8, force_scale: float = 1.0,
          newton: str = "modified") -> dict[str, np.ndarray]:
    """Integrate at the fixed step ``1 / (fs substeps)`` and return every sensor's ``n_out``
    samples at ``fs``; raises ``exudyn.SolverError`` or returns short/non-finite channels
    when the solver fails. ``force_scale`` is the largest excitation force (N), which
    scales Newton's absolute tolerance; ``newton`` is ``"modified"`` (Exudyn's defaults:
    the Jacobian kept while Newton contracts by 0.5 per iteration), ``"patient"`` (kept
    while it contracts by 0.9, up to 12 iterations; see ``PATIENT``) or ``"full"`` (a new
    Jacobian at every iteration; see :meth:`~.model.BoltedBeam.simulate`). Always resets
    the system."""
    import exudyn as exu

    mbs, SC = built.mbs, built.SC
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.endTime = n_out / fs
    ti.numberOfSteps = n_out * substeps
    ti.automaticStepSize = False
    ti.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 1.0 / fs
    if method in IMPLICIT:
        ss.linearSolver.solverType = exu.LinearSolverType.EigenDense
        ti.generalizedAlpha.spectralRadius = spectral_radius
        ti.generalizedAlpha.computeInitialAccelerations = True
        if newton not in ("modified", "patient", "full"):
            raise ValueError(f"newton {newton!r}: modified, patient or full")
        ti.newton.useModifiedNewton = newton != "full"
        if newton == "patient":
            for key, value in PATIENT.items():
                setattr(ti.newton, key, value)
        # one Newton step solves a linear step to ~1e-7 (the connectors' numerical
        # Jacobian); Exudyn's default 1e-8 forced a second step and a Jacobian update every
        # other step (6x slower for the same signals)
        ti.newton.relativeTolerance = NEWTON_TOLERANCE
        # in a free decay the step's residual falls to a floor that grows with the level of
        # the response (1 N at the nominal values: ~1e-10 N; 1.5 N with the stiffest joint:
        # above 1e-8 N); with a tolerance below it Newton never converged (70 iterations
        # per step: 700 s for an 8 s tail). 1e-6 N per N of excitation force is far below
        # the forces that matter and above that floor.
        ti.newton.absoluteTolerance = NEWTON_ABSOLUTE * max(force_scale, 1e-4)
        # the connectors' Jacobian is differentiated numerically with a step of
        # 1e-7 x max(|q|, minimumCoordinateSize); Exudyn's default 0.01 m gives 1e-9 m,
        # i.e. a velocity step of ~1.6e-5 m/s at this step size, wider than the stick band of
        # a regularised friction slider (down to ~1e-6 m/s): Newton then failed at stick-slip
        # transitions. 1e-4 m keeps the step 100 times smaller.
        ti.newton.numericalDifferentiation.minimumCoordinateSize = 1e-4
        ti.discontinuous.useRecommendedStepSize = False
    else:
        ti.explicit.computeEndOfStepAccelerations = False
        ti.discontinuous.useRecommendedStepSize = False
    try:
        ok = mbs.SolveDynamic(ss, solverType=getattr(exu.DynamicSolverType, method))
        channels = {}
        if ok is not False:
            for name, (s, comp) in built.sensors.items():
                data = np.asarray(mbs.GetSensorStoredData(s))
                channels[name] = np.ascontiguousarray(data[:n_out, 1 + comp])
        return channels
    finally:
        mbs.Reset()
        SC.Reset()
