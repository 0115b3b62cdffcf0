"""Benchmark of the shipped Exudyn models (issue 3, item 6; issue 14, item 2; issue 15).

Shaft assembly: for the nominal run and the screen run with the friction velocities at their
minimum (the stiffest stick band of Table 1, integrated with the default adaptive DOPRI5,
and with ``stiff_method = "VelocityVerlet"``): wall and CPU seconds per simulated
second (1 s chirp, 50 Hz -> 5 kHz, 20 kHz output), integrator steps per second, and the ratio
of the v-min runs to the nominal one (issue 15: within 2x). Then the ratio against the same
model built with Python user functions, measured in the same run (the Python variant on a
shorter chirp, compared per simulated second). Target: a 1 s chirp in under 4 s wall on one
core. CPU time is printed because the machine may be shared: it is less sensitive to other load
than wall time.

Bolted beam: wall (and CPU) seconds of one UNESP-BERT record (linear sweep 70 -> 110 Hz in
8 s, 8 s tail, 1024 Hz output, generalised-alpha at 1/8192 s), against two baselines run in
the same process: the same model with Python user functions and a cantilever of Exudyn's
ANCF cable elements (``ObjectANCFCable2D``, 20 elements, same integrator and step; the
discretisation the model did not choose), both per simulated second on a shorter record.
Target: the record in under 20 s on one core.

    python bench/model.py [--duration 1.0] [--python-duration 0.05] [--repeat 2]
                          [--skip-shaft] [--skip-beam] [--beam-baseline-duration 2.0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly

V_MIN = {**PARAMETERS.nominal(), "slide_v_stiction": 0.01, "slide_v_friction": 0.1}


def timed(model, params, excitation, solver, kind="symbolic"):
    """Wall and CPU seconds of one run and its metadata (step, integrator, steps taken)."""
    t0, c0 = time.perf_counter(), time.process_time()
    sig = model.simulate(params, excitation, solver, user_functions=kind)
    return time.perf_counter() - t0, time.process_time() - c0, sig.meta


def build_time(model, excitation, kind):
    """Static equilibrium + system assembly, to separate it from time integration."""
    t0 = time.perf_counter()
    built = model.build(PARAMETERS.nominal(), excitation, user_functions=kind)
    built.mbs.Reset()
    built.SC.Reset()
    return time.perf_counter() - t0


def ancf_cantilever(excitation, elements: int = 20, step: float = 1 / 8192,
                    absolute_tolerance: float | None = None) -> float:
    """Wall seconds of a uniform 0.5 m aluminium cantilever of ``elements`` ANCF cable
    elements (clamped: position and transverse slope held), the sweep at 85 mm, the tip's
    velocity sampled, integrated like the bolted beam (generalised-alpha, same Newton
    tolerances unless ``absolute_tolerance`` is given)."""
    import exudyn as exu
    from exudyn import itemInterface as ei
    from exudyn.beams import GenerateBeamElementsAlongLine

    from sensfw.models.bolted_beam import simulation
    from sensfw.models.contact import symbolic_ops
    from sensfw.models.planar.exudyn import load_function, user_function

    E, rho, b, h, L = 70e9, 2700.0, 0.0254, 0.00635, 0.5
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    template = ei.ObjectANCFCable2D(physicsMassPerLength=rho * b * h,
                                    physicsBendingStiffness=E * b * h**3 / 12,
                                    physicsAxialStiffness=E * b * h,
                                    physicsBendingDamping=1e-4 * E * b * h**3 / 12)
    beam = GenerateBeamElementsAlongLine(mbs, [0, 0, 0], [L, 0, 0], elements, template,
                                         groundConstraintsStart=[True, True, False, True])
    le = L / elements
    k = int(0.085 // le)
    marker = mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=beam["elements"][k],
                                                 localPosition=[0.085 - k * le, 0, 0]))
    load = mbs.AddLoad(ei.LoadForceVector(markerNumber=marker, loadVector=[0, 0, 0]))
    ops = symbolic_ops()
    keep = user_function(mbs, load, load_function(
        lambda ops, t: (0.0, excitation.force_expression(ops, t)), ops, "symbolic"),
        "loadVectorUserFunction", "symbolic")
    mbs.AddSensor(ei.SensorBody(bodyNumber=beam["elements"][-1], localPosition=[le, 0, 0],
                                storeInternal=True,
                                outputVariableType=exu.OutputVariableType.Velocity))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    n = excitation.n_samples
    ti.endTime, ti.numberOfSteps = n / excitation.fs, round(n / excitation.fs / step)
    ti.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 1 / excitation.fs
    ti.generalizedAlpha.spectralRadius = 0.8
    ti.newton.useModifiedNewton = True
    ti.newton.relativeTolerance = simulation.NEWTON_TOLERANCE
    ti.newton.absoluteTolerance = absolute_tolerance or simulation.NEWTON_ABSOLUTE * float(
        np.max(np.abs(excitation.force())))
    exu.config.printToConsole = False
    t0 = time.perf_counter()
    mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    wall = time.perf_counter() - t0
    del keep
    return wall


def beam(args) -> None:
    """The bolted beam: one record, and the baselines per simulated second."""
    from sensfw.excitation import LinearSweep
    from sensfw.models.bolted_beam import PARAMETERS as BEAM
    from sensfw.models.bolted_beam import BoltedBeam

    model = BoltedBeam()
    solver = SolverSettings(method="GeneralizedAlpha", step=1 / 8192, auto_step=False)
    record = LinearSweep(70.0, 110.0, 8.0, 1024.0, 1.0, tail=8.0)
    d = args.beam_baseline_duration
    short = LinearSweep(70.0, 110.0, d, 1024.0, 1.0)

    def run(excitation, kind):
        t0, c0 = time.perf_counter(), time.process_time()
        model.simulate(BEAM.nominal(), excitation, solver, user_functions=kind)
        return time.perf_counter() - t0, time.process_time() - c0

    def integrate(kind):  # time integration alone (statics, reduction, assembly excluded)
        from sensfw.models.bolted_beam import simulation

        built = model.build(BEAM.nominal(), short, user_functions=kind, step=solver.step)
        t0 = time.perf_counter()
        simulation.solve(built, short.fs, short.n_samples, 8, solver.method,
                         solver.spectral_radius, 1.0)
        return time.perf_counter() - t0

    run(short, "symbolic")  # warm-up
    wall, cpu = run(record, "symbolic")
    sym_short = integrate("symbolic") / d
    py_short = integrate("python") / d
    ancf = ancf_cantilever(short) / d
    ancf_loose = ancf_cantilever(short, absolute_tolerance=1e-4) / d
    verdict = "met" if wall < 20.0 else "MISSED"
    print(f"bolted beam: one 16 s record (8 s sweep + 8 s tail, 1024 Hz, GA 1/8192 s) in "
          f"{wall:.2f} s wall ({cpu:.2f} s CPU)   target < 20 s: {verdict}")
    print(f"  time integration per simulated s on a {d:g} s sweep: symbolic {sym_short:.2f} s,"
          f" python user functions {py_short:.2f} s ({py_short / sym_short:.1f}x), "
          f"20-element ANCF cantilever {ancf:.2f} s ({ancf / sym_short:.1f}x; with Newton's "
          f"absolute tolerance 1e-4 N {ancf_loose:.2f} s, {ancf_loose / sym_short:.1f}x)")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--python-duration", type=float, default=0.05)
    ap.add_argument("--amplitude", type=float, default=0.1)
    ap.add_argument("--repeat", type=int, default=2, help="runs per case (best is kept)")
    ap.add_argument("--skip-shaft", action="store_true")
    ap.add_argument("--skip-beam", action="store_true")
    ap.add_argument("--beam-baseline-duration", type=float, default=2.0)
    args = ap.parse_args()
    if not args.skip_beam:
        beam(args)
    if args.skip_shaft:
        return
    model, solver = ShaftAssembly(), SolverSettings()
    full = Chirp(50, 5000, args.duration, 20000, args.amplitude)
    short = Chirp(50, 5000, args.python_duration, 20000, args.amplitude)
    timed(model, PARAMETERS.nominal(), short, solver)  # warm-up (imports, first build)
    best = {}
    cases = (("nominal", PARAMETERS.nominal(), solver), ("v-min", V_MIN, solver),
             ("v-min Verlet", V_MIN, SolverSettings(stiff_method="VelocityVerlet")))
    for _ in range(args.repeat):  # alternate the cases so that all see the same load
        for name, params, settings in cases:
            wall, cpu, meta = timed(model, params, full, settings)
            if name not in best or cpu < best[name][1]:
                best[name] = (wall, cpu, meta)
    for name, (wall, cpu, meta) in best.items():
        how = meta["integrator"]
        how += (f", {meta['steps']} steps of mean {meta['mean_step'] * 1e6:.2f} us "
                f"({meta['rejected_steps']} rejected, at most {meta['step'] * 1e6:.3g} us)"
                if "tolerance" in meta else f", h = {meta['step'] * 1e6:.3g} us")
        print(f"{name:12s} {args.duration:g} s chirp: {wall / args.duration:.2f} s wall and "
              f"{cpu / args.duration:.2f} s CPU per simulated s, {meta['steps'] / cpu:,.0f} "
              f"steps per CPU s ({how})")
    w_nom, c_nom, _ = best["nominal"]
    for name in ("v-min", "v-min Verlet"):
        w, c, _ = best[name]
        verdict = "met" if w / w_nom <= 2 else "MISSED"
        print(f"{name} / nominal: {w / w_nom:.2f}x wall, {c / c_nom:.2f}x CPU (issue 15: "
              f"within 2x of the nominal run's wall time: {verdict})")
    wall = best["nominal"][0]
    verdict = "met" if wall < 4 * args.duration else "MISSED"
    print(f"nominal {args.duration:g} s chirp in {wall:.2f} s wall   target < 4 s: {verdict}")
    sym_build, py_build = build_time(model, short, "symbolic"), build_time(model, short, "python")
    sym_short = (timed(model, PARAMETERS.nominal(), short, solver)[0] - sym_build) \
        / short.duration
    py_short = (timed(model, PARAMETERS.nominal(), short, solver, "python")[0] - py_build) \
        / short.duration
    print(f"python user functions:   {py_short:.1f} s per simulated s "
          f"(measured on a {short.duration:g} s chirp)")
    print(f"time integration only (build: symbolic {sym_build:.2f} s, python {py_build:.2f} s):"
          f" ratio python/symbolic = {py_short / sym_short:.1f}x")


if __name__ == "__main__":
    main()
