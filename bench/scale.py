"""Scale-out benchmark (issue 7, item 3): runs per minute with 1 and 2 workers for the local
process pool and for Dask (a LocalCluster of worker processes), and the parallel efficiency
(rate with 2 workers / (2 x rate with 1 worker)), each baseline measured in the same run.

    python bench/scale.py [--runs 12] [--duration 0.25]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

# this folder holds bench/signal.py, which would shadow the standard library's signal module
# in the worker processes (they inherit sys.path): drop it
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

from sensfw.excitation import Chirp  # noqa: E402  (after the sys.path fix)
from sensfw.models.base import SolverSettings  # noqa: E402
from sensfw.models.shaft_assembly import PARAMETERS, ShaftAssembly  # noqa: E402
from sensfw.runs import Runner, RunSpec, RunStore  # noqa: E402


def specs(n: int, duration: float, tag: int) -> list[RunSpec]:
    m = ShaftAssembly()
    out = []
    for i in range(n):
        p = PARAMETERS.nominal()
        # distinct runs (no cache hits across configurations): vary the damping slightly
        p["slide_damping"] = 100.0 + i + tag * 0.001
        out.append(RunSpec.create(m, p, Chirp(50, 5000, duration, 20000, 0.1),
                                  SolverSettings()))
    return out


def rate(backend: str, workers: int, runs: list[RunSpec], warm: list[RunSpec]) -> float:
    """Steady-state rate: workers are started and warmed by ``warm`` before timing."""
    with tempfile.TemporaryDirectory() as tmp:
        if backend == "dask":
            from distributed import Client, LocalCluster

            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster, Client(cluster) as client:
                client.run(lambda: __import__("sensfw.models.shaft_assembly"))  # warm import
                runner = Runner(RunStore(tmp), backend="dask",
                                scheduler=cluster.scheduler_address)
                runner.run(warm)
                t0 = time.perf_counter()
                runner.run(runs)
                wall = time.perf_counter() - t0
        else:
            with Runner(RunStore(tmp), backend="processes", workers=workers) as runner:
                runner.run(warm)
                t0 = time.perf_counter()
                runner.run(runs)
                wall = time.perf_counter() - t0
        assert runner.counts.failed == 0, runner.counts
        assert runner.counts.new == len(runs) + len(warm), runner.counts
    return len(runs) / wall * 60.0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=12)
    ap.add_argument("--duration", type=float, default=0.25)
    args = ap.parse_args()
    tag = 0
    for backend in ("processes", "dask"):
        rates = {}
        for workers in (1, 2):
            tag += 1
            warm = specs(workers, 0.02, 100 + tag)
            rates[workers] = rate(backend, workers, specs(args.runs, args.duration, tag), warm)
            print(f"{backend:9s} {workers} worker(s): {rates[workers]:6.1f} runs/min")
        eff = rates[2] / (2 * rates[1])
        print(f"{backend:9s} parallel efficiency on 2 workers: {eff:.0%} (target >= 85 %)")


if __name__ == "__main__":
    main()
