"""Signal benchmark (issue 2, item 4): time to score one 1 s, 20 kHz run (Hv FRF + order
spectrum + THD) against a straightforward per-frame Python loop implementation of the order
spectrum (resample each frame's samples, FFT, pick the orders), measured in the same run.
Target: under 50 ms per run.

    python bench/signal.py [--repeat 20]
"""

from __future__ import annotations

import sys
from pathlib import Path

# this file is named like the standard library's `signal`; keep its folder off the path
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).parent]

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from sensfw.excitation import chirp_phase, log_chirp  # noqa: E402
from sensfw.signal import frf, order_spectrum, thd_from_spectrum  # noqa: E402

FS, F0, F1, T = 20000.0, 50.0, 5000.0, 1.0


def naive_order_spectrum(x, fs, f_inst, revs_per_frame=16, max_order=2.0):
    """The same angle-domain Fourier integral as ``order_spectrum`` (flat-top window over
    frames of W revolutions, half-frame hop), written the straightforward way: a Python loop
    over frames, each with its own exponentials."""
    dphi = 2 * np.pi * f_inst / fs
    phi = np.concatenate([[0.0], np.cumsum(0.5 * (dphi[1:] + dphi[:-1]))])
    rev = phi / (2 * np.pi)
    orders = np.arange(0, max_order * revs_per_frame + 1) / revs_per_frame
    a = (0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368)
    frames = []
    start = 0.0
    while start + revs_per_frame <= rev[-1]:
        sel = (rev >= start) & (rev < start + revs_per_frame)
        c = 2 * np.pi * (rev[sel] - start) / revs_per_frame
        w = a[0] - a[1] * np.cos(c) + a[2] * np.cos(2 * c) - a[3] * np.cos(3 * c) \
            + a[4] * np.cos(4 * c)
        spec = []
        for n in orders:
            X = np.sum(x[sel] * w * np.exp(-1j * n * phi[sel]) * dphi[sel])
            spec.append(abs(X) / np.sum(w * dphi[sel]) * (np.sqrt(2) if n > 0 else 1.0))
        frames.append(spec)
        start += revs_per_frame / 2
    return orders, np.sqrt(np.mean(np.square(frames), 0))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=20)
    args = ap.parse_args()
    t, force, f_inst = log_chirp(F0, F1, T, FS)
    phi = chirp_phase(t, F0, F1, T)
    rng = np.random.default_rng(0)
    x = np.sin(phi - 0.3) + 0.1 * np.sin(2 * phi) + 0.01 * rng.standard_normal(len(t))

    def fast():
        frf(force, x, FS, estimator="Hv")
        orders, P = order_spectrum(x, FS, f_inst)
        return thd_from_spectrum(orders, P)

    def naive():
        frf(force, x, FS, estimator="Hv")
        orders, P = naive_order_spectrum(x, FS, f_inst)
        return thd_from_spectrum(orders, P)

    print(f"THD of the test signal (10 % exact): vectorised {fast():.3f} %, "
          f"per-frame loop {naive():.3f} %")
    res = {}
    for name, fn in (("vectorised", fast), ("per-frame loop", naive)):
        t0 = time.perf_counter()
        for _ in range(args.repeat):
            fn()
        res[name] = (time.perf_counter() - t0) / args.repeat
    ms = res["vectorised"] * 1e3
    print(f"score one 1 s, 20 kHz run (Hv FRF + order spectrum + THD): {ms:.1f} ms "
          f"(target < 50 ms: {'met' if ms < 50 else 'MISSED'})")
    print(f"per-frame Python loop baseline: {res['per-frame loop'] * 1e3:.1f} ms "
          f"-> ratio {res['per-frame loop'] / res['vectorised']:.2f}x")


if __name__ == "__main__":
    main()
