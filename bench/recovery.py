"""How often does diagnosis find the truth? Random synthetic cases on the quick study
(issue 25), each drawn afresh from its seed (:func:`sensfw.measure.cases.draw`): an effect
and a place drawn from all that fit the shaft model (or, in a quarter of the cases, no
effect) at 25-100 % of its strength, two or three base calibration variables off by 0.6-1.6,
noise 1-5 %, one to three levels from 0.03-0.2 N.

``--study bert`` draws the same kind of cases on the bolted beam's study (its joint and beam
effects, its four calibration variables, the shaker's voltage at 0.05-0.3 V) with a short
record (a 3 s sweep over 85-100 Hz and a 1 s tail).

Each case is diagnosed with every candidate (``sensfw diagnose`` without ``--candidates``)
and the default budget. Printed: the confusion of verdicts, the rate at which the true
hypothesis's calibrated chi2 is within the noise (``chi2 / n <= 1 + 3 sqrt(2 / n)``),
simulations and wall time per case. "The data can tell" when, as issue 25's bar has it,
the true hypothesis at the better of its true values and its calibration beats H0's
calibrated BIC by the verdict's margin (10), whether or not H0 passes the noise's
chi-square test (:func:`sensfw.measure.discrepancy.fits`; the figures say how often it
does in such cases, where an effect's own distortion counts as noise);
then the verdict must name the effect and place (naming it with the same
effect at another place the channels cannot tell apart counts as right), otherwise it must
be "parameters" or "none".

``--method`` chooses the calibration: ``dfols`` (global search + DFO-LS, the default of
``diagnose``), ``local`` (Levenberg-Marquardt from the start values, no global phase:
``diagnose --local``) or ``lm`` (global search + Levenberg-Marquardt).

    python bench/recovery.py --cases 10 --first 0 --out part0.jsonl   # cases 0..9
    python bench/recovery.py --cases 10 --first 10 --out part1.jsonl  # cases 10..19
    python bench/recovery.py --merge part0.jsonl part1.jsonl           # the figures
    python bench/recovery.py --merge new*.jsonl --baseline old*.jsonl  # a change, paired

Runs in parts (each case is one line of its JSONL file, written when it ends), so a long
benchmark fits in several sessions; ``--merge`` prints the figures of any set of parts.
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: drop this folder
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402

import numpy as np  # noqa: E402

from sensfw.measure.compare import NOISE_MODELS, noise_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: the levels a case draws from (N for the quick study, V for the beam)
LEVELS = {"quick": (0.03, 0.05, 0.1, 0.2), "bert": (0.05, 0.1, 0.2, 0.3)}
MARGIN = 10.0
#: --method -> diagnose's (local, global_phase)
METHODS = {"local": ("lm", False), "dfols": ("dfols", True), "lm": ("lm", True)}
#: diagnose's default
DEFAULT_METHOD = "dfols"


def bench_study(name: str, short: bool = False, noise_model: str | None = None):
    """The quick study (``short``: the test suite's 0.15 s chirp at a 2e-5 s step), or the
    bolted beam's study with a short record: a 3 s sweep over 85-100 Hz (the second mode)
    and a 1 s tail instead of 8 s + 8 s. ``noise_model`` sets the study's
    ``[calibration] noise`` (the band errors' noise model; default the study's own)."""
    from sensfw.study import Study

    data = tomllib.loads((ROOT / "studies" / f"{name}.toml").read_text())
    if noise_model is not None:
        data.setdefault("calibration", {})["noise"] = noise_model
    if name == "quick" and short:
        data["excitation"]["duration"] = "0.15 s"
        data["solver"]["step"] = "2e-5 s"
    if name == "bert":
        data["excitation"].update({"f0": "85 Hz", "f1": "100 Hz", "duration": "3 s",
                                   "tail": "1 s"})
        data["excitation"].pop("drive", None)
        for stage in data["stages"]:  # the stages are not run; their bands must fit
            for sc in stage["scorers"]:
                if "band" in sc:
                    sc["band"] = [86.0, 99.0]
    return Study.from_dict(data, f"{name}-short" if short or name == "bert" else name)


def run_case(study, case: dict, method: str, workers: int, log=lambda s: None,
             store: Path | None = None, from_nominal: float | None = None,
             budget_scale: float = 1.0) -> dict:
    from sensfw.measure import cases, discrepancy
    from sensfw.measure.diagnose import default_budget, diagnose
    from sensfw.measure.prepared import load_measurements
    from sensfw.runs import Runner, RunStore

    tmp = Path(tempfile.mkdtemp(prefix="sensfw-recovery-"))
    meas = load_measurements(study, cases.measure(study, case, tmp))
    t0 = time.perf_counter()
    with Runner(RunStore(store or tmp / "runs"), backend="processes",
                workers=workers) as runner:
        local, global_phase = METHODS[method]
        extra = {} if from_nominal is None else {"from_nominal": from_nominal}
        if budget_scale != 1.0:
            extra["budget"] = round(budget_scale * default_budget(len(meas)))
        res = diagnose(study, meas, runner, log=log, local=local, global_phase=global_phase,
                       **extra)
        wall = time.perf_counter() - t0
        rows = {r["hypothesis"]: r for r in res.rows}
        n = res.n_entries
        h0 = rows["parameters"]
        true_row = rows.get(cases.truth(case))
        # the true hypothesis at its true values (not counted in the diagnosis's runs)
        spec, values = cases.true_values(study, case)
        (w,) = res.residuals.evaluate(spec, [values], "truth")
    chi2_truth = float(w @ w) if w is not None else math.inf
    # a candidate left out by the signature classes was not calibrated, but it nests H0
    # (at its neutral values it is H0): its optimum is at most H0's
    k_true = len(values) if case["effect"] else h0["k"]
    chi2_true_cal = true_row["chi2"] if true_row else h0["chi2"]
    where = truth_in_screen(res.rows, cases.truth(case)) if case["effect"] else {}
    row = {**case, "method": method, "verdict": res.verdict, "named": res.named,
           "n_entries": n, "chi2_h0": h0["chi2"], "k_h0": h0["k"], "k_true": k_true,
           "h0_fits_noise": h0["fits_noise"], "chi2_truth": chi2_truth,
           "chi2_true_calibrated": chi2_true_cal,
           "noise_reached": chi2_true_cal / n <= 1 + 3 * math.sqrt(2 / n),
           "truth_fits_noise": discrepancy.fits(w, k_true) if w is not None else False,
           "simulations": res.n_simulations, "by_step": res.simulations_by_step,
           "beyond_budget": res.criteria.get("beyond_budget", 0),
           "wall_s": wall, "budget_scale": budget_scale, **where}
    return judged(row)


def judged(row: dict) -> dict:
    """The row with ``can_tell`` and ``outcome`` by the bar's definition: the data can tell
    when the true hypothesis, at the better of its true values and its calibration, beats
    H0's calibrated BIC by the verdict's margin, whether or not H0 passes the noise's
    chi-square test (``can_tell_gated`` also asks that it does not)."""
    from sensfw.measure import cases, discrepancy

    n = row["n_entries"]
    k0 = row.get("k_h0", 4 if str(row.get("study", "")).startswith("bert") else 3)
    k = row.get("k_true", k0 + len(row["params"]))
    best = min(row["chi2_truth"], row["chi2_true_calibrated"])
    tell = bool(row["effect"]) and best + k * math.log(n) < row["chi2_h0"] + k0 * math.log(n) \
        - MARGIN
    # rows written before h0_fits_noise was: the test from H0's chi2 alone
    fits = row.get("h0_fits_noise", discrepancy.fits(np.full(n, math.sqrt(row["chi2_h0"] / n)),
                                                     k0))
    return {**row, "can_tell": tell, "can_tell_gated": tell and not fits,
            "outcome": cases.outcome(row, row["named"], row["verdict"], tell)}


def truth_in_screen(rows: list[dict], truth: str) -> dict:
    """Where the true candidate went in the screen: pruned by the signature classes, its
    rank by first look, whether it had a second look (and its rank there), whether it was
    calibrated on the screening level and at every level."""
    screened = [r for r in rows if r["effect"] is not None and r["screen"]]
    row = next((r for r in rows if r["hypothesis"] == truth), None)
    if row is None:
        return {"truth_stage": "pruned", "candidates": len(screened)}
    s = row["screen"] or {}
    if not s:
        return {"truth_stage": "not screened", "candidates": len(screened)}
    first = sorted(screened, key=lambda r: r["screen"].get("first_look", math.inf))
    second = sorted((r for r in screened if "predicted" in r["screen"]),
                    key=lambda r: r["screen"].get("score", math.inf))
    names = [r["hypothesis"] for r in second]
    stage = ("calibrated" if row["n_points"] else "calibrated on the level"
             if "calibrated" in s else "second look" if truth in names else "first look")
    return {"truth_stage": stage, "candidates": len(screened),
            "truth_first_rank": [r["hypothesis"] for r in first].index(truth) + 1,
            "truth_second_rank": names.index(truth) + 1 if truth in names else None,
            "second_looked": len(names)}


def summary(rows: list[dict]) -> None:
    by = {}
    for r in map(judged, rows):
        scale = r.get("budget_scale", 1.0)
        drawn = r.get("drawn") or {}
        unusual = {k: v for k, v in drawn.items()
                   if tuple(v) != {"noise": (0.01, 0.05), "factors": (0.6, 1.6)}.get(k)}
        by.setdefault(f"{r.get('study', 'quick')}, method {r['method']}" + (
            f", budget x{scale:g}" if scale != 1.0 else "") + (
            f", noise model {r['noise_model']}" if r.get("noise_model", "scatter") != "scatter"
            else "") + "".join(
            f", {k} {v[0]:g}-{v[1]:g}" for k, v in unusual.items()), []).append(r)
    for key, rs in by.items():
        print(f"{key}: {len(rs)} cases (rates with their 95 % Wilson interval)")
        counts: dict = {}
        for r in rs:
            counts[r["outcome"]] = counts.get(r["outcome"], 0) + 1
        for k, v in sorted(counts.items()):
            print(f"  {k:28s} {v}")
        tell = [r for r in rs if r["effect"] and r["can_tell"]]
        gated = [r for r in tell if not r["can_tell_gated"]]
        cannot = [r for r in rs if r["effect"] and not r["can_tell"]]
        none = [r for r in rs if not r["effect"]]

        def right(r):
            return r["outcome"] == "right"

        def rate(xs, ok):
            hit = sum(map(ok, xs))
            lo, hi = wilson(hit, len(xs))
            return (f"{hit}/{len(xs)} = {100 * hit / max(len(xs), 1):.0f} % "
                    f"[{100 * lo:.0f}-{100 * hi:.0f}]")

        print(f"  true hypothesis within the noise: {rate(rs, lambda r: r['noise_reached'])}"
              " (bar >= 95 %)")
        # where even the true values miss the noise (the model's own scatter), the noise
        # is out of reach: did the calibration get as low as the truth (within 3 sd of a
        # chi-square's spread) or to the noise?
        def as_low(r):
            return r["noise_reached"] or r["chi2_true_calibrated"] <= \
                r["chi2_truth"] + 3 * math.sqrt(2 * r["n_entries"])

        print("  true hypothesis calibrated to the noise or to its true values' chi2: "
              f"{rate(rs, as_low)}")
        print(f"  data can tell -> effect and place named: "
              f"{rate(tell, right)} (bar >= 90 %)")
        print(f"    of which H0 passes the noise's chi-square test: {len(gated)}, named "
              f"{sum(map(right, gated))}; among the others, named "
              f"{rate([r for r in tell if r['can_tell_gated']], right)}")
        print(f"  data cannot tell -> parameters/none: "
              f"{rate(cannot, lambda r: r['outcome'] == 'correct (cannot tell)')} (bar >= 95 %)")
        print(f"  no effect -> false discoveries: "
              f"{rate(none, lambda r: r['outcome'] == 'false discovery')} (bar <= 5 %)")
        sims = [r["simulations"] for r in rs]
        wall = [r["wall_s"] for r in rs if not r.get("store")]
        print(f"  simulations per case: median {np.median(sims):.0f} (bar <= 250), max "
              f"{max(sims)}; " + (f"wall per case: median {np.median(wall):.0f} s (bar <= "
                                  f"240 s), max {max(wall):.0f} s" if wall else "")
              + (f" ({len(rs) - len(wall)} case(s) with a shared run store: wall not "
                 "counted)" if len(wall) < len(rs) else ""))
        steps = [r["by_step"] for r in rs if r.get("by_step")]
        if steps:  # where they go: the mean per case of each step's simulations
            names = sorted({k for s in steps for k in s}, key=lambda k: -sum(
                s.get(k, 0) for s in steps))
            print("    by step (mean per case): " + ", ".join(
                f"{k} {sum(s.get(k, 0) for s in steps) / len(steps):.0f}" for k in names))


def wilson(hit: int, n: int) -> tuple[float, float]:
    """The 95 % Wilson score interval of a rate ``hit / n`` (Wilson 1927; Brown, Cai &
    DasGupta 2001 recommend it for small ``n``): over 80 cases a rate of 94 % is known to
    about +-5 points, so two runs a case or two apart differ by chance as often as not."""
    from statsmodels.stats.proportion import proportion_confint

    if n == 0:
        return 0.0, 1.0
    lo, hi = proportion_confint(hit, n, alpha=0.05, method="wilson")
    return float(lo), float(hi)


#: the lines of the bar compared case by case (:func:`paired`): name -> (the cases it
#: counts, whether a case meets it)
LINES = {
    "true hypothesis within the noise": (lambda r: True, lambda r: r["noise_reached"]),
    "right verdict (named, or parameters/none where right)": (
        lambda r: True, lambda r: r["outcome"] in ("right", "correct",
                                                   "correct (cannot tell)")),
    "data can tell: effect and place named": (
        lambda r: bool(r["effect"]) and r["can_tell"], lambda r: r["outcome"] == "right"),
}


def paired(before: list[dict], after: list[dict]) -> list[dict]:
    """Two runs of the same seeds (a change against its baseline), line by line of the bar:
    the cases either run counts on the line, how many meet it in both, only before, only
    after and in neither, and McNemar's exact test (McNemar 1947; the binomial test of the
    discordant cases, which is all that tells two runs of the same cases apart): the
    probability of a split of the discordant cases at least as uneven as this one if the
    change made no difference. A case the data can tell in one run and not in the other
    (H0 calibrated to another optimum) is counted where the line counts it and missed in
    the other run."""
    from scipy.stats import binomtest

    a = {r["seed"]: judged(r) for r in before}
    b = {r["seed"]: judged(r) for r in after}
    seeds = sorted(set(a) & set(b))
    out = []
    for name, (counts, meets) in LINES.items():
        both = only_a = only_b = neither = 0
        for s in seeds:
            if not (counts(a[s]) or counts(b[s])):
                continue
            ma, mb = counts(a[s]) and meets(a[s]), counts(b[s]) and meets(b[s])
            both += ma and mb
            only_a += ma and not mb
            only_b += mb and not ma
            neither += not (ma or mb)
        k = only_a + only_b
        p = binomtest(only_b, k, 0.5).pvalue if k else 1.0
        out.append({"line": name, "cases": both + only_a + only_b + neither, "both": both,
                    "only_before": only_a, "only_after": only_b, "neither": neither,
                    "p": float(p)})
    return out


def print_paired(before: list[dict], after: list[dict]) -> None:
    """:func:`paired`, printed."""
    seeds = {r["seed"] for r in before} & {r["seed"] for r in after}
    print(f"{len(seeds)} seeds in both runs; per line: cases counted, met in both / only "
          "before / only after / neither, McNemar's exact p")
    for row in paired(before, after):
        print(f"  {row['line']:<54} {row['cases']:>3}: {row['both']:>3} / "
              f"{row['only_before']:>2} / {row['only_after']:>2} / {row['neither']:>2}, "
              f"p = {row['p']:.3f}")


def part_arguments(ap: argparse.ArgumentParser, workers: int = 1) -> None:
    """The arguments every benchmark over these cases shares (this one,
    ``bench/h0_search.py``, ``bench/augment_search.py``): which cases, the workers, the
    parts it runs in (one JSONL line per case) and merges, and the shared run store."""
    ap.add_argument("--cases", type=int, default=10)
    ap.add_argument("--first", type=int, default=0, help="index of the first case")
    ap.add_argument("--seed", type=int, default=2025, help="seed of case 0 (case i: seed+i)")
    ap.add_argument("--workers", type=int, default=workers)
    ap.add_argument("--out", type=Path, default=None, help="append each case to this JSONL")
    ap.add_argument("--merge", type=Path, nargs="*", help="print the figures of these parts")
    ap.add_argument("--store", type=Path, default=None,
                    help="one run store for every case (default: a fresh one per case). "
                    "Runs are keyed by their full specification, so a case run again, with "
                    "another search or after a change, simulates only the points it has "
                    "not run before: simulations per case stay what was asked for, its "
                    "wall time does not")


def read_parts(paths) -> list[dict]:
    """Every case of the JSONL parts ``paths``."""
    return [json.loads(line) for p in paths for line in Path(p).read_text().splitlines()
            if line.strip()]


def append_part(path: Path | None, row: dict) -> None:
    """Append one case to the part ``path`` (nothing without one)."""
    if path:
        with Path(path).open("a") as f:
            f.write(json.dumps(row) + "\n")


def _range(text: str) -> tuple[float, float]:
    lo, hi = (float(x) for x in text.split(","))
    if not 0 < lo <= hi:
        raise argparse.ArgumentTypeError(f"{text!r}: need LO,HI with 0 < LO <= HI")
    return lo, hi


def main() -> None:
    ap = argparse.ArgumentParser()
    part_arguments(ap, workers=2)
    ap.add_argument("--method", choices=list(METHODS), default=DEFAULT_METHOD)
    ap.add_argument("--short", action="store_true", help="quick study: 0.15 s chirp (the "
                    "test suite's)")
    ap.add_argument("--study", choices=["quick", "bert"], default="quick",
                    help="bert: the bolted beam's joint and beam effects, a 3 s sweep")
    ap.add_argument("--verbose", action="store_true")
    ap.add_argument("--from-nominal", type=float, default=None,
                    help="diagnose's from_nominal (coded distance of H0's optimum from the "
                         "nominal values beyond which the first look also starts there; "
                         "'inf': never, as before stop 39)")
    ap.add_argument("--budget-scale", type=float, default=1.0,
                    help="diagnose's budget as this multiple of its default (150 + 50 per "
                         "level): what the rates cost in simulations")
    ap.add_argument("--noise", type=_range, default=None, metavar="LO,HI",
                    help="the noise's range (fraction of each channel's RMS; default "
                         "0.01,0.05): cases unlike those diagnosis was tuned on")
    ap.add_argument("--factors", type=_range, default=None, metavar="LO,HI",
                    help="the base variables' offsets as factors of their nominal values "
                         "(log-uniform; default 0.6,1.6)")
    ap.add_argument("--noise-model", choices=NOISE_MODELS, default=None,
                    help="the study's [calibration] noise: the band errors' noise model "
                         "(default the study's own, scatter)")
    ap.add_argument("--baseline", type=Path, nargs="*",
                    help="with --merge: parts of a baseline run of the same seeds, compared "
                         "case by case (McNemar's exact test per line of the bar)")
    args = ap.parse_args()
    if args.merge:
        summary(read_parts(args.merge))
        if args.baseline:
            print_paired(read_parts(args.baseline), read_parts(args.merge))
        return
    from sensfw.measure import cases

    study = bench_study(args.study, args.short, args.noise_model)
    rows = []
    for i in range(args.first, args.first + args.cases):
        case = cases.draw(study, args.seed + i, LEVELS[args.study],
                          noise=args.noise or cases.NOISE,
                          factors=args.factors or cases.FACTORS)
        case["study"] = study.name
        case["drawn"] = {"noise": list(args.noise or cases.NOISE),
                         "factors": list(args.factors or cases.FACTORS)}
        r = run_case(study, case, args.method, args.workers,
                     log=print if args.verbose else (lambda s: None), store=args.store,
                     from_nominal=args.from_nominal, budget_scale=args.budget_scale)
        r["store"] = str(args.store) if args.store else None
        r["noise_model"] = noise_model(study)
        r["from_nominal"] = args.from_nominal
        truth = f"{case['effect']}@{case['place']}" if case["effect"] else "no effect"
        print(f"case {i} ({truth}; {len(case['levels'])} level(s), noise "
              f"{100 * case['noise']:.1f} %): {r['verdict']} -> {r['outcome']}; true chi2 "
              f"{r['chi2_true_calibrated']:.1f} (at truth {r['chi2_truth']:.1f}) / "
              f"{r['n_entries']}, H0 {r['chi2_h0']:.1f}; {r['simulations']} simulations, "
              f"{r['wall_s']:.0f} s" + (f"; truth {r['truth_stage']} (first look "
              f"{r.get('truth_first_rank')}/{r['candidates']})" if case["effect"] else ""),
              flush=True)
        rows.append(r)
        append_part(args.out, r)
    summary(rows)


if __name__ == "__main__":
    main()
