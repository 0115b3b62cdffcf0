"""Study commands: run, report, validate, compare-designs, plugins, places."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..errors import SensfwError
from .common import (
    Backend,
    OutDir,
    Scheduler,
    ShowProgress,
    StudyFile,
    Workers,
    _json,
    _runner,
    _running,
    command,
    option_value,
    out,
    say,
)


@command()
def run(
    study_file: StudyFile,
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
    from ..pipeline import run_study
    from ..study import Study

    study = Study.load(study_file)
    if dry_run:
        _print_plan(study)
        return
    if out_dir.exists() and not out_dir.is_dir():
        raise SensfwError(f"--out {out_dir}: a file of that name exists; give a folder")
    runner = _runner(study, out_dir, workers, backend, scheduler, retry_failed, progress)
    t0 = time.perf_counter()
    try:
        result = run_study(study, runner, log=say, out=out_dir, report=report)
    finally:
        runner.progress.close()
        runner.close()
    c = runner.counts
    out.print(f"study {study.name!r}: {c.total} runs ({c.new} new, {c.cached} cached, "
              f"{c.failed} failed) in {time.perf_counter() - t0:.1f} s -> {out_dir}")
    for st in result.stages:
        if st.selected is not None:
            out.print(f"  {st.name}: selected {', '.join(st.selected)}")
        for label, per in st.validation.items():
            for name, v in per.items():
                adj, q2 = (f"{x:.3f}" if x is not None and math.isfinite(x) else "n/a"
                           for x in (v.get("r2_adj"), v.get("q2_loo")))
                out.print(f"  {st.name}: {label} / {name}: R2adj={adj} Q2(LOO)={q2}")


@command()
def report(
    out_dir: Annotated[Path, typer.Argument(help="output folder of `sensfw run`")],
) -> None:
    """Rebuild DIR/report.html from DIR/results.json, DIR/study.toml and the run store,
    without simulating (analyses and surrogates are refitted to the stored scores)."""
    from ..pipeline import load_result
    from ..report.study import write_study_report

    t0 = time.perf_counter()
    result = load_result(out_dir)
    path = write_study_report(result, out_dir / "report.html")
    out.print(f"-> {path} ({time.perf_counter() - t0:.1f} s, no simulation)")



@command("compare-designs")
def compare_designs_cmd(
    study_file: StudyFile,
    designs: Annotated[str, typer.Option(help="comma-separated design names")] =
    "oat,morris,definitive_screening,fractional_factorial,lhs",
    option: Annotated[list[str] | None, typer.Option(
        help="design option DESIGN.KEY=VALUE, e.g. morris.trajectories=4")] = None,
    reference_runs: Annotated[int | None, typer.Option(
        help="runs of the reference Latin hypercube (default 10 per variable)")] = None,
    reference_surrogate: Annotated[str, typer.Option()] = "gaussian_process",
    out_dir: OutDir = Path("out/designs"),
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Compare design strategies on the study's screening stage against a Sobol' reference."""
    from ..analysis.compare_designs import agreement_table, build_comparison, compare_designs
    from ..report.measure import write_designs_report
    from ..study import Study

    study = Study.load(study_file)
    names = [d.strip() for d in designs.split(",") if d.strip()]
    opts: dict[str, dict] = {}
    for item in option or []:
        key, sep, val = item.partition("=")
        dname, dot, oname = key.partition(".")
        if not (sep and dot):
            raise SensfwError(f"--option {item!r}: expected DESIGN.KEY=VALUE")
        opts.setdefault(dname, {})[oname] = option_value(val)
    build_comparison(study, names, opts, reference_runs, reference_surrogate)  # before any run
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        result = compare_designs(study, runner, names, opts, reference_runs,
                                 reference_surrogate, log=say)
    _json(out_dir / "designs.json", result)
    write_designs_report(study, result, out_dir / "designs.html")
    out.print(agreement_table(result).to_string())
    q2 = result["reference"]["q2_kfold"]
    out.print(f"reference Q2 (k-fold) {'n/a' if q2 is None else f'{q2:.3f}'}; fewest runs to "
              f"the reference top-{result['top_k']}: "
              f"{result['fewest_runs_to_reference_top_k']}")
    out.print(f"-> {out_dir}/designs.json, {out_dir}/designs.html")



def _print_plan(study) -> None:
    """The run count of every stage (``run --dry-run``, ``validate``)."""
    from ..pipeline import plan

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


@command()
def validate(study_file: StudyFile) -> None:
    """Check a study file and print its plan."""
    from ..study import Study

    study = Study.load(study_file)
    out.print(f"study {study.name!r} is valid: model {study.spec.model.name}, "
              f"{len(study.variable_names())} design variables, {len(study.stages)} stages")
    _print_plan(study)


@command()
def plugins() -> None:
    """List every registered plugin with its origin."""
    from ..plugins import ALL

    table = Table(title="sensfw plugins")
    table.add_column("kind")
    table.add_column("name")
    table.add_column("origin")
    for kind, reg in ALL.items():
        for name in reg.names():
            table.add_row(kind, name, reg.origin(name))
    out.print(table)


@command()
def places(
    model: Annotated[str, typer.Argument(help="model name (see `sensfw plugins`)")] =
    "shaft_assembly",
) -> None:
    """The places of a model where effects can attach, and the effects that fit each."""
    from ..models.places import fitting_places
    from ..plugins import effects, models

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


