"""Time-step convergence of the shipped model on the full chirp (issue 3, item 3; the test
suite checks a short chirp). Each case runs with the default solver settings, whose step the
model chooses from its linearised eigenvalues (``sensfw.models.stepsize``), then at half that
step; prints the step used and why, the FRF change in dB RMS (Hv, crankshaft axial,
50 Hz - 5 kHz; bar: 0.5 dB) and the relative THD change (bar: 5 %).

Cases: the nominal point and the all-min and all-max corners of Table 1, plus the screen run
with the friction velocities at their minimum (the stiffest stick-slip friction of Table 1).
``--fixed`` runs every case at ``--step`` as given (no automatic reduction), the baseline the
automatic step is measured against.

    python bench/convergence.py [--duration 1.0] [--step 1e-5] [--fixed]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly
from sensfw.models.stepsize import first_order_eigenvalues, spectral_radii
from sensfw.signal import frf, thd

CASES = {
    "nominal": PARAMETERS.nominal(),
    "all-min": {k: p.min for k, p in PARAMETERS.items()},
    "all-max": {k: p.max for k, p in PARAMETERS.items()},
    "v-min": {**PARAMETERS.nominal(), "slide_v_stiction": 0.01, "slide_v_friction": 0.1},
}


def frf_db_and_thd(sig) -> tuple[np.ndarray, float]:
    _, H = frf(sig.force, sig.channels["crank_axial"], sig.fs, nperseg=2048, fmin=50,
               fmax=5000)
    s = sig.sweep()
    return 20 * np.log10(np.abs(H)), thd(s.channels["crank_axial"], s.fs, s.f_inst)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=1e-5)
    ap.add_argument("--amplitude", type=float, default=0.1)
    ap.add_argument("--fixed", action="store_true", help="no automatic step reduction")
    args = ap.parse_args()
    model = ShaftAssembly()
    ex = Chirp(50, 5000, args.duration, 20000, args.amplitude, tail=0.05)
    for name, params in CASES.items():
        t0 = time.perf_counter()
        sig = model.simulate(params, ex, SolverSettings(step=args.step,
                                                        auto_step=not args.fixed))
        wall = time.perf_counter() - t0
        h = sig.meta["step"]
        # |lambda h| at the step used (the run's meta has it only when the model chose it)
        rho_real, rho_osc = spectral_radii(first_order_eigenvalues(
            *model.linear_matrices(params)))
        half = model.simulate(params, ex, SolverSettings(step=h / 2, auto_step=False))
        (db1, thd1), (db2, thd2) = frf_db_and_thd(sig), frf_db_and_thd(half)
        d_frf = float(np.sqrt(np.mean((db1 - db2) ** 2)))
        d_thd = abs(thd1 - thd2) / thd2
        ok = d_frf < 0.5 and d_thd < 0.05
        print(f"{name:8s} h={h * 1e6:.3g} us ({sig.meta['step_limited_by']}, "
              f"|lambda h| real {rho_real * h:.2f} osc "
              f"{rho_osc * h:.2f}) vs h/2: FRF change {d_frf:.3f} dB RMS, "
              f"THD {thd1:.3f} % vs {thd2:.3f} % ({100 * d_thd:.2f} %)  "
              f"[{'ok' if ok else 'NOT CONVERGED'}]  run {wall:.1f} s wall "
              f"({wall / ex.duration:.2f} s per simulated s)", flush=True)


if __name__ == "__main__":
    main()
