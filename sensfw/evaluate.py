"""Design -> runs -> scores: the one sequence every stage of a study, the design comparison
and the confirmation runs share.

:func:`evaluate` turns a design (a name with options, a :class:`~sensfw.designs.Design`, or a
ready run table) into run specs, makes sure each has a result in the run store (through a
:class:`~sensfw.runs.Runner`, or :class:`~sensfw.runs.StoredRuns`, which never simulates),
and scores every finished run. Failed runs give NaN rows and an entry in ``failed``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from .errors import AnalysisError
from .models.base import Signals
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
    for label, key in zip(labels, keys, strict=True):
        rec = runner.store.record(key)
        row: dict[str, float] = {}
        if rec is None or rec["status"] != "ok":
            failed[label] = "missing from the store" if rec is None else rec.get("error")
        elif known is not None and key in known:
            row = {k: np.nan if v is None else float(v) for k, v in known[key].items()}
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
