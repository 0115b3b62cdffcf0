"""Candidate integrators for the stiff friction stick band (issue 15), on the same runs.

Runs the screen run with the friction velocities at their minimum (``v-min``: the stick band
at ``|lambda| h = 4.1`` for RK4 at 10 us), a run of the paper's DoE at that minimum with the
slide bearing's stiffness at its middle level (``v-min-doe``: 3.56e6 N/mm, THD ~43 %, the
stick band meeting contact impacts) and the nominal run through Exudyn's integrators
and prints, per candidate: right-hand-side evaluations and CPU seconds per simulated second,
steps per CPU second, and the FRF change (dB RMS, Hv, crankshaft axial, 50 Hz - 5 kHz) and
relative THD change against a reference (RK4 at half the step the linearisation asks for),
the FRF change also below 200 Hz, where a low-order method's error shows first.
CPU time, because the machine may be shared.

Candidates: RK4 at the fixed step of the linearisation (``|lambda| h <= 0.6``; the former
default) and at larger fixed steps; DOPRI5 and ODE23 with error control (sensor values
resampled onto the sample grid, ``sensfw.models.integration``); the implicit trapezoidal rule
(Exudyn's generalized-alpha with spectral radius 1, Newton tolerance 1e-6, modified Newton)
and Newmark's method with ``beta = 1/12, gamma = 1/2`` (Fox & Goodwin 1949: the trapezoidal
rule for the velocity-dependent forces, so the stick band is unconditionally stable, and a
fourth-order period error where the trapezoidal rule's is second order; stable for
``omega h < sqrt(6)``; steps reduced where Newton fails, every step recorded and resampled)
and Exudyn's velocity Verlet at fixed steps, also at the step ``stiff_method = "VelocityVerlet"``
takes (which Exudyn marks as under development and which evaluates
velocity-dependent forces at the half-step velocity). Exudyn has no native connector for the
laws of this model (power-law penalty contacts with clearance and ramped damping, friction
driven by a contact's normal force); the last lines bound what native connectors could save:
the right-hand side with the contact laws replaced by trivial symbolic functions, and with no
user functions at all (native connectors of zero stiffness).

``--doe``: instead, the 27 runs of the paper's DoE at the friction-velocity minimum (1 s
chirp) with Newmark ``beta = 1/12`` at 6.25 us against DOPRI5 (the default): the FRF and THD
change and whether Newton needed a reduced step (a check that could choose Newmark per run
only if the runs without one were accurate).

    python bench/integrators.py [--duration 0.3] [--cases v-min,v-min-doe,nominal] [--doe]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import Chirp
from sensfw.models import integration
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly
from sensfw.models.stepsize import (
    StepChoice,
    choose_integration,
    explicit_step,
    first_order_eigenvalues,
)
from sensfw.signal import frf, thd

CASES = {
    "nominal": PARAMETERS.nominal(),
    "v-min": {**PARAMETERS.nominal(), "slide_v_stiction": 0.01, "slide_v_friction": 0.1},
    "v-min-doe": {**PARAMETERS.nominal(), "slide_v_stiction": 0.01, "slide_v_friction": 0.1,
                  "slide_stiffness": 3.5603e6},
}
STAGES = {"RK44": 4, "DOPRI5": 7, "ODE23": 4, "VelocityVerlet": 1}


def run(model, p, ex, q0, choice: StepChoice, implicit: bool = False,
        newmark_beta: float | None = None):
    """One run with ``choice``; returns the crankshaft channel, CPU s and RHS evaluations.
    ``newmark_beta``: Newmark's method with that beta and gamma = 1/2 (implicit), its steps
    reduced where Newton fails (every step recorded and resampled)."""
    import exudyn as exu

    built = model.build(p, ex, q0=q0)
    mbs = built.mbs
    ss = integration.simulation_settings(choice, ex.n_samples / ex.fs, ex.fs)
    if implicit:  # trapezoidal rule: no numerical damping; a Newton tolerance that converges
        ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
        ss.timeIntegration.newton.relativeTolerance = 1e-6
        ss.timeIntegration.newton.absoluteTolerance = 1e-6
        ss.timeIntegration.adaptiveStep = False
    if newmark_beta is not None:
        ga = ss.timeIntegration.generalizedAlpha
        ga.useNewmark, ga.newmarkBeta, ga.newmarkGamma = True, newmark_beta, 0.5
        ss.timeIntegration.adaptiveStep = True  # halve the step where Newton fails
        ss.solution.sensors.writePeriod = 0.0  # then steps leave the grid: resample
    c0 = time.process_time()
    mbs.SolveDynamic(ss, solverType=getattr(exu.DynamicSolverType, choice.method))
    cpu = time.process_time() - c0
    it = mbs.sys["dynamicSolver"].it
    steps = int(it.currentStepIndex) - 1
    if implicit:
        # a residual per Newton iteration and per step (numerical Jacobians not counted)
        evals = int(it.newtonStepsCount) + steps
    else:
        evals = STAGES[choice.method] * (steps + int(it.rejectedAutomaticStepSizeSteps))
    data = np.asarray(mbs.GetSensorStoredData(built.sensors["crank_axial"][0]))
    n = ex.n_samples
    x = (integration.resample(data[:, 0], data[:, 1], ex.fs, n)
         if choice.adaptive or newmark_beta is not None else data[:n, 1])
    mbs.Reset()
    built.SC.Reset()
    return x, cpu, evals, steps


def scores(x, ex):
    """FRF (dB) on its frequency lines and THD (%) of a run's crankshaft channel."""
    t = ex.time()
    f, H = frf(ex.force(t), x, ex.fs, nperseg=1024, fmin=50, fmax=5000)
    n = round(ex.duration * ex.fs)
    return f, 20 * np.log10(np.abs(H)), thd(x[:n], ex.fs, ex.f_inst(t)[:n])


def rhs_cost(model, p, ex, q0, variant: str) -> float:
    """CPU us per right-hand side (RK4, 10 us) with the contact laws as built, as trivial
    symbolic functions, or without user functions (native connectors of zero stiffness)."""
    import sensfw.models.planar.exudyn as pe

    saved = pe.link_function, pe.user_function
    if variant != "model":
        def trivial(ln, off, ops, contact, kind):
            def force(mbs, t, itemNumber, u, v, k, d, offset):
                return pe.vector([0.0 * u[0], 0.0, 0.0], kind)
            return force
        pe.link_function = trivial
    if variant == "native":
        pe.user_function = lambda mbs, item, function, name, kind: None
    try:
        _, cpu, evals, _ = run(model, p, ex, q0, StepChoice(step=1e-5, substeps=5))
    finally:
        pe.link_function, pe.user_function = saved
    return cpu / evals * 1e6


def doe_run(over: dict) -> dict:
    """One DoE run at the friction-velocity minimum: Newmark 1/12 at 6.25 us against DOPRI5
    (1 s chirp); FRF (dB RMS) and relative THD change, and the steps Newton had to add."""
    import exudyn as exu

    exu.config.printToConsole = False
    model = ShaftAssembly()
    ex = Chirp(50, 5000, 1.0, 20000, 0.1, tail=0.05)
    p = model.parameters().complete({**CASES["v-min"], **over})
    q0 = model.equilibrium(p)
    ref, *_ = run(model, p, ex, q0, StepChoice(method="DOPRI5", tolerance=1e-9, adaptive=True,
                                               step=1e-5, substeps=5))
    k = 8
    x, _, _, steps = run(model, p, ex, q0, StepChoice(method="GeneralizedAlpha",
                                                      step=1 / (20000 * k), substeps=k),
                         True, 1 / 12)
    (_, db_ref, thd_ref), (_, db, th) = scores(ref, ex), scores(x, ex)
    return {"added_steps": steps - ex.n_samples * k,
            "frf": float(np.sqrt(np.mean((db - db_ref) ** 2))),
            "thd": abs(th - thd_ref) / thd_ref, "thd_ref": thd_ref}


def doe(workers: int = 2) -> None:
    import itertools
    from concurrent.futures import ProcessPoolExecutor

    levels = {"slide_stiffness": (7.05e4, 3.56025e6, 7.05e6),
              "slide_exponent": (1.2, 1.33, 1.46),
              "clutch_drive_stiffness": (3.14e5, 1.5857e7, 3.14e7)}
    runs = [dict(zip(levels, v, strict=True)) for v in itertools.product(*levels.values())]
    with ProcessPoolExecutor(workers) as pool:
        results = list(pool.map(doe_run, runs))
    for over, r in zip(runs, results, strict=True):
        print(f"  k {over['slide_stiffness']:.3g} b {over['slide_exponent']:.2f} cd "
              f"{over['clutch_drive_stiffness']:.3g}: DOPRI5 THD {r['thd_ref']:6.2f} %, "
              f"Newmark 1/12 6.25 us FRF {r['frf']:6.2f} dB THD {100 * r['thd']:5.1f} % "
              f"({r['added_steps']} steps added by Newton failures)", flush=True)
    smooth = [r["frf"] for r in results if r["added_steps"] == 0]
    print(f"runs without an added step: {len(smooth)} of {len(results)}, FRF change up to "
          f"{max(smooth):.2f} dB; with: up to "
          f"{max(r['frf'] for r in results if r['added_steps']):.2f} dB")


def main() -> None:
    import exudyn as exu

    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=0.3)
    ap.add_argument("--cases", default="v-min,v-min-doe,nominal")
    ap.add_argument("--doe", action="store_true",
                    help="the 27 DoE runs at the friction-velocity minimum (see docstring)")
    args = ap.parse_args()
    if args.doe:
        doe()
        return
    exu.config.printToConsole = False
    model = ShaftAssembly()
    ex = Chirp(50, 5000, args.duration, 20000, 0.1, tail=0.05)
    t_sim = ex.n_samples / ex.fs
    for case in args.cases.split(","):
        p = model.parameters().complete(CASES[case])
        q0 = model.equilibrium(p)
        eigenvalues = first_order_eigenvalues(*model.linear_matrices(p, q0))
        h_lin = explicit_step(eigenvalues, 1e-5, ex.fs)
        k = h_lin.substeps
        ref, ref_cpu, *_ = run(model, p, ex, q0, StepChoice(step=h_lin.step / 2, substeps=2 * k))
        f, db_ref, thd_ref = scores(ref, ex)
        low = f < 200.0
        print(f"{case}: reference RK4 at {h_lin.step / 2 * 1e6:.3g} us ({ref_cpu:.1f} s CPU), "
              f"THD {thd_ref:.3f} %; {ex.duration:g} s chirp + {ex.tail:g} s tail", flush=True)
        adaptive = {"adaptive": True, "step": 1e-5, "substeps": 5}
        candidates = [
            (f"RK4 {h_lin.step * 1e6:.3g} us (linearisation)", StepChoice(step=h_lin.step,
                                                                          substeps=k), False),
            *[(f"RK4 {1e6 / (20000 * s):.3g} us", StepChoice(step=1 / (20000 * s), substeps=s),
               False) for s in (12, 11, 10, 9, 8) if s < k],
            *[(f"DOPRI5 tol {tol:g}", StepChoice(method="DOPRI5", tolerance=tol, **adaptive),
               False) for tol in (1e-8, 1e-9, 1e-10)],
            *[(f"ODE23 tol {tol:g}", StepChoice(method="ODE23", tolerance=tol, **adaptive),
               False) for tol in (1e-8, 5e-9, 3e-9, 1e-9)],
            *[(f"trapezoidal {h:g} us", StepChoice(method="GeneralizedAlpha", step=h * 1e-6,
                                                   substeps=round(50 / h)), True)
              for h in (10, 5)],
            *[(f"Newmark 1/12 {1e6 / (20000 * s):.3g} us", StepChoice(
                method="GeneralizedAlpha", step=1 / (20000 * s), substeps=s), "newmark")
              for s in (5, 8, 16)],
            *[(f"velocity Verlet {h:g} us", StepChoice(method="VelocityVerlet", step=h * 1e-6,
                                                       substeps=round(50 / h)), False)
              for h in (2.5, 1.25)],
        ]
        verlet = choose_integration(eigenvalues, 1e-5, ex.fs, stiff_method="VelocityVerlet")
        if verlet.method == "VelocityVerlet":  # the step stiff_method = "VelocityVerlet" takes
            candidates.append((f"velocity Verlet {verlet.step * 1e6:.3g} us (|lambda h| "
                               f"{verlet.real_lambda_h:.2f})", verlet, False))
        for label, choice, implicit in candidates:
            try:
                x, cpu, evals, steps = run(model, p, ex, q0, choice, bool(implicit),
                                           1 / 12 if implicit == "newmark" else None)
            except exu.SolverError as exc:  # a candidate that fails is a result too
                print(f"  {label:32s} failed: {exc}", flush=True)
                continue
            _, db, th = scores(x, ex)
            d_frf = float(np.sqrt(np.mean((db - db_ref) ** 2)))
            d_low = float(np.sqrt(np.mean((db[low] - db_ref[low]) ** 2)))
            print(f"  {label:32s} {evals / t_sim / 1e3:7.0f}k RHS/sim s {cpu / t_sim:6.2f} s CPU"
                  f"/sim s {steps / cpu:9,.0f} steps/CPU s   FRF {d_frf:.3f} dB (below 200 Hz "
                  f"{d_low:.3f})  THD {100 * abs(th - thd_ref) / thd_ref:.2f} %", flush=True)
        if case == "nominal":
            us = {v: rhs_cost(model, p, ex, q0, v) for v in ("model", "trivial", "native")}
            print(f"  CPU us per right-hand side: symbolic contact laws {us['model']:.2f}, "
                  f"trivial symbolic functions {us['trivial']:.2f}, no user functions "
                  f"{us['native']:.2f}")


if __name__ == "__main__":
    main()
