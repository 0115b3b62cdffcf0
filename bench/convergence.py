"""Time-step convergence of the shipped model on the full chirp (issue 3, item 3; the test
suite checks a 0.3 s chirp). For the nominal point and the all-min and all-max corners of
Table 1: the Hv FRF (crankshaft axial, 50 Hz - 5 kHz) and the THD at h and h/2; prints the
FRF change in dB RMS (bar: 0.5 dB) and the relative THD change (bar: 5 %).

    python bench/convergence.py [--duration 1.0] [--step 1e-5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly
from sensfw.signal import frf, thd

CORNERS = {
    "nominal": PARAMETERS.nominal(),
    "all-min": {k: p.min for k, p in PARAMETERS.items()},
    "all-max": {k: p.max for k, p in PARAMETERS.items()},
}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--step", type=float, default=1e-5)
    ap.add_argument("--amplitude", type=float, default=0.1)
    args = ap.parse_args()
    model = ShaftAssembly()
    ex = Chirp(50, 5000, args.duration, 20000, args.amplitude, tail=0.05)
    for name, params in CORNERS.items():
        out = []
        t0 = time.perf_counter()
        for h in (args.step, args.step / 2):
            sig = model.simulate(params, ex, SolverSettings(step=h))
            _, H = frf(sig.force, sig.channels["crank_axial"], sig.fs, nperseg=2048,
                       fmin=50, fmax=5000)
            s = sig.sweep()
            out.append((20 * np.log10(np.abs(H)),
                        thd(s.channels["crank_axial"], s.fs, s.f_inst)))
        d_frf = float(np.sqrt(np.mean((out[0][0] - out[1][0]) ** 2)))
        d_thd = abs(out[0][1] - out[1][1]) / out[1][1]
        ok = d_frf < 0.5 and d_thd < 0.05
        print(f"{name:8s} h={args.step:g} vs {args.step / 2:g}: FRF change {d_frf:.3f} dB RMS, "
              f"THD {out[0][1]:.3f} % vs {out[1][1]:.3f} % ({100 * d_thd:.2f} %)  "
              f"[{'ok' if ok else 'NOT CONVERGED'}]  {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
