"""A study's results and its output folder: :class:`StageResult` and :class:`StudyResult`
(everything a report needs), :func:`results_json` (the machine-readable summary) and what
:func:`sensfw.pipeline.run_study` writes into the folder :func:`sensfw.pipeline.load_result`
reads back (:func:`keep_study_file`, :func:`write_result`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import SensfwError
from .params import DesignSpace
from .runs import RunCounts, RunStore
from .runs.store import run_step
from .study import StageSpec, Study


@dataclass
class StageResult:
    """Everything one stage produced."""

    spec: StageSpec
    space: DesignSpace
    table: pd.DataFrame  # physical design-variable values, index = run labels
    keys: list[str]  # run key of each row
    scores: pd.DataFrame  # rows = run labels, columns = scorer labels (NaN = failed)
    reference_key: str | None = None
    screening: object | None = None  # the design's analysis (ScreeningResult)
    selected: list[str] | None = None
    surrogates: dict[str, dict[str, object]] = field(default_factory=dict)  # label -> name -> est
    regression: dict[str, dict] = field(default_factory=dict)
    validation: dict[str, dict] = field(default_factory=dict)
    failed: dict[str, str] = field(default_factory=dict)  # run label -> error
    notes: list[str] = field(default_factory=list)

    @property
    def name(self) -> str:
        return self.spec.name


@dataclass
class StudyResult:
    """A study's stages with the run store they read (``store``) and the run counts."""

    study: Study
    stages: list[StageResult]
    store: RunStore
    counts: RunCounts
    #: where a study stopped: ``{"stage": name, "error": message}`` of the stage that
    #: failed (``stages`` holds those before it), None for a finished study
    stopped: dict | None = None


def jsonable(x):
    """``x`` with numpy scalars and arrays, DataFrames (records) and Series (dicts) turned into
    what :func:`json.dumps` writes; non-finite floats become ``None`` (JSON has no NaN)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        x = float(x)
        return x if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, pd.DataFrame):
        return jsonable(x.to_dict(orient="records"))
    if isinstance(x, pd.Series):
        return jsonable(x.to_dict())
    return x


def results_json(res: StudyResult) -> dict:
    """The machine-readable summary (``results.json``); deterministic for identical runs."""
    stages = []
    for st in res.stages:
        entry: dict = {
            "name": st.name, "design": st.spec.design, "n_runs": len(st.table),
            "variables": st.space.names,
            "runs": [{"label": lab, "key": key, **{v: float(st.table.loc[lab, v])
                                                    for v in st.space.names},
                      **run_step(res.store, key)}
                     for lab, key in zip(st.table.index, st.keys, strict=True)],
            "failed": st.failed,
            "scores": {c: st.scores[c].to_dict() for c in st.scores.columns},
            # what each score is: a rebuild rescores a label whose scorer has changed
            "scorers": {sc.key: sc.model_dump(mode="json", exclude_none=True)
                        for sc in st.spec.scorers},
        }
        if st.reference_key is not None:
            entry["reference_key"] = st.reference_key
        if st.screening is not None:
            entry["importance"] = st.screening.importance.to_dict()
            entry["analysis"] = jsonable(st.screening.table.reset_index())
        if st.selected is not None:
            entry["sensitivity"] = st.screening.importance.to_dict()
            entry["selected"] = list(st.selected)
        if st.regression:
            entry["regression"] = st.regression
        if st.validation:
            entry["validation"] = st.validation
        if st.notes:
            entry["notes"] = st.notes
        stages.append(entry)
    source = str(Path(res.study.source).resolve()) if res.study.source else None
    out = {"study": res.study.name, "study_file": source, "runs": res.counts.as_dict(),
           "stages": stages}
    if res.stopped is not None:
        out["stopped"] = res.stopped
    return jsonable(out)


def keep_study_file(study: Study, out: str | Path) -> Path:
    """``out/study.toml``: a copy of the study's file (or, for a study built from a dict,
    its content as TOML), so that the folder alone rebuilds its report
    (:func:`load_result`)."""
    import shutil

    import tomlkit

    target = Path(out) / "study.toml"
    target.parent.mkdir(parents=True, exist_ok=True)
    if study.source is not None and Path(study.source).is_file():
        if not target.exists() or not target.samefile(study.source):
            shutil.copyfile(study.source, target)
        return target
    data = study.spec.model_dump(mode="json", exclude_none=True)
    try:
        target.write_text(tomlkit.dumps(data), encoding="utf-8")
    except (TypeError, ValueError) as err:  # tomlkit's ConvertError: a None in an option
        raise SensfwError(f"{target}: the study cannot be written as TOML ({err}; TOML has "
                          "no null: leave such an option out)") from None
    return target


def write_result(result: StudyResult, out: str | Path, report: bool = True,
                 wall: float | None = None) -> dict:
    """Write ``results.json`` (:func:`results_json`, returned), ``timing.json`` (``wall``
    seconds and the run counts) and, with ``report``, ``report.html`` into ``out``."""
    import json

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    data = results_json(result)
    (out / "results.json").write_text(json.dumps(data, indent=1, sort_keys=False))
    (out / "timing.json").write_text(json.dumps(
        {"wall_s": wall, "runs": result.counts.as_dict()}, indent=1))
    if report:
        from .report.study import write_study_report

        write_study_report(result, out / "report.html")
    return data
