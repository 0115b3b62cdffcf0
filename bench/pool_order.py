"""The process pool's order (``sensfw.runs.executor.ProcessPool``: a batch longest first,
Graham's LPT rule) against the order given, in the same run, on batches shaped like a
calibration's points: one run per record, records of unequal cost.

Each point is one batch of three runs of the bolted beam with micro-slip (the first round's
values of the README) on a sampled sweep 84 -> 96 Hz (``--duration`` s) at 3, 8.5 and 17 N,
in that order (the way a calibration lists its levels); ``--points`` batches one after
another through a pool of ``--workers``, once with the pool's order and once in the given
order (a pool whose ``order`` returns the batch as it is), after one warm-up batch each.
Prints the wall time of each, their ratio, and the workers' idle share (1 - the runs'
summed time / (wall x workers))::

    python bench/pool_order.py [--points 8] [--duration 1.0] [--workers 2]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module in the workers: drop it
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

from sensfw.excitation import LinearSweep, SampledForce  # noqa: E402  (after the sys.path fix)
from sensfw.models.base import SolverSettings  # noqa: E402
from sensfw.models.bolted_beam import BoltedBeam  # noqa: E402
from sensfw.runs import RunSpec  # noqa: E402
from sensfw.runs.executor import ProcessPool  # noqa: E402

MICRO_SLIP = {"clamp_stiffness": 50196.56, "joint_stiffness": 9316438.5,
              "damping_ratio": 0.0061782, "microslip_residual": 0.0113271,
              "microslip_force": 766.128, "microslip_exponent": -0.359747}
LEVELS = (3.0, 8.5, 17.0)


class GivenOrder(ProcessPool):
    """The pool as it was: every batch in the order given."""

    def order(self, specs, kinds=None):
        return list(specs)


def point(i: int, duration: float) -> list[RunSpec]:
    m = BoltedBeam(effects=["micro_slip"])
    p = m.parameters().complete({**m.parameters().nominal(), **MICRO_SLIP})
    p["damping_ratio"] *= 1.0 + 1e-3 * i  # distinct runs, the same cost
    ref = {"name": "bolted_beam", "options": {"effects": ["micro_slip"]}}
    out = []
    for level in LEVELS:
        sweep = LinearSweep(84.0, 96.0, duration, 1024.0, level)
        ex = SampledForce(samples=sweep.force(), fs=1024.0, amplitude=level)
        out.append(RunSpec.create(m, p, ex, SolverSettings(method="GeneralizedAlpha",
                                                           step=1 / 8192, auto_step=False),
                                  ref))
    return out


def timed(pool: ProcessPool, points: int, duration: float) -> tuple[float, float]:
    """Wall seconds of ``points`` batches after a warm-up batch, and the runs' summed
    seconds."""
    walls: list[float] = []
    pool.map(point(-1, duration), lambda s, r: None)
    t0 = time.perf_counter()
    for i in range(points):
        pool.map(point(i, duration), lambda s, r: walls.append(r.wall))
    return time.perf_counter() - t0, sum(walls)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=8)
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    rows = {}
    for name, cls in (("given order", GivenOrder), ("longest first", ProcessPool)):
        with cls(args.workers) as pool:
            rows[name] = timed(pool, args.points, args.duration)
    for name, (wall, runs) in rows.items():
        print(f"{name:14s}: {wall:6.1f} s for {args.points} points, runs {runs:6.1f} s, "
              f"idle {100 * (1 - runs / (wall * args.workers)):4.1f} %")
    print(f"given order / longest first: {rows['given order'][0] / rows['longest first'][0]:.2f}")


if __name__ == "__main__":
    main()
