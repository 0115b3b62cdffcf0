"""Time-step convergence of the shipped model on the full chirp (issue 3, item 3; issue 15; the
test suite checks a short chirp). Each case runs with the default solver settings: the model
picks per run a fixed RK4 step from its linearised eigenvalues, or, where an over-damped
eigenvalue lies beyond RK4's stability at the requested step, adaptive DOPRI5 steps under error
control (``sensfw.models.stepsize``; ``--stiff-method VelocityVerlet``: velocity Verlet at a
fixed step). Each case is then rerun with the same integrator at half the
step (fixed runs) or half the tolerance (adaptive runs), and prints the FRF change in dB RMS
(Hv, crankshaft axial, 50 Hz - 5 kHz; bar: 0.5 dB) and the relative THD change (bar: 5 %).
Runs with the stiff treatment are also compared with RK4 at the fixed step the linearisation
asks for (``explicit_step``), an independent integrator (halving a tolerance whose steps
are set by stability changes few steps, so for DOPRI5 that comparison is the stronger check).

Cases: the nominal point and the all-min and all-max corners of Table 1, plus the screen run
with the friction velocities at their minimum (the stiffest stick-slip friction of Table 1).
``--fixed`` runs every case with RK4 at ``--step`` as given (no automatic choice), the
baseline the automatic choice is measured against.

    python bench/convergence.py [--duration 1.0] [--step 1e-5] [--fixed] [--no-reference]
                                [--stiff-method DOPRI5|VelocityVerlet] [--cases v-min,...]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly
from sensfw.models.stepsize import explicit_step, first_order_eigenvalues
from sensfw.signal import frf, thd

CASES = {
    "nominal": PARAMETERS.nominal(),
    "all-min": {k: p.min for k, p in PARAMETERS.items()},
    "all-max": {k: p.max for k, p in PARAMETERS.items()},
    "v-min": {**PARAMETERS.nominal(), "slide_v_stiction": 0.01, "slide_v_friction": 0.1},
}


def frf_db_and_thd(sig) -> tuple[np.ndarray, float]:
    _, H = frf(sig.force, sig.channels["crank_axial"], sig.fs,
               nperseg=min(2048, len(sig.force)), fmin=50, fmax=5000)
    s = sig.sweep()
    return 20 * np.log10(np.abs(H)), thd(s.channels["crank_axial"], s.fs, s.f_inst)


def change(a, b) -> tuple[float, float, float, float]:
    """FRF change (dB RMS), relative THD change, and both THDs (%) from ``b`` to ``a``."""
    (db1, thd1), (db2, thd2) = frf_db_and_thd(a), frf_db_and_thd(b)
    return float(np.sqrt(np.mean((db1 - db2) ** 2))), abs(thd1 - thd2) / thd2, thd1, thd2


def timed(model, params, ex, solver):
    t0, c0 = time.perf_counter(), time.process_time()
    sig = model.simulate(params, ex, solver)
    return sig, time.perf_counter() - t0, time.process_time() - c0


def verdict(d_frf: float, d_thd: float) -> str:
    return "ok" if d_frf < 0.5 and d_thd < 0.05 else "NOT CONVERGED"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=1e-5)
    ap.add_argument("--amplitude", type=float, default=0.1)
    ap.add_argument("--fixed", action="store_true", help="RK4 at --step, no automatic choice")
    ap.add_argument("--no-reference", action="store_true",
                    help="skip the RK4 reference of the stiff runs")
    ap.add_argument("--stiff-method", default="DOPRI5",
                    choices=["DOPRI5", "VelocityVerlet"])
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args()
    model = ShaftAssembly()
    ex = Chirp(50, 5000, args.duration, 20000, args.amplitude, tail=0.05)
    for name in args.cases.split(","):
        params = CASES[name]
        solver = SolverSettings(step=args.step, auto_step=not args.fixed,
                                stiff_method=args.stiff_method)
        sig, wall, cpu = timed(model, params, ex, solver)
        meta = sig.meta
        steps_per_s = meta["steps"] / cpu
        head = (f"{name:8s} {meta['integrator']:15s} h={meta['step'] * 1e6:.3g} us "
                f"({meta['step_limited_by']}, |lambda h| real {meta['real_lambda_h']:.2f} "
                f"osc {meta['oscillatory_lambda_h']:.2f})")
        if "tolerance" in meta:
            head += (f", tol {meta['tolerance']:g}: {meta['steps']} steps of mean "
                     f"{meta['mean_step'] * 1e6:.2f} us, {meta['rejected_steps']} rejected")
            half = model.simulate(params, ex, SolverSettings(step=args.step,
                                                             tolerance=meta["tolerance"] / 2,
                                                             stiff_method="DOPRI5"))
            what = "tol/2"
        else:
            half = model.simulate(params, ex, SolverSettings(method=meta["integrator"],
                                                             step=meta["step"] / 2,
                                                             auto_step=False))
            what = "h/2"
        d_frf, d_thd, thd1, thd2 = change(sig, half)
        print(f"{head}\n    run {wall:.1f} s wall, {cpu:.1f} s CPU ({cpu / ex.duration:.2f} s "
              f"CPU per simulated s, {steps_per_s:,.0f} steps per CPU s); vs {what}: FRF "
              f"change {d_frf:.3f} dB RMS, THD {thd1:.3f} % vs {thd2:.3f} % "
              f"({100 * d_thd:.2f} %)  [{verdict(d_frf, d_thd)}]", flush=True)
        stiff = "tolerance" in meta or meta["integrator"] == "VelocityVerlet"
        if stiff and not args.no_reference:
            fixed = explicit_step(first_order_eigenvalues(*model.linear_matrices(params)),
                                  args.step, ex.fs)
            ref, _, rcpu = timed(model, params, ex, SolverSettings(step=fixed.step,
                                                                       auto_step=False))
            d_frf, d_thd, thd1, thd2 = change(sig, ref)
            print(f"    vs RK4 at the {fixed.step * 1e6:.3g} us the linearisation asks for "
                  f"({rcpu:.1f} s CPU, {rcpu / cpu:.1f}x): FRF change {d_frf:.3f} dB RMS, "
                  f"THD {thd1:.3f} % vs {thd2:.3f} % ({100 * d_thd:.2f} %)  "
                  f"[{verdict(d_frf, d_thd)}]", flush=True)


if __name__ == "__main__":
    main()
