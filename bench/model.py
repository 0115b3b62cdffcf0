"""Benchmark of the shipped Exudyn model (issue 3, item 6).

Prints wall seconds per simulated second of the nominal run (1 s chirp, 50 Hz -> 5 kHz,
20 kHz output), integrator steps per wall second, and the ratio against the same model built
with Python user functions, measured in the same run (the Python variant on a shorter chirp,
compared per simulated second). Target: a 1 s chirp in under 4 s wall on one core.

    python bench/model.py [--duration 1.0] [--python-duration 0.05]
"""

from __future__ import annotations

import argparse
import time

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly


def timed(model, excitation, solver, kind):
    """Wall seconds of one run and the step it used (the model may take a smaller one)."""
    t0 = time.perf_counter()
    sig = model.simulate(PARAMETERS.nominal(), excitation, solver, user_functions=kind)
    return time.perf_counter() - t0, sig.meta["step"]


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
    args = ap.parse_args()
    model, solver = ShaftAssembly(), SolverSettings()
    full = Chirp(50, 5000, args.duration, 20000, args.amplitude)
    short = Chirp(50, 5000, args.python_duration, 20000, args.amplitude)
    timed(model, short, solver, "symbolic")  # warm-up (imports, first build)
    wall, step = timed(model, full, solver, "symbolic")
    steps = full.n_samples / full.fs / step
    sym_build, py_build = build_time(model, short, "symbolic"), build_time(model, short, "python")
    sym_short = (timed(model, short, solver, "symbolic")[0] - sym_build) / short.duration
    py_short = (timed(model, short, solver, "python")[0] - py_build) / short.duration
    verdict = "met" if wall < 4 * args.duration else "MISSED"
    print(f"symbolic user functions: {args.duration:g} s chirp in {wall:.2f} s wall "
          f"({wall / args.duration:.2f} s per simulated s, {steps / wall:,.0f} RK4 steps/s, "
          f"h = {step:g} s)   target < 4 s: {verdict}")
    print(f"python user functions:   {py_short:.1f} s per simulated s "
          f"(measured on a {short.duration:g} s chirp)")
    print(f"time integration only (build: symbolic {sym_build:.2f} s, python {py_build:.2f} s):"
          f" ratio python/symbolic = {py_short / sym_short:.1f}x")


if __name__ == "__main__":
    main()
