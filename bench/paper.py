"""The paper's study on this machine (issue 4, item 6): wall time, runs per minute, the
retained variables and the R^2adj of each Eq. 18 fit. The paper needed about 90 min per run
(122 h for the 81 DoE runs); target here: the whole study in under 5 minutes on 2 cores.

    python bench/paper.py [--out DIR] [--workers N]

A fresh output folder is used so that every run is computed (no run-store hits).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="sensfw-paper-"))
    if (out / "runs").exists() and any((out / "runs").iterdir()):
        sys.exit(f"{out}/runs is not empty; give a fresh --out to time every run")
    cmd = [sys.executable, "-m", "sensfw", "run", str(ROOT / "studies" / "paper.toml"),
           "--out", str(out), "--no-progress"]
    if args.workers:
        cmd += ["--workers", str(args.workers)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(proc.stderr)
    data = json.loads((out / "results.json").read_text())
    runs = data["runs"]
    print(f"paper study: {runs['total']} runs ({runs['failed']} failed) in {wall:.1f} s "
          f"= {wall / 60:.2f} min -> {runs['new'] / wall * 60:.1f} runs/min "
          f"(target < 5 min: {'met' if wall < 300 else 'MISSED'}); output in {out}")
    for st in data["stages"]:
        if "selected" in st:
            ranked = sorted(st["sensitivity"].items(), key=lambda kv: -kv[1])
            print(f"  {st['name']}: {st['n_runs']} runs, selected {', '.join(st['selected'])}")
            print("    normalised sensitivity: " + ", ".join(f"{k} {v:.0%}" for k, v in ranked))
        for label, reg in st.get("regression", {}).items():
            print(f"  {st['name']}: {label}: R2 = {reg['r2']:.3f}, R2adj = {reg['r2_adj']:.3f}, "
                  f"Q2(LOO) = {reg['q2']:.3f}, F p = {reg['f_pvalue']:.2g} ({reg['n_obs']} runs)")


if __name__ == "__main__":
    main()
