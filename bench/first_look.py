"""Where does the true candidate rank in the screen's first look, with its middle probe
(what :func:`sensfw.measure.screening.screen` runs) and with the best of all its probes?
An experiment on ``bench/recovery.py``'s cases (issue 25): each case is diagnosed up to
the screen (H0's calibration and the signature classes as the diagnosis has them), then
every candidate runs every probe on the screening level from H0's optimum and, where the
screen would, from the nominal base values; its score is the lowest of the runs' chi2 and
their linearised joint fits (the screen's). Nothing after the first look is run.

    python bench/first_look.py 2031 2047 2050 --store S   # seeds (2025 + case index)

Prints per seed the truth's rank and score both ways and the best four. With ``--store``
(the recovery benchmark's run store) only the probes the diagnosis did not run are
simulated: about two per candidate.
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: drop this folder
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402
import importlib.util  # noqa: E402
import math  # noqa: E402
import tempfile  # noqa: E402

BENCH = Path(__file__).resolve().parent


class _Stop(Exception):
    pass


def _recovery():
    spec = importlib.util.spec_from_file_location("sensfw_bench_recovery",
                                                  BENCH / "recovery.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    return mod


def ranks(seed: int, store: Path | None, workers: int = 2,
          from_nominal: float = 0.25) -> dict[str, dict]:
    """The truth's first-look rank and score with the middle probe and with all probes."""
    import sensfw.measure.diagnose as diagnose
    from sensfw.measure import cases
    from sensfw.measure.prepared import load_measurements
    from sensfw.measure.screening import _linearised, look_origins
    from sensfw.runs import Runner, RunStore

    rec = _recovery()
    study = rec.bench_study("quick", True)
    case = cases.draw(study, seed, rec.LEVELS["quick"])
    truth = cases.truth(case)
    tmp = Path(tempfile.mkdtemp(prefix="sensfw-first-look-"))
    meas = load_measurements(study, cases.measure(study, case, tmp))
    scores: dict[str, dict[str, float]] = {"middle": {}, "all": {}}

    def screen(res, h0, hyps, h0_cmp, level, calibrate_on, budget, **kw):
        J0 = h0.fit.jacobian[res.level_slices()[level]]
        origins = look_origins(res, h0, level, kw.get("from_nominal", from_nominal))
        for h in hyps:
            probes = h.effect.probes(h0_cmp)
            for o in origins:
                ws = res.evaluate(h.effects, [{**o.values, **h.neutral, **p} for p in probes],
                                  f"first look {h.name}", [level])
                for i, w in enumerate(ws):
                    if w is None:
                        continue
                    s = min(float(w @ w), _linearised(o.w, J0, w - o.w, o.z)[0])
                    for key in ("all",) + (("middle",) if i == len(probes) // 2 else ()):
                        scores[key][h.name] = min(scores[key].get(h.name, math.inf), s)
        raise _Stop

    original = diagnose.screen
    diagnose.screen = screen
    try:
        with Runner(RunStore(store or tmp / "runs"), backend="processes",
                    workers=workers) as runner:
            diagnose.diagnose(study, meas, runner)
    except _Stop:
        pass
    finally:
        diagnose.screen = original
    out = {}
    for key, d in scores.items():
        order = sorted(d, key=d.get)
        out[key] = {"rank": order.index(truth) + 1 if truth in order else None,
                    "of": len(order), "score": d.get(truth, math.inf),
                    "best": [(n, d[n]) for n in order[:4]]}
    return {"truth": truth, **out}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("seeds", type=int, nargs="+")
    ap.add_argument("--store", type=Path, default=None)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    for seed in args.seeds:
        r = ranks(seed, args.store, args.workers)
        for key in ("middle", "all"):
            x = r[key]
            best = ", ".join(f"{n} {s:.4g}" for n, s in x["best"])
            print(f"{seed} {r['truth']}: {key:6s} rank {x['rank']} of {x['of']}, "
                  f"score {x['score']:.4g}; best {best}", flush=True)


if __name__ == "__main__":
    main()
