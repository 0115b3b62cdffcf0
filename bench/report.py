"""`sensfw report DIR` on the quick study (issue 26, item 6): time of the command, and the
surrogate fits a rebuild makes when the DoE also fits `auto`.

    python bench/report.py [--out DIR]

Runs ``studies/quick.toml`` into DIR (once; later calls reuse it) and times
``sensfw report DIR`` as a user does: a fresh process, imports included, wall and CPU
seconds (the CPU time is what the wall time is on an idle machine: the command runs in one
process). Then the same study with ``surrogates = ["eq18", "auto"]`` on its DoE stage is run
into DIR-auto, sharing DIR's run store (no simulation: only the fits and their validation),
and its report is timed the same way. Last, in this process, the surrogate fits of
rebuilding DIR-auto are counted twice: taking each surrogate's validation from
results.json, as ``sensfw report`` does now, and validating again, as it did before (for
`auto` that is its own cross-validation over every candidate inside the validation's
leave-one-out and k-fold refits).
"""

from __future__ import annotations

import sys
from pathlib import Path

# this folder holds bench/signal.py, which would shadow the standard library's signal module
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != Path(__file__).resolve().parent]

import argparse  # noqa: E402  (after the sys.path fix)
import resource  # noqa: E402
import subprocess  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def sensfw(*args: str) -> tuple[float, float]:
    """(wall, CPU) seconds of ``python -m sensfw ARGS``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "sensfw", *args], capture_output=True,
                          text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        sys.exit(proc.stderr)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def with_auto(out: Path) -> Path:
    """DIR-auto: the study with `auto` on the DoE stage, run on DIR's run store."""
    import tomlkit

    dst = out.with_name(out.name + "-auto")
    dst.mkdir(exist_ok=True)
    doc = tomlkit.parse((out / "study.toml").read_text())
    doc["stages"][1]["surrogates"] = ["eq18", "auto"]
    study = dst / "auto.toml"
    study.write_text(tomlkit.dumps(doc))
    if not (dst / "runs").exists():
        (dst / "runs").symlink_to((out / "runs").resolve())
    if not (dst / "results.json").exists():
        wall, cpu = sensfw("run", str(study), "--out", str(dst), "--no-progress",
                           "--no-report")
        print(f"quick study with auto, run on the stored runs: {wall:.1f} s ({cpu:.1f} CPU s)")
    return dst


def count_fits(folder: Path) -> None:
    """Surrogate fits and CPU seconds of rebuilding ``folder``, with and without the
    validation stored in its results.json."""
    import sensfw.pipeline as pipeline
    from sensfw.surrogates import SurrogateBase

    fits: Counter = Counter()
    begin = SurrogateBase._begin_fit

    def counting(self, X, y):
        fits[type(self).__name__] += 1
        return begin(self, X, y)

    SurrogateBase._begin_fit = counting
    run_study = pipeline.run_study
    try:
        for way in ("validation from results.json (now)", "validated again (before)"):
            if way.startswith("validated again"):
                pipeline.run_study = lambda *a, **k: run_study(*a, **{**k, "validated": None})
            fits.clear()
            t0 = time.process_time()
            pipeline.load_result(folder)
            cpu = time.process_time() - t0
            print(f"  rebuild, {way}: {sum(fits.values())} surrogate fits "
                  f"({', '.join(f'{k} {n}' for k, n in sorted(fits.items()))}), "
                  f"{cpu:.1f} CPU s")
    finally:
        SurrogateBase._begin_fit = begin
        pipeline.run_study = run_study


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="sensfw-report-")) / "quick"
    if not (out / "results.json").exists():
        wall, _ = sensfw("run", str(ROOT / "studies" / "quick.toml"), "--out", str(out),
                         "--no-progress", "--no-report")
        print(f"quick study run in {wall:.1f} s -> {out}")
    wall, cpu = sensfw("report", str(out))
    print(f"sensfw report (quick study): {wall:.1f} s ({cpu:.1f} CPU s)")
    auto = with_auto(out)
    wall, cpu = sensfw("report", str(auto))
    print(f"sensfw report (quick study, DoE also fits auto): {wall:.1f} s ({cpu:.1f} CPU s)")
    count_fits(auto)


if __name__ == "__main__":
    main()
