"""How close does H0's first calibration get to its optimum? The recovery benchmark's cases
(``bench/recovery.py``: the quick study's 0.15 s chirp, case ``i`` drawn from seed ``2025 +
i``), H0 alone ("parameters only", no candidate) calibrated at the diagnosis's budget
(``0.3 * default_budget(levels) // levels`` points) by several searches, each on a fresh
record of runs (the run store only saves simulation time):

- ``surrogate``: design, surrogate search (60 % of the points), DFO-LS from its best: the
  candidates' calibration and diagnosis's H0 (``calibrate``'s before stop 42);
- ``surrogate 30 %``: the same with 30 % for design and search;
- ``design DFO-LS``: the design (``2 d + 1`` points) and DFO-LS from its best two points;
- ``surrogate 30 %, 4x``: four times the points;
- ``two searches``: :func:`sensfw.measure.diagnose.two_searches`, the design's DFO-LS
  then the surrogate search seeded with its runs, each with the points above
  (``sensfw calibrate``'s since stop 42;
  tried as diagnosis's H0 at stop 42 and not kept, RECOVERY.md).

``--calibrate``: at ``sensfw calibrate``'s budget instead (60 points,
:func:`sensfw.measure.recalibrate.default_budget`), the surrogate search (``calibrate``'s
before stop 42) against the two searches with half of the points each.

Printed per search: in how many cases it ended within 5 % and 20 % of the lowest chi2 any
search found for that case, how often above 1.5 times it, and its mean simulations. The
landscape is rough with narrow basins, so the lowest found is an upper bound of H0's
optimum, not the optimum.

    python bench/h0_search.py --cases 20 --first 0 --out h0a.jsonl --store runs
    python bench/h0_search.py --cases 20 --first 20 --out h0b.jsonl --store runs
    python bench/h0_search.py --merge h0a.jsonl h0b.jsonl
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: this folder goes last
HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE] + [str(HERE)]

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import recovery as rec  # noqa: E402

#: search -> (calibrate_hypothesis options, points factor); None: two_searches
SEARCHES = {
    "surrogate": ({"global_share": 0.6}, 1),
    "surrogate 30 %": ({"global_share": 0.3}, 1),
    "design DFO-LS": ({"global_share": 0.0}, 1),
    "surrogate 30 %, 4x": ({"global_share": 0.3}, 4),
    "two searches": (None, 2),  # the points of each search: two_searches halves them
}


def run_case(study, i: int, seed0: int, store: Path | None, workers: int,
             calibrate: bool = False) -> dict:
    from sensfw.measure import cases
    from sensfw.measure.calibration import Coordinates
    from sensfw.measure.diagnose import calibrate_hypothesis, default_budget, two_searches
    from sensfw.measure.hypotheses import Hypothesis, calibration_residuals
    from sensfw.measure.prepared import load_measurements
    from sensfw.measure.recalibrate import default_budget as calibrate_budget
    from sensfw.runs import Runner, RunStore

    case = cases.draw(study, seed0 + i, rec.LEVELS["quick"])
    tmp = Path(tempfile.mkdtemp(prefix="sensfw-h0-"))
    meas = load_measurements(study, cases.measure(study, case, tmp))
    row = {"case": i, "seed": seed0 + i, "effect": case["effect"], "place": case["place"],
           "levels": case["levels"], "chi2": {}, "simulations": {}, "wall_s": {}}
    with Runner(RunStore(store or tmp / "runs"), backend="processes",
                workers=workers) as runner:
        searches = {"surrogate": SEARCHES["surrogate"], "two searches": (None, 1)} \
            if calibrate else SEARCHES
        for name, (opts, factor) in searches.items():
            _, _, space, res = calibration_residuals(study, meas, runner)
            res.nominal()
            points = calibrate_budget(res.n_levels) // res.n_levels if calibrate else \
                int(0.3 * default_budget(res.n_levels)) // res.n_levels
            h0 = Hypothesis(None, "", Coordinates.of(space))
            t0 = time.perf_counter()
            base = {"q": max(2, workers), "local": "dfols"}
            fit = two_searches(res, h0, points * factor, base) if opts is None else \
                calibrate_hypothesis(res, h0, points * factor, **base, **opts)
            row["chi2"][name] = fit.chi2
            row["simulations"][name] = res.n_simulations
            row["wall_s"][name] = time.perf_counter() - t0
        row["n_entries"] = res.entries.size()
    return row


def summary(rows: list[dict]) -> None:
    names = list(rows[0]["chi2"])
    print(f"{len(rows)} cases; chi2 / the lowest any search found for the case")
    print(f"{'search':<22} {'within 5 %':>10} {'within 20 %':>11} {'> 1.5x':>7} "
          f"{'simulations':>11}")
    for name in names:
        r = np.array([row["chi2"][name] / min(row["chi2"].values()) for row in rows])
        sims = np.mean([row["simulations"][name] for row in rows])
        print(f"{name:<22} {int(np.sum(r < 1.05)):>10} {int(np.sum(r < 1.2)):>11} "
              f"{int(np.sum(r > 1.5)):>7} {sims:>11.1f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    rec.part_arguments(ap)
    ap.add_argument("--calibrate", action="store_true",
                    help="at sensfw calibrate's budget: the surrogate search, two searches")
    args = ap.parse_args()
    if args.merge:
        summary(rec.read_parts(args.merge))
        return
    study = rec.bench_study("quick", short=True)
    rows = []
    for i in range(args.first, args.first + args.cases):
        row = run_case(study, i, args.seed, args.store, args.workers, args.calibrate)
        rows.append(row)
        print(f"case {i} (seed {row['seed']}): " + ", ".join(
            f"{k} {v:.4g}" for k, v in row["chi2"].items()), flush=True)
        rec.append_part(args.out, row)
    summary(rows)


if __name__ == "__main__":
    main()
