"""Design -> runs -> scores: the one sequence every stage of a study, the design comparison,
the confirmation runs and the measurement loop share.

:func:`evaluate` turns a design (a name with options, a :class:`~sensfw.designs.Design`, or a
ready run table) into run specs, makes sure each has a result in the run store (through a
:class:`~sensfw.runs.Runner`, or :class:`~sensfw.runs.StoredRuns`, which never simulates),
and scores every finished run. Failed runs give NaN rows and an entry in ``failed``.
The measurement loop (:mod:`sensfw.measure.residuals`) makes its runs with the same
pieces: :func:`variant_spec` (the study's model with extra effects, driven as a measurement
says) and :func:`simulate` (specs -> stored runs -> signals or the reasons they failed).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from .errors import AnalysisError, SensfwError
from .excitation import Excitation
from .models.base import Model, Signals
from .params import DesignSpace
from .runs import RunSpec
from .study import StageSpec, Study


@dataclass
class Evaluation:
    """What :func:`evaluate` produced."""

    table: pd.DataFrame  # physical design-variable values, index = run labels
    keys: list[str]  # run key of each row
    scores: pd.DataFrame  # rows = run labels, columns = scorer labels (NaN = failed)
    failed: dict[str, str] = field(default_factory=dict)  # run label -> error
    design: Any = None  # the Design that generated the table (None for a given table)
    reference: Signals | None = None  # the reference run's signals, where scorers need it
    reference_key: str | None = None
    wall: float = 0.0  # wall seconds spent making sure the runs exist


def model_with_effects(study: Study, effects: Sequence = ()) -> Model:
    """The study's model with extra effects (``[{"name": ..., "attach": ...}, ...]`` or
    :class:`~sensfw.effects.Effect` objects, whose ``attach`` the model resolves), after the
    effects the study's own model options name."""
    import inspect

    from .plugins import models

    cls = models.get(study.spec.model.name)
    options = dict(study.spec.model.options)
    if effects:
        if "effects" not in inspect.signature(cls).parameters:
            raise SensfwError(f"model {study.spec.model.name!r} does not take effects")
        options["effects"] = [*options.get("effects", []), *effects]
    return cls(**options)


def variant_spec(study: Study, values: Mapping[str, float], excitation: Excitation,
                 effects: Sequence[Mapping] = ()) -> RunSpec:
    """The run of the study's model with extra ``effects`` (specs), every parameter at its
    nominal value but ``values`` (checked against their bounds), driven by ``excitation``.
    The worker rebuilds the model from the study's reference with the study's own effects
    followed by ``effects``. The study's ``solver.timeout`` is for a run of its own
    excitation; a longer drive (an FRF-only record's stepped sine holds a dwell per line,
    often minutes of signal) gets it in proportion to its length (:func:`run_timeout`)."""
    model = model_with_effects(study, effects) if effects else study.model
    params = study.parameters.nominal()
    declared = model.parameters()
    for name in declared:
        params.setdefault(name, declared[name].nominal)
    for k, v in values.items():
        params[k] = (declared[k] if k in declared else study.parameters[k]).check(v)
    ref = study.model_ref()
    if effects:
        ref = {"name": ref["name"], "options": {
            **ref["options"], "effects": [*ref["options"].get("effects", []),
                                          *(dict(e) for e in effects)]}}
    return RunSpec.create(model, params, excitation,
                          replace(study.solver, timeout=run_timeout(study, excitation)), ref)


def run_timeout(study: Study, excitation: Excitation) -> float | None:
    """The study's ``solver.timeout`` for a run driven by ``excitation``: scaled by the
    drive's length over the study's excitation's where the drive is longer (the timeout
    guards against a run that stalls, and a run's cost grows with its length)."""
    timeout = study.solver.timeout
    own = study.excitation.n_samples / study.excitation.fs
    length = excitation.n_samples / excitation.fs
    if timeout is None or not own > 0 or length <= own:
        return timeout
    return timeout * length / own


def simulate(runner, specs: Sequence[RunSpec], label: str = "runs"
             ) -> tuple[list[Signals | None], list[str | None]]:
    """Make sure every spec has a stored run (``runner`` simulates the missing ones in
    parallel) and load them: per spec its signals (None: the run failed) and the reason
    it failed (the run store's)."""
    runner.run(list(specs), label=label)
    signals, errors = [], []
    for s in specs:
        res = runner.load(s.key())
        ok = res is not None and res.ok
        signals.append(res.signals if ok else None)
        errors.append(None if ok else (res.error if res is not None else None)
                      or "no result stored")
    return signals, errors


def make_specs(study: Study, space: DesignSpace, table: pd.DataFrame) -> list[RunSpec]:
    """One run spec per row of ``table`` (physical values of ``space``'s variables)."""
    specs = []
    for _, row in table.iterrows():
        params = space.to_parameters(row.to_dict())
        specs.append(RunSpec.create(study.model, params, study.excitation, study.solver,
                                    study.model_ref()))
    return specs


def reference_spec(study: Study) -> RunSpec:
    """The nominal run (every parameter at its nominal value): the FRF reference H_v,0."""
    return RunSpec.create(study.model, study.parameters.nominal(), study.excitation,
                          study.solver, study.model_ref())


def make_scorers(study: Study, stage: StageSpec) -> dict[str, Any]:
    """The stage's scorers by label, on the study's output channel unless they name one."""
    from .scorers import make_scorer

    return {sc.key: make_scorer(sc.name, channel=sc.channel or study.output, **sc.options())
            for sc in stage.scorers}


def needs_reference(scorers: Mapping[str, Any]) -> bool:
    return any(s.needs_reference for s in scorers.values())


def score_runs(scorers: Mapping[str, Any], runner, keys: list[str], labels: list[str],
               reference: Signals | None,
               known: Mapping[str, Mapping[str, float]] | None = None
               ) -> tuple[pd.DataFrame, dict[str, str]]:
    """Score every run; failed runs give NaN rows and an entry in the failure dict.
    ``known`` (run key -> row) holds scores computed before (``results.json``), which are
    used instead of scoring the stored signals again."""
    rows, failed = [], {}

    def ours(column: str) -> str | None:  # the scorer a stored score column belongs to
        return next((n for n in scorers if column == n or column.startswith(f"{n}.")), None)

    for label, key in zip(labels, keys, strict=True):
        rec = runner.store.record(key)
        row: dict[str, float] = {}
        # a run other stages share holds their scores too: this stage's only, all of them
        stored = {k: v for k, v in (known or {}).get(key, {}).items() if ours(k)}
        if rec is None or rec["status"] != "ok":
            failed[label] = "missing from the store" if rec is None else rec.get("error")
        elif stored and {ours(k) for k in stored} == set(scorers):
            row = {k: np.nan if v is None else float(v) for k, v in stored.items()}
        else:
            res = runner.load(key)
            for name, scorer in scorers.items():
                values = scorer.score(res.signals, reference)
                if len(values) == 1:
                    row[name] = float(next(iter(values.values())))
                else:
                    row.update({f"{name}.{k}": float(v) for k, v in values.items()})
        rows.append(row)
    return pd.DataFrame(rows, index=labels), failed


def evaluate(study: Study, space: DesignSpace, design, runner, scorers: Mapping[str, Any],
             reference: Signals | RunSpec | None = None, *, options: Mapping | None = None,
             label: str = "runs", known: Mapping[str, Mapping[str, float]] | None = None
             ) -> Evaluation:
    """Design -> runs -> scores.

    Parameters
    ----------
    study, space
        The study and the design space of the runs.
    design : str, Design or DataFrame
        A registered design name (with ``options``), a design instance, or a run table of
        physical values (columns ``space.names``, index = run labels).
    runner
        A :class:`~sensfw.runs.Runner` (simulates what the store lacks) or
        :class:`~sensfw.runs.StoredRuns` (never simulates).
    scorers : mapping
        Label -> scorer (:func:`make_scorers`).
    reference : Signals or RunSpec, optional
        The reference signals of scorers that compare, or the spec of the reference run,
        which is then run in the same batch and loaded (a failed reference is an
        :class:`~sensfw.errors.AnalysisError`).
    known : mapping, optional
        Scores computed before, by run key (see :func:`score_runs`).
    """
    from .designs import Design, make_design

    if isinstance(design, pd.DataFrame):
        made, table = None, design
    else:
        made = design if isinstance(design, Design) else make_design(design, **(options or {}))
        table = made.generate(space, seed=study.spec.study.seed)
    specs = make_specs(study, space, table)
    ref_spec = reference if isinstance(reference, RunSpec) else None
    t0 = time.perf_counter()
    runner.run(specs + ([ref_spec] if ref_spec else []), label=label)
    wall = time.perf_counter() - t0
    signals = None if ref_spec else reference
    if ref_spec is not None:
        res = runner.load(ref_spec.key())
        if res is None or not res.ok:
            raise AnalysisError(f"{label}: the nominal reference run failed "
                                f"({res.error if res else 'missing'}); FRF-based scores need it")
        signals = res.signals
    keys = [s.key() for s in specs]
    scores, failed = score_runs(scorers, runner, keys, list(table.index), signals, known)
    return Evaluation(table=table, keys=keys, scores=scores, failed=failed, design=made,
                      reference=signals, reference_key=ref_spec.key() if ref_spec else None,
                      wall=wall)
