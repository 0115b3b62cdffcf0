"""Newton for the bolted beam's joint effects with slider bodies (``micro_slip``): full Newton
(a numerical Jacobian at every iteration) against the patient modified Newton the model uses
(``sensfw.models.bolted_beam.simulation.PATIENT``), on the same run, in the same process.

A linear sweep 84 -> 96 Hz through the second bending mode (2 s, 1024 Hz output,
generalised-alpha at 1/8192 s), micro_slip at the joint (joint 1e5 N/mm, sliders 1.6e6 N/mm,
macro-slip 700 N, exponent -0.5), at each ``--levels`` force. Prints per level the wall time
of each and their ratio, and the laser signals' relative RMS difference, next to the
difference of full Newton from itself at half the step (the discretisation error the Newton
choice must stay within).

    python bench/joint_newton.py [--levels 3,15] [--duration 2.0]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import LinearSweep
from sensfw.models.bolted_beam import BoltedBeam, simulation

POINT = {"joint_stiffness": 1e5, "microslip_stiffness": 1.6e6, "microslip_force": 700.0,
         "microslip_exponent": -0.5}


def laser(model, p, ex, newton: str, substeps: int) -> tuple[np.ndarray, float]:
    """Wall seconds and laser signal of one run with ``newton``, as ``BoltedBeam.simulate``
    integrates it (``substeps`` steps per output sample)."""
    t0 = time.perf_counter()
    built = model.build(p, ex, step=1.0 / (ex.fs * substeps))
    scale = float(np.max(np.abs(ex.force())))
    channels = simulation.solve(built, ex.fs, ex.n_samples, substeps, "GeneralizedAlpha",
                                0.8, scale, newton=newton)
    return channels["Laser"], time.perf_counter() - t0


def rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", default="3,15", help="force amplitudes (N), comma-separated")
    ap.add_argument("--duration", type=float, default=2.0)
    args = ap.parse_args()
    model = BoltedBeam(effects=["micro_slip"])
    p = model.parameters().complete({**model.parameters().nominal(), **POINT})
    for level in (float(x) for x in args.levels.split(",")):
        ex = LinearSweep(84.0, 96.0, args.duration, 1024.0, level)
        full, t_full = laser(model, p, ex, "full", 8)
        patient, t_patient = laser(model, p, ex, "patient", 8)
        half, _ = laser(model, p, ex, "full", 16)
        print(f"{level:g} N: full Newton {t_full:.1f} s, patient {t_patient:.1f} s, ratio "
              f"{t_full / t_patient:.2f}; laser RMS difference patient-full "
              f"{100 * rel(patient, full):.1f} %, full at half the step from full "
              f"{100 * rel(full, half):.1f} %, patient from that {100 * rel(patient, half):.1f} %",
              flush=True)


if __name__ == "__main__":
    main()
