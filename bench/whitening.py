"""Is the residual vector white at the truth? Each entry of a hypothesis's residual vector
is a dB difference divided by its standard error (:mod:`sensfw.measure.discrepancy`), so
the model that made a record, at the values that made it, should leave ``chi2 ~ n``: every
verdict (the noise's chi-square test, BIC's margin) rests on that. This benchmark draws
``bench/recovery.py``'s random cases (issue 25), simulates the true hypothesis at its true
values and prints, per case, ``chi2 / n`` against the noise test's bound
``1 + 3 sqrt(2 / n)`` and, over all cases, the mean squared whitened entry by kind: the
THD entries and the band entries by the size of their standard error. A whitening that
holds gives a mean near 1 in every row and a bound exceeded in about one case in a
thousand.

    python bench/whitening.py --cases 40 --first 0 --store S   # seeds 2025-2064

Two simulations per case and level (the nominal model, which fixes the entries as a
diagnosis does, and the truth); with ``--store`` (the recovery benchmark's) none are new.
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: this folder goes last
HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE] + [str(HERE)]

import argparse  # noqa: E402
import math  # noqa: E402
import tempfile  # noqa: E402

import numpy as np  # noqa: E402
import recovery as rec  # noqa: E402

#: band entries grouped by their standard error (dB)
SIGMA_GROUPS = ((0.0, 0.15), (0.15, 0.3), (0.3, 0.6), (0.6, math.inf))


def at_truth(study, case: dict, runner) -> dict:
    """The true hypothesis's dB residuals, standard errors and which entries are THD."""
    from sensfw.measure import cases, discrepancy
    from sensfw.measure.prepared import load_measurements
    from sensfw.measure.residuals import Residuals

    tmp = Path(tempfile.mkdtemp(prefix="sensfw-whitening-"))
    meas = load_measurements(study, cases.measure(study, case, tmp))
    res = Residuals(study, meas, runner,
                    study.calibration_space(list(study.spec.calibration.parameters)))
    res.nominal()  # fixes the entries and their standard errors, as diagnose does
    spec, values = cases.true_values(study, case)
    (comps,) = res.comparisons(spec, [values], "truth", detail=False)
    r, s = discrepancy.residuals(comps, res.entries)
    thd = np.concatenate([[False] * len(b) + [True] * int(t)
                          for b, t in zip(res.entries.bands, res.entries.thd, strict=True)])
    return {"r": r, "s": s, "thd": thd, "levels": res.level_slices()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cases", type=int, default=40)
    ap.add_argument("--first", type=int, default=0, help="index of the first case")
    ap.add_argument("--seed", type=int, default=2025, help="seed of case 0 (case i: seed+i)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--store", type=Path, default=None, help="a run store to share")
    ap.add_argument("--noise-model", choices=rec.NOISE_MODELS, default=None,
                    help="the study's [calibration] noise (the band errors' noise model)")
    ap.add_argument("--noise", type=rec._range, default=None, metavar="LO,HI",
                    help="the cases' noise range (bench/recovery.py's --noise)")
    ap.add_argument("--factors", type=rec._range, default=None, metavar="LO,HI",
                    help="the base variables' offset factors (bench/recovery.py's --factors)")
    args = ap.parse_args()
    from sensfw.measure import cases
    from sensfw.runs import Runner, RunStore

    study = rec.bench_study("quick", short=True, noise_model=args.noise_model)
    store = args.store or Path(tempfile.mkdtemp(prefix="sensfw-whitening-runs-"))
    rows = []
    with Runner(RunStore(store), backend="processes", workers=args.workers) as runner:
        for i in range(args.first, args.first + args.cases):
            case = cases.draw(study, args.seed + i, rec.LEVELS["quick"],
                              noise=args.noise or cases.NOISE,
                              factors=args.factors or cases.FACTORS)
            t = at_truth(study, case, runner)
            z2 = (t["r"] / t["s"]) ** 2
            n = len(z2)
            bound = 1 + 3 * math.sqrt(2 / n)
            rows.append({**t, "z2": z2, "over": z2.sum() / n > bound})
            truth = cases.truth(case) if case["effect"] else "no effect"
            print(f"{args.seed + i} {truth:32s} noise {100 * case['noise']:.1f} % levels "
                  f"{case['levels']}: chi2/n {z2.sum() / n:.2f} (bound {bound:.2f}"
                  f"{', EXCEEDED' if rows[-1]['over'] else ''}), THD entries "
                  f"{z2[t['thd']].sum():.1f} of {z2.sum():.1f}", flush=True)
    per_level = [float(np.mean(r["z2"][sl])) for r in rows for sl in r["levels"]]
    z2 = np.concatenate([r["z2"] for r in rows])
    s = np.concatenate([r["s"] for r in rows])
    thd = np.concatenate([r["thd"] for r in rows])
    print(f"\n{len(rows)} cases: chi2/n above the noise test's bound in "
          f"{sum(r['over'] for r in rows)}; chi2/n median "
          f"{np.median([r['z2'].mean() for r in rows]):.2f}; per level: largest "
          f"{max(per_level):.2f} of {len(per_level)} levels (what a calibration that "
          f"'explains' a level may leave, sensfw.measure.screening.TRUTH_PER_ENTRY)")
    print("entries                      count   mean z^2   median z^2 (Gaussian: 1, 0.45)")
    print(f"THD                        {thd.sum():7d}   {z2[thd].mean():8.2f}   "
          f"{np.median(z2[thd]):8.2f}")
    for lo, hi in SIGMA_GROUPS:
        sel = ~thd & (s >= lo) & (s < hi)
        if sel.any():
            print(f"bands, sigma {lo:.2f}-{hi:.2f} dB    {sel.sum():7d}   "
                  f"{z2[sel].mean():8.2f}   {np.median(z2[sel]):8.2f}")


if __name__ == "__main__":
    main()
