"""Newton's iteration limits for the bolted beam's micro-slip runs: cost and accuracy.

The micro-slip joint's Jenkins sliders are piecewise linear (stuck: a spring; slipping: a
constant force). Where they switch inside a step, Exudyn's modified Newton keeps a Jacobian
of the wrong pattern and converges slowly (contraction 0.3-0.5 per iteration: up to nine
iterations before it renews it), or it diverges into a state where every slider slips and
the residual no longer moves (contraction exactly 1 with fresh Jacobians and full Newton),
and spends its 25 iterations, nearly all with a new Jacobian, before the step is retried at
half the step. This benchmark runs the rig-like record of ``bench/beam_runs.py`` (a linear
sweep 70 -> 110 Hz in 8 s, 8 s of silence, 1024 Hz, generalised-alpha at 1/8192 s) at the
forces of the 0.05, 0.15 and 0.30 V records through the linear model, the micro-slip model
of the README's first round and the micro-slip + dry-friction model of its second
(``tests/measure/test_bert_loop.py``'s values), once per Newton setting, and against a
reference at an eighth of the step (Exudyn's defaults). A run whose modified Newton fails
at some step at every step size the model allows is run again with full Newton (the
model's fallback, slow: a Jacobian per iteration), which the line says. Per model, level
and setting: wall seconds and their ratio to Exudyn's defaults in the same run, Newton
iterations, Jacobians, steps taken (planned 131072 at 1/8192 s for 16 s, less the quiet
tail, plus the retried), and the laser's distance from the reference (RMS relative, and the
largest difference of its spectrum over 80-105 Hz, dB)::

    python bench/beam_newton.py [--levels 2.82,8.46,16.9] [--models linear,micro-slip,dry]
"""

from __future__ import annotations

import sys
from pathlib import Path

# bench/signal.py would shadow the standard library's signal module: this folder goes last
HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != HERE] + [str(HERE)]

import argparse  # noqa: E402  (after the sys.path fix)
import json  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from beam_runs import LINEAR, MICRO_SLIP, distance, record  # noqa: E402

from sensfw.excitation import SampledForce  # noqa: E402
from sensfw.models.base import SolverSettings  # noqa: E402
from sensfw.models.bolted_beam import BoltedBeam, simulation  # noqa: E402

DRY = {"clamp_stiffness": 22445.56, "joint_stiffness": 8772824.7, "damping_ratio": 0.0059576,
       "microslip_force": 887.469, "microslip_exponent": -0.654005,
       "microslip_residual": 0.0138544, "dry_friction_force": 0.518444,
       "dry_friction_stiffness": 10.3357}
MODELS = {"linear": ([], LINEAR), "micro-slip": (["micro_slip"], MICRO_SLIP),
          "dry": (["micro_slip", {"name": "dry_friction", "attach": "beam1"}], DRY)}
#: the settings compared (``simulation.MODIFIED``): Exudyn's defaults first (the baseline,
#: the model's until model version 3), then a Jacobian renewed after three iterations and a
#: step given up after ten (the model's since version 3), and a tighter pair
SETTINGS = {"Exudyn's defaults": {},
            "renew after 3, fail after 10": {"maxModifiedNewtonIterations": 3,
                                             "maxIterations": 10},
            "renew after 2, fail after 8": {"maxModifiedNewtonIterations": 2,
                                            "maxIterations": 8}}


def run(model: BoltedBeam, p: dict, ex, step: float, settings: dict):
    """Laser signal, wall seconds and the run's meta (Newton's counts, steps)."""
    saved = dict(simulation.MODIFIED)
    simulation.MODIFIED.clear()
    simulation.MODIFIED.update({k: v for k, v in settings.items() if k != "divisor"})
    step = step / settings.get("divisor", 1)
    try:
        t0 = time.perf_counter()
        sig = model.simulate(p, ex, SolverSettings(method="GeneralizedAlpha", step=step,
                                                   auto_step=False))
        return sig.channels["Laser"], time.perf_counter() - t0, sig.meta
    finally:
        simulation.MODIFIED.clear()
        simulation.MODIFIED.update(saved)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--levels", default="2.82,8.46,16.9", help="force amplitudes (N)")
    ap.add_argument("--models", default=",".join(MODELS))
    ap.add_argument("--settings", default=None,
                    help="JSON object {label: {Exudyn newton setting: value}} to compare "
                         "with Exudyn's defaults instead of SETTINGS (\"divisor\": n runs it "
                         "at 1/n of the step)")
    ap.add_argument("--reference", type=int, default=8, help="the reference's step divisor")
    ap.add_argument("--json", type=Path, default=None, help="append the rows to this JSONL")
    args = ap.parse_args()
    settings = ({"Exudyn's defaults": {}, **json.loads(args.settings)} if args.settings
                else SETTINGS)
    step = 1.0 / 8192
    for name in args.models.split(","):
        effects, values = MODELS[name]
        model = BoltedBeam(effects=effects)
        p = model.parameters().complete({**model.parameters().nominal(), **values})
        run(model, p, SampledForce(samples=np.zeros(1024), fs=1024.0), step, {})  # warm-up
        for level in (float(x) for x in args.levels.split(",")):
            ex = record(level)
            ref, t_ref, _ = run(model, p, ex, step / args.reference, {})
            print(f"{name} {level:g} N: reference at 1/{args.reference} of the step "
                  f"{t_ref:.1f} s", flush=True)
            base = None
            for label, s in settings.items():
                laser, wall, meta = run(model, p, ex, step, s)
                base = base or wall
                rms, db = distance(laser, ref)
                row = {"model": name, "level_N": level, "settings": label, "wall_s": wall,
                       "speed-up": base / wall, "iterations": meta["newton_iterations"],
                       "jacobians": meta["newton_jacobians"], "steps": meta["steps"],
                       "newton": meta["newton"], "laser_rms_pct": rms, "laser_db": db}
                print(f"  {label:30s} {wall:6.2f} s  x{base / wall:4.2f}  iterations "
                      f"{row['iterations']:7d}  Jacobians {row['jacobians']:7d}  steps "
                      f"{row['steps']:7d}  laser vs reference {rms:.2g} % / {db:.2g} dB"
                      + ("" if meta["newton"] == "modified" else
                         f"  (modified Newton failed: {meta['newton']} Newton)"),
                      flush=True)
                if args.json:
                    with args.json.open("a") as f:
                        f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
