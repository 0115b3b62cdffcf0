"""The bolted beam's micro-slip (Jenkins elements integrated by return mapping,
``sensfw.models.bolted_beam.simulation.JenkinsSliders``) against the linear model, on the same
sweep, in the same process.

A linear sweep 84 -> 96 Hz through the second bending mode (``--duration`` s, 1024 Hz
output, generalised-alpha at 1/8192 s), micro_slip at the joint (joint 1e5 N/mm, Jenkins
elements 1.6e6 N/mm in all: joint 1.7e6 N/mm with a residual of 1e5 / 1.7e6; macro-slip 700 N,
exponent -0.5), at each ``--levels`` force.
Prints per level the wall time of the micro-slip run and its ratio to the linear model's
(joint at the residual 1e5 N/mm), the run's difference from itself at half the step (laser, RMS
relative) and the linear model's (the discretisation error of the sweep itself).

Before the return mapping each Jenkins element was a slider body with regularised friction
(a viscous stick band): 7-18 s for the 2 s sweep at 3-40 N with patient modified Newton
(17-34 s with full Newton), within 2.6-7.7 % (laser RMS) of the return mapping's signal.

    python bench/jenkins.py [--levels 3,15,40] [--duration 2.0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import LinearSweep
from sensfw.models.bolted_beam import BoltedBeam, simulation

POINT = {"joint_stiffness": 1.7e6, "microslip_residual": 1e5 / 1.7e6, "microslip_force": 700.0,
         "microslip_exponent": -0.5}


def laser(model, p, ex, substeps: int) -> tuple[np.ndarray, float]:
    """Laser signal and wall seconds of one run as ``BoltedBeam.simulate`` integrates it
    (``substeps`` steps per output sample)."""
    t0 = time.perf_counter()
    built = model.build(p, ex, step=1.0 / (ex.fs * substeps))
    scale = float(np.max(np.abs(ex.force())))
    channels = simulation.solve(built, ex.fs, ex.n_samples, substeps, "GeneralizedAlpha",
                                0.8, scale)
    return channels["Laser"], time.perf_counter() - t0


def rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", default="3,15,40", help="force amplitudes (N), comma-separated")
    ap.add_argument("--duration", type=float, default=2.0)
    args = ap.parse_args()
    model, linear = BoltedBeam(effects=["micro_slip"]), BoltedBeam()
    p = model.parameters().complete({**model.parameters().nominal(), **POINT})
    p_lin = {**{k: p[k] for k in linear.parameters()}, "joint_stiffness": 1e5}
    for level in (float(x) for x in args.levels.split(",")):
        ex = LinearSweep(84.0, 96.0, args.duration, 1024.0, level)
        lin, t_lin = laser(linear, p_lin, ex, 8)
        lin_half, _ = laser(linear, p_lin, ex, 16)
        ms, t_ms = laser(model, p, ex, 8)
        ms_half, _ = laser(model, p, ex, 16)
        print(f"{level:g} N: micro-slip {t_ms:.2f} s, linear {t_lin:.2f} s, ratio "
              f"{t_ms / t_lin:.2f}; at half the step the laser moves {100 * rel(ms, ms_half):.1f} "
              f"% (linear model: {100 * rel(lin, lin_half):.1f} %); micro-slip vs linear "
              f"{100 * rel(ms, lin):.0f} %", flush=True)


if __name__ == "__main__":
    main()
