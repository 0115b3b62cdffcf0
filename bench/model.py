"""Benchmark of the shipped Exudyn model (issue 3, item 6; issue 15).

For the nominal run and the screen run with the friction velocities at their minimum (the
stiffest stick band of Table 1, integrated adaptively): wall and CPU seconds per simulated
second (1 s chirp, 50 Hz -> 5 kHz, 20 kHz output), integrator steps per second, and the
ratio of the two runs (issue 15: within 2x). Then the ratio against the same model built
with Python user functions, measured in the same run (the Python variant on a shorter chirp,
compared per simulated second). Target: a 1 s chirp in under 4 s wall on one core. CPU time
is printed because the machine may be shared: it is less sensitive to other load than wall
time.

    python bench/model.py [--duration 1.0] [--python-duration 0.05] [--repeat 2]
"""

from __future__ import annotations

import argparse
import time

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


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--python-duration", type=float, default=0.05)
    ap.add_argument("--amplitude", type=float, default=0.1)
    ap.add_argument("--repeat", type=int, default=2, help="runs per case (best is kept)")
    args = ap.parse_args()
    model, solver = ShaftAssembly(), SolverSettings()
    full = Chirp(50, 5000, args.duration, 20000, args.amplitude)
    short = Chirp(50, 5000, args.python_duration, 20000, args.amplitude)
    timed(model, PARAMETERS.nominal(), short, solver)  # warm-up (imports, first build)
    best = {}
    for _ in range(args.repeat):  # alternate the cases so that both see the same load
        for name, params in (("nominal", PARAMETERS.nominal()), ("v-min", V_MIN)):
            wall, cpu, meta = timed(model, params, full, solver)
            if name not in best or cpu < best[name][1]:
                best[name] = (wall, cpu, meta)
    for name, (wall, cpu, meta) in best.items():
        how = meta["integrator"]
        how += (f", {meta['steps']} steps of mean {meta['mean_step'] * 1e6:.2f} us "
                f"({meta['rejected_steps']} rejected, at most {meta['step'] * 1e6:.3g} us)"
                if "tolerance" in meta else f", h = {meta['step'] * 1e6:.3g} us")
        print(f"{name:8s} {args.duration:g} s chirp: {wall / args.duration:.2f} s wall and "
              f"{cpu / args.duration:.2f} s CPU per simulated s, {meta['steps'] / cpu:,.0f} "
              f"steps per CPU s ({how})")
    (_, c_nom, _), (_, c_vmin, _) = best["nominal"], best["v-min"]
    print(f"v-min / nominal: {c_vmin / c_nom:.2f}x CPU (issue 15: within 2x)")
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
