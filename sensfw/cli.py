"""The ``sensfw`` command line (typer + rich).

User errors (study file, measurement file, plugin name, a stage that cannot be analysed) are
printed without a traceback and exit with status 2.

Over 400 lines because it is flat: one typer function per command (their options and the
printing of their results); the work of every command is in the library.
"""

from __future__ import annotations

import contextlib
import functools
import json
import sys
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from .errors import SensfwError

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Which parameters of a nonlinear multibody model matter, and does the "
                       "model agree with the rig?")
console = Console(stderr=True)
out = Console()


Workers = Annotated[int | None, typer.Option(help="worker processes (default: cores)")]
Backend = Annotated[str | None, typer.Option(help="serial | processes | dask")]
Scheduler = Annotated[str | None, typer.Option(help="Dask scheduler tcp://host:port")]
ShowProgress = Annotated[bool, typer.Option(help="show the progress bar")]


def _user_errors(fn):
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except SensfwError as err:
            console.print(f"[bold red]error:[/] {err}", highlight=False, markup=True,
                          soft_wrap=True)
            raise typer.Exit(code=2) from None
        except KeyboardInterrupt:
            console.print("[yellow]interrupted; finished runs are kept in the run store[/]")
            raise typer.Exit(code=130) from None
    return wrapper


class RichProgress:
    """Runs done/failed with ETA, one bar per batch of runs."""

    def __init__(self, enabled: bool = True):
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self.enabled = enabled
        self._progress = Progress(
            TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("[red]{task.fields[failed]} failed"),
            TextColumn("cached {task.fields[cached]}"),
            TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
            console=console, disable=not enabled, transient=False)
        self._task = None

    def start(self, label: str, total: int, cached: int) -> None:
        if not self._progress.live.is_started:
            self._progress.start()
        self._task = self._progress.add_task(label, total=total, completed=cached, failed=0,
                                             cached=cached)

    def advance(self, ok: bool) -> None:
        task = self._progress.tasks[self._task]
        self._progress.update(self._task, advance=1,
                              failed=task.fields["failed"] + (0 if ok else 1))

    def stop(self) -> None:
        pass

    def close(self) -> None:
        if self._progress.live.is_started:
            self._progress.stop()


def _runner(study, out_dir: Path, workers, backend, scheduler, retry_failed=False,
            progress=True):
    from .runs import Runner, RunStore

    ex = study.spec.execution
    return Runner(store=RunStore(out_dir / "runs"),
                  backend=backend or ("dask" if scheduler else ex.backend),
                  workers=workers or ex.workers, scheduler=scheduler or ex.scheduler,
                  progress=RichProgress(progress), retry_failed=retry_failed)


@app.command()
@_user_errors
def run(
    study_file: Annotated[Path, typer.Argument(help="study TOML file")],
    out_dir: Annotated[Path, typer.Option("--out", "-o", help="output folder")] = Path("out"),
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    dry_run: Annotated[bool, typer.Option("--dry-run", help="print the plan, run nothing")] = False,
    retry_failed: Annotated[bool, typer.Option(help="recompute runs that failed before")] = False,
    report: Annotated[bool, typer.Option(help="write report.html")] = True,
    progress: ShowProgress = True,
) -> None:
    """Run a study: screen, design of experiments, Eq. 18 regression, report."""
    from .pipeline import plan, results_json, run_study
    from .study import Study

    study = Study.load(study_file)
    if dry_run:
        table = Table(title=f"plan of study {study.name!r}")
        for col in ("stage", "design", "variables", "runs", "scorers", "surrogates"):
            table.add_column(col)
        total = 0
        for p in plan(study):
            total += p["n_runs"]
            table.add_row(p["stage"], p["design"], p["variables"], str(p["n_runs"]),
                          ", ".join(p["scorers"]), ", ".join(p["surrogates"]))
        out.print(table)
        out.print(f"at most {total} runs (+1 nominal reference); cached runs are not recomputed")
        return
    out_dir.mkdir(parents=True, exist_ok=True)
    _keep_study_file(study_file, out_dir)
    runner = _runner(study, out_dir, workers, backend, scheduler, retry_failed, progress)
    t0 = time.perf_counter()
    try:
        result = run_study(study, runner, log=lambda s: console.print(f"[cyan]{s}"))
    finally:
        runner.progress.close()
        runner.close()
    data = results_json(result)
    (out_dir / "results.json").write_text(json.dumps(data, indent=1, sort_keys=False))
    (out_dir / "timing.json").write_text(json.dumps(
        {"wall_s": time.perf_counter() - t0, "runs": runner.counts.as_dict()}, indent=1))
    if report:
        from .report.study import write_study_report

        write_study_report(result, out_dir / "report.html")
    c = runner.counts
    out.print(f"study {study.name!r}: {c.total} runs ({c.new} new, {c.cached} cached, "
              f"{c.failed} failed) in {time.perf_counter() - t0:.1f} s -> {out_dir}")
    for st in data["stages"]:
        if "selected" in st:
            out.print(f"  {st['name']}: selected {', '.join(st['selected'])}")
        for label, per in st.get("validation", {}).items():
            for name, v in per.items():
                adj = "n/a" if v.get("r2_adj") is None else f"{v['r2_adj']:.3f}"
                out.print(f"  {st['name']}: {label} / {name}: R2adj={adj} "
                          f"Q2(LOO)={v['q2_loo']:.3f}")


def _keep_study_file(study_file: Path, out_dir: Path) -> None:
    """Copy the study file into the output folder (``study.toml``), so that the folder
    alone rebuilds its report (``sensfw report DIR``)."""
    import shutil

    target = out_dir / "study.toml"
    if not target.exists() or not target.samefile(study_file):
        shutil.copyfile(study_file, target)


@app.command()
@_user_errors
def report(
    out_dir: Annotated[Path, typer.Argument(help="output folder of `sensfw run`")],
) -> None:
    """Rebuild DIR/report.html from DIR/results.json, DIR/study.toml and the run store,
    without simulating (analyses and surrogates are refitted to the stored scores)."""
    from .pipeline import load_result
    from .report.study import write_study_report

    t0 = time.perf_counter()
    result = load_result(out_dir)
    path = write_study_report(result, out_dir / "report.html")
    out.print(f"-> {path} ({time.perf_counter() - t0:.1f} s, no simulation)")


@app.command()
@_user_errors
def simulate(
    study_file: Annotated[Path, typer.Argument(help="study TOML file")],
    out_file: Annotated[Path, typer.Option(
        "--out", "-o", help="measurement file to write: .csv (one per level) or .uff (all "
                            "levels in one file)")],
    set_: Annotated[list[str] | None, typer.Option("--set", help="NAME=VALUE (paper units)")]
    = None,
    effect: Annotated[list[str] | None, typer.Option(
        help="NAME[@PLACE][:PARAM=VALUE,...] hidden physical effect")] = None,
    noise: Annotated[float, typer.Option(help="noise std as a fraction of each RMS")] = 0.0,
    seed: Annotated[int, typer.Option(help="noise seed")] = 0,
    amplitude: Annotated[float | None, typer.Option(help="excitation level (N, or V)")] = None,
    levels: Annotated[str | None, typer.Option(
        help="several levels, e.g. 0.1,0.3,1.0 (one file per level, or one UFF)")] = None,
    excitation: Annotated[str | None, typer.Option(
        help="log_chirp | linear_sweep | random | stepped_sine (default: the study's)")]
    = None,
    offset: Annotated[float, typer.Option(help="DC offset on the force, fraction of the "
                                               "level")] = 0.0,
    drift: Annotated[float, typer.Option(help="slow drift of the applied force amplitude, "
                                              "e.g. 0.2 for +-20 %")] = 0.0,
    delay: Annotated[float, typer.Option(help="pre-trigger delay (s)")] = 0.0,
    channel_gain: Annotated[float | None, typer.Option(
        help="record the amplifier voltage instead of the force: shaker gain in N/V")] = None,
) -> None:
    """Simulate one configuration and write it as a rig would record it (synthetic data)."""
    from .excitation import KINDS
    from .measure.io import write_csv, write_uff
    from .measure.synthetic import Rig, synthesize
    from .study import Study

    study = Study.load(study_file)
    sets = {}
    for item in set_ or []:
        key, sep, val = item.partition("=")
        if not sep:
            raise SensfwError(f"--set {item!r}: expected NAME=VALUE")
        try:
            sets[key.strip()] = float(val)
        except ValueError:
            raise SensfwError(f"--set {item!r}: expected NAME=VALUE with a number") from None
    if excitation is not None and (excitation not in KINDS or excitation == "sampled"):
        raise SensfwError(f"--excitation {excitation!r}: use one of log_chirp, linear_sweep, "
                          "random, stepped_sine")
    if levels and amplitude is not None:
        raise SensfwError("give --amplitude or --levels, not both")
    try:
        values = [float(v) for v in levels.split(",")] if levels else [amplitude]
    except ValueError:
        raise SensfwError(f"--levels {levels!r}: expected numbers separated by commas") \
            from None
    if any(v is not None and not v > 0 for v in values):
        raise SensfwError(f"--levels {levels!r}: levels must be positive")
    records = []
    for i, level in enumerate(values):
        rig = Rig(noise=noise, offset=offset, drift=drift, delay=delay, gain=channel_gain,
                  seed=seed + i)
        sig, info = synthesize(study, sets, effect or [], amplitude=level,
                               excitation=excitation, rig=rig)
        records.append((sig, info))
    out_file.parent.mkdir(parents=True, exist_ok=True)
    meta = {"source": "sensfw simulate", "excitation": excitation or study.excitation.kind,
            "effects": [e for e in effect or []], "noise": noise, "offset": offset,
            "drift": drift, "delay": delay}
    if out_file.suffix.lower() in (".uff", ".unv"):
        write_uff(out_file, [(sig, info["amplitude"]) for sig, info in records])
        written = [out_file]
    else:
        written = []
        for sig, info in records:
            path = out_file if len(records) == 1 else \
                out_file.with_name(f"{out_file.stem}_{info['amplitude']:g}{out_file.suffix}")
            written.append(write_csv(path, sig, level=info["amplitude"], meta=meta))
    paths = written * len(records) if len(written) == 1 else written
    for (sig, info), path in zip(records, paths, strict=True):
        out.print(f"wrote {path} ({len(sig.t)} samples at {sig.fs:g} Hz, {info['excitation']}"
                  f", level {info['amplitude']:g} {info['unit']}, noise {noise:g})")


@contextlib.contextmanager
def _running(study, out_dir: Path, workers, backend, scheduler, progress):
    """A Runner on ``out_dir/runs``; its progress bar and workers are closed on exit."""
    out_dir.mkdir(parents=True, exist_ok=True)
    runner = _runner(study, out_dir, workers, backend, scheduler, progress=progress)
    try:
        yield runner
    finally:
        runner.progress.close()
        runner.close()


def _json(path: Path, data) -> None:
    from .pipeline import _jsonable

    path.write_text(json.dumps(_jsonable(data), indent=1))


Measured = Annotated[list[Path], typer.Option("--measured", "-m",
                                              help="measurement file(s) (.csv or .uff)")]


@app.command()
@_user_errors
def compare(
    study_file: Annotated[Path, typer.Argument(help="study TOML file")],
    measured: Measured,
    out_dir: Annotated[Path, typer.Option("--out", "-o")] = Path("out/compare"),
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """See where the model fails: FRF error per band, resonances, harmonics, THD, levels."""
    from .measure.compare import compare_measurements
    from .measure.session import load_measurements
    from .report.measure import write_compare_report
    from .study import Study

    study = Study.load(study_file)
    meas = load_measurements(study, [str(m) for m in measured])
    for m in meas:
        for note in m.notes:
            if "not the study's" in note:
                console.print(f"[yellow]notice:[/] {m.file}: {note}", highlight=False)
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        result = compare_measurements(study, meas, runner)
    _json(out_dir / "compare.json", result.to_dict())
    write_compare_report(study, result.levels, result.pairs, result.amplitude, result.notes,
                         out_dir / "report.html")
    for c in result.levels:
        thd = "" if c.thd_model is None else \
            f"; THD model {c.thd_model:.2f} % vs measured {c.thd_measured:.2f} %"
        out.print(f"level {c.level:.3g} {c.unit}: FRF error {c.frf_rms_db:.2f} dB RMS "
                  f"(noise floor {c.noise_floor_db:.2f} dB){thd}")
    if result.amplitude:
        for line in result.amplitude["summary"]:
            out.print("  " + line)
    out.print(f"-> {out_dir}/compare.json, {out_dir}/report.html")


@app.command()
@_user_errors
def diagnose(
    study_file: Annotated[Path, typer.Argument(help="study TOML file")],
    measured: Measured,
    out_dir: Annotated[Path, typer.Option("--out", "-o")] = Path("out/diagnose"),
    candidates: Annotated[str | None, typer.Option(
        help="comma-separated effect names (default: every registered effect)")] = None,
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Which physical effect does the model lack? Calibrate each candidate, rank by BIC."""
    from .measure.diagnose import Evaluator
    from .measure.diagnose import diagnose as run_diagnose
    from .measure.session import Variant, load_measurements
    from .report.measure import write_diagnose_report
    from .study import Study

    study = Study.load(study_file)
    meas = load_measurements(study, [str(m) for m in measured])
    t0 = time.perf_counter()
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        names = [c.strip() for c in candidates.split(",")] if candidates else None
        result = run_diagnose(study, meas, runner, names,
                              log=lambda s: console.print(f"[cyan]{s}"))
        ev = Evaluator(study, meas, runner)
        base_cmp = ev.comparisons([Variant()], "baseline")[0]
        best_cmp = None
        if result["ranking"]:
            top = result["ranking"][0]
            best_cmp = ev.comparisons([Variant.of([{"name": top["effect"],
                                                     "attach": top["attach"]}],
                                                   top["params"])], "best")[0]
    result["wall_s"] = time.perf_counter() - t0
    _json(out_dir / "diagnose.json", result)
    write_diagnose_report(study, result, base_cmp, best_cmp, out_dir / "report.html")
    out.print(f"verdict: {result['verdict']}  ({result['n_simulations']} simulations, "
              f"{result['wall_s']:.0f} s)")
    for r in result["ranking"][:5]:
        out.print(f"  {r['effect']:18s} error {r['error_before']:.3f} -> {r['error_after']:.3f}"
                  f" dB, dBIC {r['delta_bic']:+.1f}")
    out.print(f"-> {out_dir}/diagnose.json, {out_dir}/report.html")


def _diagnosed_values(path: Path, name: str, attach: str) -> tuple[dict, str]:
    """The calibrated values and attach point of effect ``name`` in a diagnose.json."""
    try:
        ranking = json.loads(path.read_text()).get("ranking", [])
        rows = [r for r in ranking
                if r.get("effect") == name and (not attach or r.get("attach") == attach)]
    except (OSError, ValueError, AttributeError) as err:
        raise SensfwError(f"{path}: not a readable diagnose.json ({err})") from None
    if not rows:
        raise SensfwError(f"{path}: no ranking entry for effect {name!r}")
    if not isinstance(rows[0].get("params"), dict) or not rows[0].get("attach"):
        raise SensfwError(f"{path}: the entry for {name!r} lacks 'params' or 'attach'")
    return rows[0]["params"], rows[0]["attach"]


@app.command()
@_user_errors
def augment(
    study_file: Annotated[Path, typer.Argument(help="study TOML file")],
    measured: Measured,
    effect: Annotated[str, typer.Option(help="effect to add, NAME[@ATTACH]")],
    out_dir: Annotated[Path, typer.Option("--out", "-o")] = Path("out/augment"),
    start_from: Annotated[Path | None, typer.Option(
        help="diagnose.json: start from the values diagnose found for this effect")] = None,
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Add a physical effect, calibrate it, write the augmented study and the error path."""
    from .measure.diagnose import augment as run_augment
    from .measure.session import load_measurements
    from .plugins import effects
    from .report.measure import write_augment_report
    from .study import Study
    from .studyfile import add_effect

    study = Study.load(study_file)
    meas = load_measurements(study, [str(m) for m in measured])
    name, _, attach = effect.partition("@")
    start = None
    if start_from is not None:
        start, attach = _diagnosed_values(start_from, name, attach)
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        result = run_augment(study, meas, runner, name, attach or None, start=start,
                             log=lambda s: console.print(f"[cyan]{s}"))
    declared = {p.name: p for p in effects.get(name)().parameters()}
    calibrated = {k: {"min": declared[k].min, "nominal": float(v), "max": declared[k].max}
                  for k, v in result["params"].items()}
    note = (f"[augmented with {name}, calibrated against "
            f"{', '.join(m.file for m in meas)}]")
    text = add_effect(study_file.read_text(encoding="utf-8"), name, result["attach"],
                      calibrated, note)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "study.toml").write_text(text, encoding="utf-8")
    Study.load(out_dir / "study.toml")  # the augmented file must itself be valid
    _json(out_dir / "augment.json", result)
    write_augment_report(study, result, out_dir / "report.html")
    for t in result["trajectory"]:
        out.print(f"  {t['step']:13s} error {t['error']:.3f} dB")
    out.print(f"-> {out_dir}/study.toml, {out_dir}/augment.json, {out_dir}/report.html")


@app.command("compare-designs")
@_user_errors
def compare_designs_cmd(
    study_file: Annotated[Path, typer.Argument(help="study TOML file")],
    designs: Annotated[str, typer.Option(help="comma-separated design names")] =
    "oat,morris,definitive_screening,fractional_factorial,lhs",
    option: Annotated[list[str] | None, typer.Option(
        help="design option DESIGN.KEY=VALUE, e.g. morris.trajectories=4")] = None,
    reference_runs: Annotated[int | None, typer.Option(
        help="runs of the reference Latin hypercube (default 10 per variable)")] = None,
    reference_surrogate: Annotated[str, typer.Option()] = "gaussian_process",
    out_dir: Annotated[Path, typer.Option("--out", "-o")] = Path("out/designs"),
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Compare design strategies on the study's screening stage against a Sobol' reference."""
    from .analysis.compare_designs import agreement_table, compare_designs
    from .plugins import designs as registry
    from .report.measure import write_designs_report
    from .study import Study

    study = Study.load(study_file)
    names = [d.strip() for d in designs.split(",") if d.strip()]
    for n in names:
        registry.get(n)
    opts: dict[str, dict] = {}
    for item in option or []:
        key, sep, val = item.partition("=")
        dname, dot, oname = key.partition(".")
        if not (sep and dot):
            raise SensfwError(f"--option {item!r}: expected DESIGN.KEY=VALUE")
        try:
            value = json.loads(val)
        except json.JSONDecodeError:
            value = val
        opts.setdefault(dname, {})[oname] = value
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        result = compare_designs(study, runner, names, opts, reference_runs,
                                 reference_surrogate, log=lambda s: console.print(f"[cyan]{s}"))
    _json(out_dir / "designs.json", result)
    write_designs_report(study, result, out_dir / "designs.html")
    out.print(agreement_table(result).to_string())
    out.print(f"reference Q2 (k-fold) {result['reference']['q2_kfold']:.3f}; fewest runs to "
              f"the reference top-{result['top_k']}: "
              f"{result['fewest_runs_to_reference_top_k']}")
    out.print(f"-> {out_dir}/designs.json, {out_dir}/designs.html")


@app.command()
@_user_errors
def validate(study_file: Annotated[Path, typer.Argument(help="study TOML file")]) -> None:
    """Check a study file and print its plan."""
    from .study import Study

    study = Study.load(study_file)
    out.print(f"study {study.name!r} is valid: model {study.spec.model.name}, "
              f"{len(study.variable_names())} design variables, {len(study.stages)} stages")


@app.command()
@_user_errors
def plugins() -> None:
    """List every registered plugin with its origin."""
    from .plugins import ALL

    table = Table(title="sensfw plugins")
    table.add_column("kind")
    table.add_column("name")
    table.add_column("origin")
    for kind, reg in ALL.items():
        for name in reg.names():
            table.add_row(kind, name, reg.origin(name))
    out.print(table)


@app.command()
@_user_errors
def places(
    model: Annotated[str, typer.Argument(help="model name (see `sensfw plugins`)")] =
    "shaft_assembly",
) -> None:
    """The places of a model where effects can attach, and the effects that fit each."""
    from .models.places import fitting_places
    from .plugins import effects, models

    places_ = models.get(model)().places()
    if not places_:
        out.print(f"model {model!r} declares no places")
        return
    fits: dict[str, list[str]] = {name: [] for name in places_}
    for name in effects.names():
        for place in fitting_places(places_, effects.get(name)):
            fits[place].append(name)
    table = Table(title=f"places of {model}")
    for col in ("place", "kind", "description", "effects that fit"):
        table.add_column(col)
    for name, pl in places_.items():
        table.add_row(name, pl.kind, pl.description, ", ".join(fits[name]))
    out.print(table)


def main() -> None:  # pragma: no cover
    sys.exit(app())
