"""Does ``sensfw augment`` calibrate the true effect to its optimum? The recovery
benchmark's cases (``bench/recovery.py``: the quick study's 0.15 s chirp, case ``i`` drawn
from seed ``2025 + i``; the cases without an effect are skipped), each augmented with its
true effect at its true place, without start values (``sensfw augment --effect
NAME@PLACE``: both calibrations global) and the default budget, three times: one search
per calibration (``searches=(1, 1)``, ``augment`` before stop 43), two searches
(:func:`sensfw.measure.diagnose.two_searches`) for the base variables and one for the joint
calibration (``(2, 1)``), two for each (``(2, 2)``). Each augment runs on a fresh record of
runs (the run store only saves simulation time).

Printed per search: how often the joint calibration reaches the noise (``chi2 / n <= 1 + 3
sqrt(2 / n)``, as ``bench/recovery.py``), how often it ends as low as the true values'
chi2 (within 3 standard deviations of a chi-square, ``3 sqrt(2 n)``), how often within 5 %
and 20 % of the lowest chi2 found for the case (either search or the true values), how
often above 1.5 times it, and the mean simulations.

    python bench/augment_search.py --cases 20 --first 0 --out aa.jsonl --store runs
    python bench/augment_search.py --cases 20 --first 20 --out ab.jsonl --store runs
    python bench/augment_search.py --merge aa.jsonl ab.jsonl
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
import time  # noqa: E402

import numpy as np  # noqa: E402
import recovery as rec  # noqa: E402

#: name -> augment's ``searches`` (base variables, joint)
SEARCHES = {"one search": (1, 1), "two for H0": (2, 1), "two each": (2, 2)}


def run_case(study, case: dict, store: Path | None, workers: int) -> dict:
    from sensfw.measure import cases
    from sensfw.measure.augment import augment
    from sensfw.measure.hypotheses import calibration_residuals
    from sensfw.measure.prepared import load_measurements
    from sensfw.runs import Runner, RunStore

    tmp = Path(tempfile.mkdtemp(prefix="sensfw-augment-"))
    meas = load_measurements(study, cases.measure(study, case, tmp))
    row = {"seed": case["seed"], "effect": case["effect"], "place": case["place"],
           "levels": case["levels"], "noise": case["noise"], "chi2": {},
           "simulations": {}, "wall_s": {}}
    with Runner(RunStore(store or tmp / "runs"), backend="processes",
                workers=workers) as runner:
        _, _, _, res = calibration_residuals(study, meas, runner)
        spec, values = cases.true_values(study, case)
        (w,) = res.evaluate(spec, [values], "truth")
        row["chi2_truth"] = float(w @ w) if w is not None else math.inf
        row["n_entries"] = res.entries.size()
        for name, searches in SEARCHES.items():
            t0 = time.perf_counter()
            out = augment(study, meas, runner, case["effect"], case["place"],
                          searches=searches)
            row["chi2"][name] = out["chi2"]
            row["simulations"][name] = out["n_simulations"]
            row["wall_s"][name] = time.perf_counter() - t0
    return row


def summary(rows: list[dict]) -> None:
    names = list(rows[0]["chi2"])
    print(f"{len(rows)} cases with an effect, augmented with it; the joint calibration's chi2")
    print(f"{'search':<14} {'noise':>6} {'as low as truth':>15} {'within 5 %':>10} "
          f"{'within 20 %':>11} {'> 1.5x':>7} {'simulations':>11}")
    for name in names:
        chi2 = np.array([r["chi2"][name] for r in rows])
        n = np.array([r["n_entries"] for r in rows])
        truth = np.array([r["chi2_truth"] for r in rows])
        lowest = np.array([min(min(r["chi2"].values()), r["chi2_truth"]) for r in rows])
        ratio = chi2 / lowest
        noise = chi2 / n <= 1 + 3 * np.sqrt(2 / n)
        as_low = noise | (chi2 <= truth + 3 * np.sqrt(2 * n))
        sims = np.mean([r["simulations"][name] for r in rows])
        print(f"{name:<14} {int(noise.sum()):>6} {int(as_low.sum()):>15} "
              f"{int(np.sum(ratio < 1.05)):>10} {int(np.sum(ratio < 1.2)):>11} "
              f"{int(np.sum(ratio > 1.5)):>7} {sims:>11.1f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    rec.part_arguments(ap)
    args = ap.parse_args()
    if args.merge:
        summary(rec.read_parts(args.merge))
        return
    from sensfw.measure import cases

    study = rec.bench_study("quick", short=True)
    rows = []
    for i in range(args.first, args.first + args.cases):
        case = cases.draw(study, args.seed + i, rec.LEVELS["quick"])
        if not case["effect"]:
            print(f"case {i} (seed {args.seed + i}): no effect, skipped", flush=True)
            continue
        row = {"case": i, **run_case(study, case, args.store, args.workers)}
        rows.append(row)
        print(f"case {i} (seed {row['seed']}, {row['effect']}@{row['place']}, "
              f"{row['n_entries']} entries, truth {row['chi2_truth']:.4g}): " + ", ".join(
                  f"{k} {v:.4g} ({row['simulations'][k]})" for k, v in row["chi2"].items()),
              flush=True)
        rec.append_part(args.out, row)
    if rows:
        summary(rows)


if __name__ == "__main__":
    main()
