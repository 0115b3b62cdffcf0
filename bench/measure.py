"""A three-level ``compare`` on the quick study (issue 13): how long the measurement loop's
first step takes, against the model runs it needs, measured in the same run.

    python bench/measure.py [--workers N]

Three synthetic measurements (0.05, 0.15 and 0.45 N, 2 % noise, a 30 % DC offset, a +-20 %
drift and a 1 ms delay: the rig effects :mod:`sensfw.measure.checks` copes with) are made
first; then ``sensfw compare`` runs on a fresh run store. The baseline is the same three
model runs simulated directly (``model.simulate``), so the printed ratio is compare's
overhead: loading, sweep estimation, alignment, the worker processes, FRFs, order spectra
and the report.
"""

from __future__ import annotations

import sys
from pathlib import Path

# this folder holds bench/signal.py, which would shadow the standard library's signal module
# (subprocess imports it): drop it before anything else is imported
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
LEVELS = (0.05, 0.15, 0.45)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    from sensfw.measure.io import write_csv
    from sensfw.measure.synthetic import Rig, synthesize
    from sensfw.study import Study

    study = Study.load(ROOT / "studies" / "quick.toml")
    tmp = Path(tempfile.mkdtemp(prefix="sensfw-bench-measure-"))
    files = []
    for i, level in enumerate(LEVELS):
        sig, _ = synthesize(study, amplitude=level,
                               rig=Rig(noise=0.02, offset=0.3, drift=0.2, delay=1e-3, seed=i))
        files.append(write_csv(tmp / f"m_{level:g}.csv", sig, level=level))
    # baseline: the three model runs, simulated directly in this process
    t0 = time.perf_counter()
    for level in LEVELS:
        study.model.simulate(study.parameters.nominal(),
                             study.excitation.with_amplitude(level), study.solver)
    direct = time.perf_counter() - t0
    cmd = [sys.executable, "-m", "sensfw", "compare", str(ROOT / "studies" / "quick.toml"),
           *[a for f in files for a in ("-m", str(f))], "--out", str(tmp / "compare"),
           "--no-progress", "--workers", str(args.workers)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(proc.stderr)
    print(proc.stdout.strip())
    print(f"three-level compare on the quick study: {wall:.1f} s wall "
          f"({args.workers} workers); the same three model runs simulated directly: "
          f"{direct:.1f} s; ratio {wall / direct:.2f}")


if __name__ == "__main__":
    main()
