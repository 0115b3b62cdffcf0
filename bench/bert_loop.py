"""The README's worked loop on the UNESP-BERT sweeps, timed step by step (issue 25's bar:
calibrate, then two diagnose/augment rounds, in at most 30 minutes on 2 cores, with the
six-level table no worse than the README's).

Runs the README's commands as written (``sensfw calibrate``, ``diagnose``, ``augment``,
``compare``; the CLI, so what a user runs is what is timed), each in a fresh output folder,
and prints per step its wall time, its simulations and what it found (the calibrated
values, the verdict, the augmented error), then the six-level table of ``compare`` (laser,
80-105 Hz) for the models of the rounds run, and the total against the bar::

    python bench/bert_loop.py --out out/bert-loop               # first round
    python bench/bert_loop.py --out out/bert-loop --rounds 2    # both rounds

A step whose output is already in ``--out`` is read, not run again (its wall time is the
one stored in ``bench_loop.json``), so a loop stopped half-way resumes. The records come
from ``--data`` (default ``$SENSFW_BERT_DATA`` or ``../shared/data/bert`` next to the
repository). Wall times are those of the machine as it is; run it alone for the figures
the bar asks for.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LEVELS = ("0p05", "0p10", "0p15", "0p20", "0p25", "0p30")
FITTED = ("0p05", "0p15", "0p30")
BAR_S = 30 * 60
ROUND1 = ("micro_slip@joint,cubic_stiffness@joint,clearance@joint,damping@joint",
          "micro_slip@joint")
ROUND2 = ("dry_friction@beam1,dry_friction@beam2,friction@clamp,damping@beam1,"
          "added_mass@beam1", "dry_friction@beam1")


def data_dir(arg: str | None) -> Path:
    base = Path(arg or os.environ.get("SENSFW_BERT_DATA") or ROOT.parent / "shared/data/bert")
    sweeps = base / "T5Nm" / "chirp_70_110Hz"
    if not sweeps.is_dir():
        sys.exit(f"bert_loop: no UNESP-BERT sweeps at {sweeps} (--data or $SENSFW_BERT_DATA)")
    return sweeps


class Loop:
    """The steps of the loop, each a ``sensfw`` command with its output folder."""

    def __init__(self, out: Path, sweeps: Path, workers: int):
        self.out, self.sweeps, self.workers = out, sweeps, workers
        self.log_path = out / "bench_loop.json"
        self.times = json.loads(self.log_path.read_text()) if self.log_path.exists() else {}

    def records(self, levels) -> list[str]:
        return [a for lv in levels for a in ("-m", str(self.sweeps / f"level_{lv}"))]

    def step(self, name: str, args: list[str], result: str) -> dict:
        """Run ``sensfw ARGS --out OUT/NAME`` unless ``OUT/NAME/RESULT`` exists; returns
        the result's JSON."""
        folder = self.out / name
        path = folder / result
        if not path.exists():
            cmd = [sys.executable, "-m", "sensfw", *args, "--out", str(folder),
                   "--workers", str(self.workers), "--no-progress"]
            print(f"[{name}] {' '.join(cmd[3:])}", flush=True)
            t0 = time.perf_counter()
            with open(self.out / f"{name}.log", "w") as log:
                done = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
            if done.returncode:
                sys.exit(f"bert_loop: {name} failed (rc {done.returncode}); see "
                         f"{self.out / (name + '.log')}")
            self.times[name] = time.perf_counter() - t0
            self.log_path.write_text(json.dumps(self.times, indent=1))
        return json.loads(path.read_text())


def six_levels(cmp: dict) -> dict[str, tuple[float, float, float]]:
    """Per level: measured and model resonance (Hz) and the laser's FRF error (dB)."""
    rows = {}
    for c in cmp["levels"]:
        res = [r for r in c["resonances"] if r.get("measured_hz") and r.get("model_hz")]
        r = res[0] if res else {"measured_hz": float("nan"), "model_hz": float("nan")}
        rows[f"{c['level']:.2f}"] = (r["measured_hz"], r["model_hz"], c["frf_error_db"]["value"])
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="out/bert-loop")
    ap.add_argument("--data", default=None)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--rounds", type=int, choices=(0, 1, 2), default=1,
                    help="diagnose/augment rounds after the calibration (0: calibrate only)")
    args = ap.parse_args()
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    loop = Loop(out, data_dir(args.data), args.workers)
    fitted, six = loop.records(FITTED), loop.records(LEVELS)
    band = ["--error-band", "80,105"]
    summary = []

    cal = loop.step("cal", ["calibrate", str(ROOT / "studies/bert.toml"),
                            *loop.records(("0p05",))], "calibrate.json")
    summary.append(("calibrate (0.05 V)", "cal", cal["n_simulations"],
                    ", ".join(f"{k} {v:.4g}" for k, v in cal["params"].items())))
    tables = {"linear": six_levels(loop.step("cal-cmp", ["compare", str(out / "cal/study.toml"),
                                                          *six, *band], "compare.json"))}
    study = out / "cal/study.toml"
    rounds = [ROUND1, ROUND2][:args.rounds]
    for i, (candidates, effect) in enumerate(rounds, start=1):
        extra = ["--no-prune"] if i == 2 else []
        diag = loop.step(f"diag{i}", ["diagnose", str(study), *fitted, *extra,
                                      "--candidates", candidates], "diagnose.json")
        summary.append((f"diagnose, round {i}", f"diag{i}", diag["n_simulations"],
                        f"{diag['verdict']} (README: {effect})"))
        aug = loop.step(f"aug{i}", ["augment", str(study), *fitted, "--effect", effect,
                                    "--start-from", str(out / f"diag{i}/diagnose.json")],
                        "augment.json")
        summary.append((f"augment, round {i}", f"aug{i}", aug["n_simulations"],
                        f"chi2 {aug['chi2']:.4g}; " + ", ".join(
                            f"{k} {v:.4g}" for k, v in aug["params"].items())))
        study = out / f"aug{i}/study.toml"
        tables[f"round {i}"] = six_levels(loop.step(f"aug{i}-cmp", ["compare", str(study),
                                                                    *six, *band],
                                                    "compare.json"))

    print("\n| step | simulations | wall (s) | result |\n|---|---|---|---|")
    total = 0.0
    for label, name, sims, what in summary:
        wall = loop.times.get(name, float("nan"))
        total += wall
        print(f"| {label} | {sims} | {wall:.0f} | {what} |")
    print(f"\nthe loop (compare runs not counted): {total:.0f} s = {total / 60:.1f} min "
          f"against the bar's {BAR_S / 60:.0f} min ({total / BAR_S:.2f}x)")
    names = list(tables)
    print("\nlaser, 80-105 Hz (resonance: the 1/24-octave Hv FRF's peak); '(fit)': the levels "
          "diagnose and augment fit, the linear model saw 0.05 V only")
    print("\n| level (V) | measured resonance (Hz) | " + " | ".join(
        f"{n} (Hz)" for n in names) + " | " + " | ".join(f"error {n} (dB)" for n in names)
        + " |")
    print("|---" * (2 + 2 * len(names)) + "|")
    for lv in tables["linear"]:
        fit = " (fit)" if lv.replace(".", "p") in FITTED else ""
        meas = tables["linear"][lv][0]
        print(f"| {lv}{fit} | {meas:.2f} | " + " | ".join(
            f"{tables[n][lv][1]:.2f}" for n in names) + " | " + " | ".join(
            f"{tables[n][lv][2]:.2f}" for n in names) + " |")


if __name__ == "__main__":
    main()
