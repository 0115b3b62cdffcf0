"""What one UNESP-BERT run costs: the bolted beam on a rig-like record as it runs now (the
reduced beams' exact Jacobian, ``simulation.REDUCED_JACOBIAN = "exact"``, and the silent
tail integrated only while the beam rings, ``simulation.QUIET``) against the same run
integrated to the end, and against Exudyn's numerical Jacobian and the whole tail (how it
ran before), in the same process.

The record is the rig's sweep as a sampled drive (what ``drive = "measured"`` feeds the
model: a linear sweep 70 -> 110 Hz in 8 s, 8 s of silence, 1024 Hz, generalised-alpha at
1/8192 s) at the forces of the 0.05, 0.15 and 0.30 V records (56.4 N/V), through the
linear model calibrated at 0.05 V and the micro-slip model of the README's first round
(the values ``tests/measure/test_bert_loop.py`` stores). Per model and level: wall seconds
of each, their ratios to now, where the quiet tail stopped, and how far apart now and
before are (laser: RMS relative, and the largest difference of its spectrum over 80-105 Hz,
dB) beside how far the run moves at half the step (``--half``: the discretisation error
the difference should stay within)::

    python bench/beam_runs.py [--levels 2.82,8.46,16.9] [--half]
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module that scipy imports
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402  (after the sys.path fix)
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.signal import welch  # noqa: E402

from sensfw.excitation import LinearSweep, SampledForce  # noqa: E402
from sensfw.models.base import SolverSettings  # noqa: E402
from sensfw.models.bolted_beam import BoltedBeam, simulation  # noqa: E402

LINEAR = {"clamp_stiffness": 39876.46, "joint_stiffness": 1.0e7, "damping_ratio": 0.015443}
MICRO_SLIP = {"clamp_stiffness": 50196.56, "joint_stiffness": 9316438.5,
              "damping_ratio": 0.0061782, "microslip_residual": 0.0113271,
              "microslip_force": 766.128, "microslip_exponent": -0.359747}


def record(level: float) -> SampledForce:
    sweep = LinearSweep(70.0, 110.0, 8.0, 1024.0, level, tail=8.0)
    return SampledForce(samples=sweep.force(), fs=1024.0, amplitude=level,
                        sweep={"kind": "linear_sweep", "f0": 70.0, "f1": 110.0,
                               "t_start": 0.0, "t_end": 8.0})


def run(model: BoltedBeam, p: dict, ex, step: float, jacobian: str = "exact",
        quiet: float = simulation.QUIET) -> tuple[np.ndarray, float, float | None]:
    """Laser signal, wall seconds and the quiet tail's stop (s) of one run."""
    saved = simulation.REDUCED_JACOBIAN, simulation.QUIET
    simulation.REDUCED_JACOBIAN, simulation.QUIET = jacobian, quiet
    try:
        t0 = time.perf_counter()
        sig = model.simulate(p, ex, SolverSettings(method="GeneralizedAlpha", step=step,
                                                   auto_step=False))
        return sig.channels["Laser"], time.perf_counter() - t0, sig.meta["quiet_from"]
    finally:
        simulation.REDUCED_JACOBIAN, simulation.QUIET = saved


def distance(a: np.ndarray, b: np.ndarray, fs: float = 1024.0) -> tuple[float, float]:
    """RMS distance of ``a`` from ``b`` relative to ``b`` (%) and the largest difference of
    their spectra over 80-105 Hz (dB)."""
    f, pa = welch(a, fs, nperseg=1024)
    _, pb = welch(b, fs, nperseg=1024)
    band = (f >= 80) & (f <= 105)
    rms = np.sqrt(np.mean((a - b) ** 2) / np.mean(b**2))
    return 100 * float(rms), float(np.max(np.abs(10 * np.log10(pa[band] / pb[band]))))


def apart(a: np.ndarray, b: np.ndarray, fs: float = 1024.0) -> str:
    rms, db = distance(a, b, fs)
    return f"{rms:.2g} % / {db:.2g} dB"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", default="2.82,8.46,16.9", help="force amplitudes (N)")
    ap.add_argument("--half", action="store_true", help="also run the exact one at half the step")
    args = ap.parse_args()
    step = 1.0 / 8192
    for name, model, values in (("linear", BoltedBeam(), LINEAR),
                                ("micro-slip", BoltedBeam(effects=["micro_slip"]), MICRO_SLIP)):
        p = model.parameters().complete({**model.parameters().nominal(), **values})
        for jacobian in ("exact", "numerical"):  # warm-up: imports, first assembly
            run(model, p, SampledForce(samples=np.zeros(1024), fs=1024.0), step, jacobian)
        for level in (float(x) for x in args.levels.split(",")):
            ex = record(level)
            now, t_now, stop = run(model, p, ex, step)
            _, t_full, _ = run(model, p, ex, step, quiet=0.0)
            before, t_before, _ = run(model, p, ex, step, "numerical", quiet=0.0)
            line = (f"{name:10s} {level:5.2f} N: now {t_now:5.2f} s (quiet from "
                    f"{stop or 16.0:.1f} s of 16); whole tail x{t_full / t_now:.2f}; "
                    f"numerical Jacobian and whole tail x{t_before / t_now:.2f}; now vs "
                    f"before (laser RMS / spectrum 80-105 Hz) {apart(now, before)}")
            if args.half:
                half, _, _ = run(model, p, ex, step / 2)
                line += f"; at half the step {apart(now, half)}"
            print(line, flush=True)


if __name__ == "__main__":
    main()
