"""How well a record's own noise is estimated, over random cases. The propagated noise model
(``[calibration] noise = "propagated"``), the THD entries' noise floor and a comparison's
"noise alone" figures all rest on two estimates made from the record alone:
:func:`sensfw.measure.bands.noise_sigma` (white noise on an output channel) and
:func:`sensfw.measure.bands.excitation_noise_sigma` (on the excitation). This benchmark
draws ``bench/recovery.py``'s random cases (issue 25: an effect or none, base variables off
nominal, noise 1-5 % of each channel's RMS, one to three levels), simulates each level once
without noise, adds ``--draws`` realisations of the case's noise as the rig does
(:func:`sensfw.measure.synthetic.record`) and prints, per estimator, the ratio of the
estimate to the true standard deviation over every (case, level, channel): its median, its
5-95 % range and how often it reads low. Each estimator's parts are printed beside it: the
local fit's residual and the spectrum above the sweep (the estimates before stop 63) and
the short-time spectrum's low quantile (:func:`~sensfw.measure.bands.tf_noise_sigma`).

    python bench/noise_estimates.py --cases 20               # seeds 2025-2044
    python bench/noise_estimates.py --cases 20 --noise 0.05,0.10

One simulation per case and level (no run store: the levels are simulated directly).
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: this folder goes last
HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE] + [str(HERE)]

import argparse  # noqa: E402

import numpy as np  # noqa: E402
import recovery as rec  # noqa: E402


def summary(name: str, ratios) -> str:
    r = np.asarray(ratios, float)
    lo, med, hi = np.percentile(r, [5, 50, 95])
    return (f"{name:34s} {len(r):5d}   median {med:5.2f}   5-95 % {lo:5.2f}-{hi:5.2f}   "
            f"below 0.95: {np.mean(r < 0.95):4.0%}   above 1.3: {np.mean(r > 1.3):4.0%}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=20)
    ap.add_argument("--first", type=int, default=0, help="index of the first case")
    ap.add_argument("--seed", type=int, default=2025, help="seed of case 0 (case i: seed+i)")
    ap.add_argument("--draws", type=int, default=3, help="noise realisations per level")
    ap.add_argument("--noise", type=rec._range, default=None, metavar="LO,HI",
                    help="the cases' noise range (bench/recovery.py's --noise)")
    args = ap.parse_args()
    from sensfw.measure import bands, cases
    from sensfw.measure.synthetic import Rig, record, synthesize

    study = rec.bench_study("quick", short=True)
    band = (study.excitation.f0, study.excitation.f1)
    out = {k: [] for k in ("output", "output: local fit", "output: short-time",
                           "excitation", "excitation: above the band",
                           "excitation: short-time")}
    for i in range(args.first, args.first + args.cases):
        case = cases.draw(study, args.seed + i, rec.LEVELS["quick"],
                          noise=args.noise or cases.NOISE)
        hidden = []
        if case["effect"]:
            hidden = [cases.truth(case) + ":" + ",".join(
                f"{k}={v!r}" for k, v in case["params"].items())]
        worst = []
        for j, level in enumerate(case["levels"]):
            clean, _ = synthesize(study, sets=case["sets"], effects=hidden, amplitude=level,
                                  rig=Rig(noise=0.0))
            rng = np.random.default_rng(case["seed"] * 10 + j)
            sp = case["noise"] * float(np.sqrt(np.mean(clean.force**2)))
            for _ in range(args.draws):
                sig = record(clean, Rig(noise=case["noise"]), level, rng)
                top = bands.usable_limit(sig)
                out["excitation"].append(bands.excitation_noise_sigma(sig, band) / sp)
                out["excitation: above the band"].append(
                    (bands.above_band_noise_sigma(sig, band) or 0.0) / sp)
                out["excitation: short-time"].append(
                    bands.tf_noise_sigma(sig.force, sig.fs, top) / sp)
                for ch, x in clean.channels.items():
                    sx = case["noise"] * float(np.sqrt(np.mean(x**2)))
                    est = bands.noise_sigma(sig, ch) / sx
                    out["output"].append(est)
                    out["output: local fit"].append(
                        bands.local_fit_noise_sigma(sig, ch) / sx)
                    out["output: short-time"].append(
                        bands.tf_noise_sigma(sig.channel(ch), sig.fs, top) / sx)
                    worst.append(est)
        truth = cases.truth(case) if case["effect"] else "no effect"
        print(f"{args.seed + i} {truth:38s} noise {100 * case['noise']:.1f} % levels "
              f"{case['levels']}: output estimate / truth {min(worst):.2f}-{max(worst):.2f}",
              flush=True)
    print("\nestimate / true standard deviation    count")
    for name, ratios in out.items():
        print(summary(name, ratios))


if __name__ == "__main__":
    main()
