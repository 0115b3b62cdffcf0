"""Run a study end to end: stage by stage, design -> runs -> scores -> analysis/surrogates.

The paper's three steps are the default study (``studies/paper.toml``): an OAT screen scored
by the FRF scalar selects variables, a 3-level full factorial on them is scored by order
amplitudes and THD, and Eq. 18 is fitted to each score. :func:`run_study` writes the output
folder that :func:`load_result` reads back; the results themselves (:class:`StageResult`,
:func:`results_json`) are in :mod:`sensfw.results`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import AnalysisError, SensfwError
from .evaluate import evaluate, make_scorers, needs_reference, reference_spec
from .models.base import Signals
from .params import DesignSpace
from .results import (  # noqa: F401  (jsonable, results_json: the results' names, here too)
    StageResult,
    StudyResult,
    jsonable,
    keep_study_file,
    results_json,
    write_result,
)
from .runs import RunCounts, RunStore
from .study import StageSpec, Study


def stage_variables(study: Study, stage: StageSpec, done: dict[str, StageResult]) -> list[str]:
    if isinstance(stage.variables, list):
        return list(stage.variables)
    if stage.variables == "all":
        return study.variable_names()
    ref = stage.variables.split(":", 1)[1]
    selected = done[ref].selected or []
    if not selected:
        raise AnalysisError(f"stage {stage.name!r}: stage {ref!r} selected no variables")
    groups = next(s for s in study.stages if s.name == ref).groups
    return [v for g in selected for v in groups.get(g, [g])]


def _select(stage: StageSpec, screening, scores: pd.DataFrame) -> list[str]:
    sel = stage.select
    return list(screening.select(threshold=sel.threshold, max_variables=sel.max_variables))


def _declared_options(name: str) -> set[str]:
    """The options surrogate ``name`` declares (:func:`sensfw.options.options_model`)."""
    from .options import options_model
    from .plugins import surrogates

    return set(options_model(surrogates.get(name)).model_fields)


def _stored_validation(stored: dict | None, est, X) -> dict | None:
    """``stored`` (a surrogate's validation from an earlier ``results.json``) if it is the
    validation of ``est``: its fitted values are ``est``'s predictions at ``X`` (a changed
    option or score gives others), else None."""
    if not stored or "fitted" not in stored:
        return None
    fitted = np.asarray([np.nan if v is None else v for v in stored["fitted"]], float)
    pred = np.asarray(est.predict(X), float)
    if fitted.shape != pred.shape or not np.allclose(fitted, pred, rtol=1e-9, atol=1e-12):
        return None
    return dict(stored)


def fit_surrogates(study: Study, stage: StageSpec, space: DesignSpace, table: pd.DataFrame,
                   scores: pd.DataFrame, result: StageResult,
                   validated: dict | None = None) -> None:
    """Fit every requested surrogate to every score; Eq. 18 statistics go to ``regression``,
    the validation of every surrogate to ``validation``. ``validated`` (score label ->
    surrogate -> validation, from an earlier ``results.json``) is taken instead of validating
    again where it belongs to the same fit (:func:`_stored_validation`): cross-validation
    refits a surrogate k (and up to n) times, and ``auto`` chooses again in every refit."""
    from .analysis.validation import validate
    from .surrogates import make_surrogate

    bounds = {v.name: (v.low, v.high) for v in space.variables}
    for label in scores.columns:
        y = scores[label].to_numpy(dtype=float)
        ok = np.isfinite(y)
        X = table.loc[ok, space.names]
        if ok.sum() < 3:
            result.notes.append(f"{label}: only {ok.sum()} finished runs, no surrogate fitted")
            continue
        if np.ptp(y[ok]) <= 1e-12 * max(np.max(np.abs(y[ok])), 1e-300):
            result.notes.append(f"{label}: the score does not vary over the {ok.sum()} "
                                f"finished runs (every one {y[ok][0]:.6g}): no surrogate "
                                "fitted, nothing depends on the variables")
            continue
        result.surrogates[label] = {}
        result.validation[label] = {}
        for sur in stage.surrogates:
            name, opts = sur.key, sur.options()
            if "bounds" in _declared_options(sur.name) and "bounds" not in opts:
                opts["bounds"] = [bounds[n] for n in space.names]
            try:
                est = make_surrogate(sur.name, **opts).fit(X, y[ok])
            except SensfwError as err:
                result.notes.append(f"{label}/{name}: {err}")
                continue
            result.surrogates[label][name] = est
            stored = _stored_validation((validated or {}).get(label, {}).get(name), est, X)
            result.validation[label][name] = stored or validate(est, X, y[ok],
                                                                seed=study.spec.study.seed)
            if est.summary_ is not None and est.coefficient_table_ is not None \
                    and label not in result.regression:
                result.regression[label] = {
                    "surrogate": name,
                    "options": {k: v for k, v in opts.items() if k != "bounds"},
                    **{k: est.summary_.get(k) for k in ("r2", "r2_adj", "q2", "f_stat",
                                                        "f_pvalue", "n_obs")},
                    "coefficients": jsonable(
                        est.coefficient_table_[["term", "estimate", "se", "t", "p"]]),
                    "coefficients_coded": jsonable(
                        est.coefficient_table_coded_[["term", "estimate", "se", "t", "p"]]),
                }


def confirm(study: Study, stage: StageSpec, space: DesignSpace, runner,
            result: StageResult, scorers: dict, reference: Signals | None) -> None:
    """Confirmation runs: new random points inside the bounds, simulated and compared with
    each surrogate's prediction (error and prediction-interval coverage)."""
    from scipy.stats import qmc

    from .analysis.validation import confirmation

    n = stage.confirmation_runs
    sampler = qmc.LatinHypercube(d=len(space), seed=study.spec.study.seed + 7919)
    table = space.decode(2 * sampler.random(n) - 1)
    table.index = [f"confirm:{i:03d}" for i in range(n)]
    ev = evaluate(study, space, table, runner, scorers, reference,
                  label=f"{stage.name} confirmation")
    for label, per in result.surrogates.items():
        y = ev.scores[label].to_numpy(dtype=float) if label in ev.scores \
            else np.full(n, np.nan)
        ok = np.isfinite(y)
        for name, est in per.items():
            try:
                result.validation[label][name]["confirmation"] = confirmation(
                    est, table.loc[ok, space.names], y[ok])
            except SensfwError as err:
                result.validation[label][name]["confirmation"] = {"error": str(err)}
    if ev.failed:
        result.notes.append(f"{len(ev.failed)} confirmation run(s) failed")


def run_stage(study: Study, stage: StageSpec, runner, done: dict[str, StageResult],
              known: dict | None = None, validated: dict | None = None) -> StageResult:
    """One stage: :func:`~sensfw.evaluate.evaluate` its design, then the design's analysis
    (screening and selection) or the surrogates (+ confirmation runs). ``runner`` is a
    :class:`~sensfw.runs.Runner` or a :class:`~sensfw.runs.StoredRuns`; ``known`` holds
    scores by run key and ``validated`` the stage's surrogate validation
    (:func:`fit_surrogates`) from an earlier ``results.json``."""
    from .designs import make_design

    variables = stage_variables(study, stage, done)
    space = study.space(stage, variables)
    design = make_design(stage.design, **stage.design_options)
    scorers = make_scorers(study, stage)
    ref = reference_spec(study) if needs_reference(scorers) else None
    ev = evaluate(study, space, design, runner, scorers, ref, label=stage.name, known=known)
    table, scores, failed = ev.table, ev.scores, ev.failed
    result = StageResult(spec=stage, space=space, table=table, keys=ev.keys, scores=scores,
                         reference_key=ev.reference_key, failed=failed)
    if failed:
        why = "; ".join(f"{k}: {v.splitlines()[0] if v else v}"
                        for k, v in list(failed.items())[:5])
        if len(failed) >= len(table):
            raise AnalysisError(f"stage {stage.name!r}: all {len(table)} runs failed (each is "
                                f"kept in the run store with its error): {why}")
        result.notes.append(f"{len(failed)} of {len(table)} runs failed and were left out: "
                            + why)
    if stage.select is not None:
        by = _score_column(scores, stage.select.by or stage.scorers[0].key, stage,
                           chosen=stage.select.by is not None)
        result.screening = design.analyze(space, table, scores[by].to_numpy(dtype=float))
        result.notes.extend(result.screening.notes)
        result.selected = _select(stage, result.screening, scores)
    elif not stage.surrogates:
        try:
            by = _score_column(scores, stage.scorers[0].key, stage, chosen=False)
            result.screening = design.analyze(space, table, scores[by].to_numpy(dtype=float))
        except SensfwError as err:
            result.notes.append(f"analysis of {stage.design}: {err}")
    if stage.surrogates:
        fit_surrogates(study, stage, space, table, scores, result, validated)
        if stage.confirmation_runs:
            confirm(study, stage, space, runner, result, scorers, ev.reference)
    return result


def _score_column(scores, by: str, stage, chosen: bool) -> str:
    """The score column a stage's analysis reads: ``by`` itself, or a scorer's one value
    (``label.key``) where it gives several; several and not chosen: the first, by the
    study's ``select.by = "label.key"`` otherwise."""
    if by in scores.columns:
        return by
    cols = [c for c in scores.columns if c.startswith(f"{by}.")]
    if not cols:
        raise AnalysisError(f"stage {stage.name!r}: no score {by!r} (scores: "
                            f"{', '.join(scores.columns)})")
    if len(cols) > 1 and chosen:
        raise AnalysisError(f"stage {stage.name!r}: scorer {by!r} gives several values "
                            f"({', '.join(cols)}): name one, select.by = {cols[0]!r}")
    return cols[0]


def run_study(study: Study, runner=None, log: Callable[[str], None] = lambda s: None,
              known: dict | None = None, *, out: str | Path | None = None,
              report: bool = True, validated: dict | None = None) -> StudyResult:
    """Every stage in order.

    Parameters
    ----------
    runner
        A :class:`~sensfw.runs.Runner` (or :class:`~sensfw.runs.StoredRuns` to rebuild
        without simulating); default, with ``out``: a runner on the run store ``out/runs``
        with the study's ``[execution]`` settings, closed at the end.
    out : path, optional
        The output folder to write, the one :func:`load_result` reads back: the study file
        (``study.toml``) before anything runs, then ``results.json``, ``timing.json`` and,
        with ``report``, ``report.html`` (:func:`write_result`).
    known : dict, optional
        Scores by stage name, then run key, from an earlier ``results.json``
        (:func:`~sensfw.evaluate.score_runs`): per stage, since two stages may give a
        shared run different scores under one label (``rms`` of another channel).
    validated : dict, optional
        Surrogate validation by stage name from an earlier ``results.json``
        (:func:`fit_surrogates`).
    """
    import time

    from .runs import Runner, RunStore

    own = runner is None
    if own:
        if out is None:
            raise SensfwError("run_study needs a runner or an output folder (out=)")
        ex = study.spec.execution
        runner = Runner(store=RunStore(Path(out) / "runs"), backend=ex.backend,
                        workers=ex.workers, scheduler=ex.scheduler)
    if out is not None:
        keep_study_file(study, out)
    t0 = time.perf_counter()
    try:
        done: dict[str, StageResult] = {}
        stages = []
        for stage in study.stages:
            log(f"stage {stage.name}: design {stage.design}")
            try:
                res = run_stage(study, stage, runner, done, (known or {}).get(stage.name),
                                (validated or {}).get(stage.name))
            except Exception as err:  # a bug's crash as much as a user error
                if out is not None and stages:  # the stages that finished are written
                    write_result(StudyResult(study=study, stages=stages, store=runner.store,
                                             counts=runner.counts,
                                             stopped={"stage": stage.name, "error": str(err)
                                                      if isinstance(err, SensfwError) else
                                                      f"{type(err).__name__}: {err}"}),
                                 out, report=report, wall=time.perf_counter() - t0)
                raise
            done[stage.name] = res
            stages.append(res)
            if res.selected is not None:
                log(f"stage {stage.name}: selected {', '.join(res.selected) or '(none)'}")
    finally:
        if own:
            runner.close()
    result = StudyResult(study=study, stages=stages, store=runner.store, counts=runner.counts)
    if out is not None:
        write_result(result, out, report=report, wall=time.perf_counter() - t0)
    return result


def load_result(out_dir: str | Path) -> StudyResult:
    """The :class:`StudyResult` of a finished study, rebuilt from its output folder without
    simulating: the study file copied there (``study.toml``, else the path recorded in
    ``results.json``), the run store ``runs/`` and the scores in ``results.json``. Designs
    are regenerated (deterministic for the study's seed), analyses and surrogates refitted
    to the stored scores (their validation is taken from ``results.json`` where it belongs
    to the same fit); confirmation runs are scored from the store."""
    import json

    from .runs import StoredRuns

    out = Path(out_dir)
    path = out / "results.json"
    if not path.is_file():
        raise SensfwError(f"{out}: no results.json, not the output folder of a finished "
                          f"`sensfw run`: check the folder's name, or run the study with "
                          f"--out {out} first")
    try:
        data = json.loads(path.read_text())
        stages = data["stages"]
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise SensfwError(f"{path}: not a readable results.json ({err})") from None
    study_file = out / "study.toml"
    if not study_file.exists():
        study_file = Path(data.get("study_file") or study_file)
    study = Study.load(study_file)
    known: dict[str, dict[str, dict]] = {}
    now = {stage.name: {sc.key: sc.model_dump(mode="json", exclude_none=True)
                        for sc in stage.scorers} for stage in study.stages}
    for st in stages:  # each stage's own scores: a run two stages share has both
        own = known.setdefault(st["name"], {})
        then = st.get("scorers")  # absent in results written before stop 53: trusted
        same = {lab for lab, spec in (then or {}).items()
                if now.get(st["name"], {}).get(lab) == spec}

        def kept(column: str, then=then, same=same) -> bool:
            """A stored score column whose scorer the study file still has unchanged."""
            return then is None or column.split(".", 1)[0] in same or column in same

        for r in st.get("runs", []):
            own.setdefault(r["key"], {}).update(
                {c: v.get(r["label"]) for c, v in st.get("scores", {}).items()
                 if r["label"] in v and kept(c)})
    validated = {st["name"]: st["validation"] for st in stages if "validation" in st}
    runs = StoredRuns(RunStore(out / "runs"), RunCounts(**data.get("runs", {})))
    stopped = data.get("stopped")
    if stopped is not None:  # a study that stopped: the stages that finished
        spec = study.spec.model_dump(mode="json", exclude_none=True)
        spec["stages"] = spec["stages"][:len(stages)]
        study = Study.from_dict(spec, study.source)
    result = run_study(study, runs, known=known, validated=validated)
    result.stopped = stopped
    return result


def plan(study: Study) -> list[dict]:
    """Run counts of every stage before anything runs (``--dry-run``)."""
    from .designs import make_design

    out = []
    n_selected: dict[str, int] = {}
    for stage in study.stages:
        design = make_design(stage.design, **stage.design_options)
        if isinstance(stage.variables, str) and stage.variables.startswith("selected:"):
            ref = stage.variables.split(":", 1)[1]
            k = n_selected.get(ref, 0)
            names = None
            note = f"up to {k} variables selected by {ref!r}"
        else:
            names = stage_variables(study, stage, {})
            k = len(names)
            note = f"{k} variables"
        if k:
            space = study.space(stage, names if names is not None else
                                study.variable_names()[:k])
            n = design.n_runs(space)
        else:
            n = 0
        if stage.select is not None:
            groups = sorted(map(len, stage.groups.values()), reverse=True)
            most = stage.select.max_variables or (len(groups) if groups else k)
            n_selected[stage.name] = sum(groups[:most]) if groups else most
        out.append({"stage": stage.name, "design": stage.design, "variables": note,
                    "n_runs": int(n), "scorers": [s.key for s in stage.scorers],
                    "surrogates": [s.key for s in stage.surrogates],
                    "confirmation_runs": stage.confirmation_runs})
    return out


