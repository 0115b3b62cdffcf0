"""Diagnosis cost on the quick study (issue 16): simulations and wall time of ``sensfw
diagnose`` with every registered effect at every place it fits, for

* offsets only: two sensitive base parameters off their nominal values (slide stiffness
  x1.6, friction transition velocities x0.6), no effect, 2 % noise;
* offsets + a flexible mode (1.8 kHz, 2 % damping, 0.03 kg) on the driveshaft.

Budget (the issue's bar): at most 300 simulations and 10 minutes each on 2 cores. The
baseline printed next to each is one simulation of the same model in this process, so
``wall / (simulations x one run / 2 workers)`` is the overhead of everything else.

    python bench/diagnose.py [--workers 2] [--case offsets|mode|both]
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: drop this folder
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OFFSETS = {"slide_stiffness": 7.05e5 * 1.6, "slide_v_friction": 0.6, "slide_v_stiction": 0.06}
CASES = {"offsets": [], "mode": ["flexible_mode@driveshaft:flex_frequency=1800,"
                                 "flex_damping=0.02,flex_mass=0.03"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--case", choices=["offsets", "mode", "both"], default="both")
    ap.add_argument("--verbose", action="store_true", help="print the diagnosis's log")
    args = ap.parse_args()
    from sensfw.measure.diagnose import diagnose
    from sensfw.measure.io import write_csv
    from sensfw.measure.prepared import load_measurements
    from sensfw.measure.synthetic import Rig, synthesize
    from sensfw.runs import Runner, RunStore
    from sensfw.study import Study

    study = Study.load(ROOT / "studies" / "quick.toml")
    t0 = time.perf_counter()
    study.model.simulate(study.parameters.complete(
        {**study.parameters.nominal(), **OFFSETS}), study.excitation, study.solver)
    one = time.perf_counter() - t0
    cases = list(CASES) if args.case == "both" else [args.case]
    for case in cases:
        tmp = Path(tempfile.mkdtemp(prefix=f"sensfw-bench-diagnose-{case}-"))
        sig, _ = synthesize(study, sets=OFFSETS, effects=CASES[case], amplitude=0.1,
                            rig=Rig(noise=0.02, seed=7))
        f = write_csv(tmp / "m.csv", sig, level=0.1)
        t0 = time.perf_counter()
        with Runner(RunStore(tmp / "runs"), backend="processes",
                    workers=args.workers) as runner:
            res = diagnose(study, load_measurements(study, [str(f)]), runner,
                           log=print if args.verbose else (lambda s: None))
        wall = time.perf_counter() - t0
        print(f"{case}: verdict {res.verdict} ({res.reason})")
        print(f"  {res.n_simulations} simulations (bar 300), {wall:.0f} s wall (bar 600 s, "
              f"{args.workers} workers); one simulation {one:.2f} s: overhead x"
              f"{wall / (res.n_simulations * one / args.workers):.2f}")
        truth = {**study.parameters.nominal(), **OFFSETS,
                 "slide_friction_velocity": OFFSETS["slide_v_friction"]}
        rows = [res.rows[0]] + [r for r in res.rows[1:] if r["hypothesis"] == res.verdict]
        for row in rows:
            print(f"  {row['hypothesis']}: chi2 {row['chi2']:.1f}")
            for c in row["calibration"]:
                t = truth.get(c["name"])
                print(f"    {c['name']} = {c['value']:.4g} [{c['interval'][0]:.4g}, "
                      f"{c['interval'][1]:.4g}]" + (f" (truth {t:.4g})" if t else "")
                      + f" {' '.join(c['flags'])}")


if __name__ == "__main__":
    main()
