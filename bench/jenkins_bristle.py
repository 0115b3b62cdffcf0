"""Exudyn's own Jenkins element against the bolted beam's return mapping, on a toy.

The beam integrates each Jenkins element (a spring ``k`` in series with a Coulomb slider
``F``) as a symbolic force ``clip(k (s - x), -F, F)`` with the slider position ``x`` frozen
during a step and moved by a Python pre-step function after it
(``sensfw.models.bolted_beam.simulation.JenkinsSliders``). Exudyn has the same element
built in: ``ObjectConnectorCoordinateSpringDamperExt`` with its bristle friction
(``stickingStiffness`` = k, ``dynamicFrictionForce`` = F, ``frictionProportionalZone`` = 0),
which switches stick and slip in a PostNewton iteration, in C++.

The toy: two mass points (0.5 and 0.3 kg) along x, the first on a spring to the ground,
``--elements`` Jenkins elements between them (k 2e5-6e5 N/m, F 1-12 N), a sine of 95 Hz
at each ``--levels`` force (ramped over 0.2 s), 1 s, generalised-alpha at 1/8192 s as the
beam. Prints per level and element kind the wall time, and the velocity's RMS error
against the same kind at an eighth of the step (its own discretisation error), and how far
the two kinds' fine-step solutions lie apart (whether they converge to the same motion)::

    python bench/jenkins_bristle.py [--levels 3,30,100] [--elements 12]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

FREQ, END, STEP = 95.0, 1.0, 1.0 / 8192


def run(kind: str, n: int, amp: float, sub: int) -> tuple[np.ndarray, float]:
    """Velocity of the second mass at the step ``STEP / sub`` (sampled at ``STEP``) and the
    solver's wall seconds."""
    import exudyn as exu
    from exudyn import itemInterface as ei
    from exudyn.utilities import CreateSymbolicUserFunction

    k_j, f_j = np.linspace(2e5, 6e5, n), np.linspace(1.0, 12.0, n)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ei.ObjectGround())
    n1 = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=[0, 0]))
    n2 = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=[1, 0]))
    mbs.AddObject(ei.ObjectMassPoint2D(nodeNumber=n1, mass=0.5))
    mbs.AddObject(ei.ObjectMassPoint2D(nodeNumber=n2, mass=0.3))
    mg = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    p1 = mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=n1))
    p2 = mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=n2))
    mbs.AddObject(ei.ObjectConnectorCartesianSpringDamper(
        markerNumbers=[mg, p1], stiffness=[2e5, 2e5, 0], damping=[20, 20, 0]))
    x1 = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=n1, coordinate=0))
    x2 = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=n2, coordinate=0))
    y2 = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=n2, coordinate=1))
    g0 = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=mbs.AddNode(ei.NodePointGround()),
                                               coordinate=0))
    mbs.AddObject(ei.ObjectConnectorCoordinateSpringDamper(markerNumbers=[g0, y2],
                                                           stiffness=1e5, damping=5))
    mbs.AddObject(ei.ObjectConnectorCoordinateSpringDamper(markerNumbers=[x1, x2],
                                                           stiffness=5e3, damping=2))
    keep = []
    if kind == "return mapping":
        xs = [exu.symbolic.Real(f"bench_jenkins_x{i}", 0.0) for i in range(n)]
        x = np.zeros(n)

        def law(i):
            k, f = float(k_j[i]), float(f_j[i])

            def force(mbs, t, itemNumber, u, v, k_, d_, off):
                s = u[0] - 1.0  # the reference distance of the two points
                fs = exu.symbolic.max(exu.symbolic.min(k * (s - xs[i]), exu.symbolic.Real(f)),
                                      exu.symbolic.Real(-f))
                return [fs, exu.symbolic.Real(0.0), exu.symbolic.Real(0.0)]
            return force

        for i in range(n):
            co = mbs.AddObject(ei.ObjectConnectorCartesianSpringDamper(
                markerNumbers=[p1, p2], stiffness=[0, 0, 0], damping=[0, 0, 0]))
            uf = CreateSymbolicUserFunction(mbs, law(i), "springForceUserFunction", co)
            mbs.SetObjectParameter(co, "springForceUserFunction", uf)
            keep.append(uf)

        def prestep(mbs, t):  # the return mapping of the converged step
            q = mbs.systemData.GetODE2Coordinates()
            s = q[2] - q[0]
            trial = k_j * (s - x)
            for i in np.flatnonzero(np.abs(trial) > f_j):
                x[i] = s - np.copysign(f_j[i], trial[i]) / k_j[i]
                xs[i].SetValue(float(x[i]))
            return True

        mbs.SetPreStepUserFunction(prestep)
    else:
        for i in range(n):
            data = mbs.AddNode(ei.NodeGenericData(numberOfDataCoordinates=3,
                                                  initialCoordinates=[0, 0, 0]))
            mbs.AddObject(ei.ObjectConnectorCoordinateSpringDamperExt(
                markerNumbers=[x1, x2], nodeNumber=data, stiffness=0, damping=0,
                dynamicFrictionForce=float(f_j[i]), staticFrictionOffsetForce=0.0,
                stickingStiffness=float(k_j[i]), stickingDamping=0.0,
                frictionProportionalZone=0.0))
    load = mbs.AddLoad(ei.LoadForceVector(markerNumber=p1, loadVector=[0, 0, 0]))
    mbs.SetLoadParameter(load, "loadVectorUserFunction", lambda mbs, t, lv: [
        amp * np.sin(2 * np.pi * FREQ * t) * min(t / 0.2, 1.0), 0, 0])
    sensor = mbs.AddSensor(ei.SensorNode(nodeNumber=n2, storeInternal=True,
                                         outputVariableType=exu.OutputVariableType.Velocity))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    h = STEP / sub
    ti.endTime, ti.numberOfSteps, ti.verboseMode = END, round(END / h), 0
    ti.adaptiveStep, ti.minimumStepSize = True, h / 64
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = h
    ss.linearSolver.solverType = exu.LinearSolverType.EigenDense
    ti.generalizedAlpha.spectralRadius = 0.8
    ti.generalizedAlpha.computeInitialAccelerations = True
    ti.newton.relativeTolerance = 1e-6
    ti.newton.absoluteTolerance = 1e-6 * amp
    ti.newton.numericalDifferentiation.minimumCoordinateSize = 1e-4
    ti.discontinuous.useRecommendedStepSize = False
    t0 = time.perf_counter()
    mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    wall = time.perf_counter() - t0
    v = np.asarray(mbs.GetSensorStoredData(sensor))[::sub, 1]
    return v, wall


def rms_rel(a: np.ndarray, ref: np.ndarray) -> float:
    n = min(len(a), len(ref))
    return float(np.sqrt(np.mean((a[:n] - ref[:n]) ** 2) / np.mean(ref[:n] ** 2)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", default="3,30,100")
    ap.add_argument("--elements", type=int, default=12)
    args = ap.parse_args()
    kinds = ("return mapping", "Exudyn bristle")
    for amp in (float(a) for a in args.levels.split(",")):
        fine = {k: run(k, args.elements, amp, 8)[0] for k in kinds}
        out = {k: run(k, args.elements, amp, 1) for k in kinds}
        print(f"{amp:g} N: fine-step solutions {rms_rel(fine[kinds[1]], fine[kinds[0]]):.1e} "
              "apart")
        for k in kinds:
            v, wall = out[k]
            print(f"  {k:15s} {wall:6.3f} s, error against its h/8 run "
                  f"{100 * rms_rel(v, fine[k]):.2f} %")
        print(f"  return mapping / bristle wall: {out[kinds[0]][1] / out[kinds[1]][1]:.2f}")


if __name__ == "__main__":
    main()
