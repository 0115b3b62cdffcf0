"""Does a cheaper design reach the conclusions of the paper's pipeline on the same model?

The paper's pipeline (``studies/paper.toml``) concludes three things: which variables the
screen keeps (the top 4), how its second stage predicts (Eq. 18 on the 3^4 full factorial,
whose leave-one-out error says how well), and which Eq. 18 terms are significant. Another
strategy reaches the same conclusions when (:func:`agreement`):

1. **screen**: it keeps the same set of variables;
2. **predictions**: for every score, its second-stage surrogate predicts the full-factorial
   runs it did not run with an RMSE at most the full factorial's own leave-one-out RMSE
   (Eq. 18, PRESS residuals). The surrogate is the one of Eq. 18 and a Gaussian process
   (``log_features = "auto"``) with the higher leave-one-out Q^2 on the strategy's own runs,
   a choice made without the full factorial;
3. **significant terms**: for every score, Eq. 18 fitted to its second-stage runs (variables
   coded to [-1, 1] by the full factorial's bounds, so that every term tests an effect at
   the centre of the box and no p-value depends on where the physical zero lies) flags at
   p < 0.05 every term the full factorial flags with p < 0.001, and none that the full
   factorial finds with p > 0.5; terms in between may go either way. That band is where the
   full factorial's own decision would not be reproduced: a term at p = 0.001 (z = 3.29)
   keeps p < 0.05 in an independent replicate of the same size with probability
   Phi(3.29 - 1.96) = 0.91, one at p = 0.5 (z = 0.67) turns significant with probability
   Phi(0.67 - 1.96) = 0.10 (Goodman 1992, Stat. Med. 11:875;
   :func:`replication_probability`). The strict form, the same set at p < 0.05, is reported
   too.

``bench/strategies.py`` measures this for several strategies; a study's ``[agree_with]``
section makes its report measure it against a finished run of the paper's pipeline
(:func:`agreement_for`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy import stats

from ..errors import AnalysisError

ALPHA, MUST, MUST_NOT = 0.05, 0.001, 0.5


def replication_probability(p: float, alpha: float = ALPHA) -> float:
    """Probability that an independent replicate of the same size gives p < ``alpha`` for a
    term whose two-sided p-value is ``p`` (normal approximation, Goodman 1992)."""
    z = stats.norm.isf(p / 2)
    return float(stats.norm.cdf(z - stats.norm.isf(alpha / 2)))


def _eq18(bounds, X: pd.DataFrame, y: np.ndarray):
    from ..surrogates import make_surrogate

    return make_surrogate("eq18", bounds=bounds).fit(X, y)


def _coded_p(est) -> pd.Series:
    return est.coefficient_table_coded_.set_index("term")["p"]


@dataclass
class Conclusions:
    """The full factorial's conclusions: its runs (``table``, ``scores``), its leave-one-out
    RMSE and coded p-values of Eq. 18 per score, and the screen's selection."""

    names: list[str]
    bounds: list[tuple[float, float]]
    table: pd.DataFrame
    scores: pd.DataFrame
    selected: list[str] | None = None
    runs: int | None = None  # runs of the whole pipeline

    def __post_init__(self):
        self.rmse_loo: dict[str, float] = {}
        self.p: dict[str, pd.Series] = {}
        for label in self.scores.columns:
            y = self.scores[label].to_numpy(dtype=float)
            ok = np.isfinite(y)
            est = _eq18(self.bounds, self.table.loc[ok, self.names], y[ok])
            self.rmse_loo[label] = float(np.sqrt(np.mean((y[ok] - est.loo_predict()) ** 2)))
            self.p[label] = _coded_p(est)

    def classes(self, label: str) -> tuple[set[str], set[str], set[str]]:
        """(significant at p < 0.05, must be flagged, must not be flagged) for ``label``."""
        p = self.p[label]
        return set(p.index[p < ALPHA]), set(p.index[p < MUST]), set(p.index[p > MUST_NOT])


def _key(row) -> tuple:
    return tuple(np.round(np.asarray(row, float), 9))


def agreement(ref: Conclusions, table: pd.DataFrame, scores: pd.DataFrame) -> dict[str, Any]:
    """Criteria 2 and 3 (module docstring) for second-stage runs ``table`` (physical values
    of ``ref.names``) with ``scores`` (the same labels as ``ref.scores``)."""
    from ..surrogates import make_surrogate
    from ..surrogates.base import SurrogateError

    names = ref.names
    ran = {_key(r) for r in table[names].to_numpy()}
    held = [lab for lab, r in zip(ref.table.index, ref.table[names].to_numpy(), strict=True)
            if _key(r) not in ran]
    out: dict[str, Any] = {"n": len(table), "held_out": len(held), "scores": {}}
    for label in ref.scores.columns:
        if label not in scores:
            out["scores"][label] = {"error": f"no score {label!r}"}
            continue
        y = scores[label].to_numpy(dtype=float)
        ok = np.isfinite(y)
        X = table.loc[ok, names]
        try:
            eq = _eq18(ref.bounds, X, y[ok])
        except SurrogateError as err:  # too few runs for 15 coefficients
            out["scores"][label] = {"error": str(err).splitlines()[0]}
            continue
        A = eq.result_.model.exog
        if np.linalg.matrix_rank(A) < A.shape[1]:  # p-values of aliased terms mean nothing
            out["scores"][label] = {"error": f"Eq. 18 is rank-deficient on these runs "
                                             f"(rank {np.linalg.matrix_rank(A)} of "
                                             f"{A.shape[1]} terms)"}
            continue
        gp = make_surrogate("gaussian_process", bounds=ref.bounds, log_features="auto")
        gp.fit(X, y[ok])
        ss = float(np.sum((y[ok] - y[ok].mean()) ** 2))
        # leave-one-out is undefined where a run has leverage 1 (Eq. 18 on some fractions):
        # such a surrogate cannot be chosen by it
        q2 = {}
        for name, est in (("eq18", eq), ("gaussian_process", gp)):
            with np.errstate(divide="ignore", invalid="ignore"):
                v = 1 - float(np.sum((y[ok] - est.loo_predict()) ** 2)) / ss
            q2[name] = v if np.isfinite(v) else -np.inf
        chosen = max(q2, key=q2.get)
        est = eq if chosen == "eq18" else gp
        truth = ref.scores.loc[held, label].to_numpy(dtype=float)
        fine = np.isfinite(truth)
        pred = est.predict(ref.table.loc[held, names]) if held else np.zeros(0)
        rmse = float(np.sqrt(np.mean((truth[fine] - pred[fine]) ** 2))) if fine.any() else 0.0
        sig_ref, must, must_not = ref.classes(label)
        p = _coded_p(eq)
        sig = set(p.index[p < ALPHA])
        row = {"surrogate": chosen, "q2_loo": q2[chosen], "rmse": rmse,
               "rmse_loo_reference": ref.rmse_loo[label], "ratio": rmse / ref.rmse_loo[label],
               "predicts": rmse <= ref.rmse_loo[label], "strict": sig == sig_ref,
               "missed": sorted(must - sig), "wrong": sorted(sig & must_not),
               "significant": sorted(sig)}
        row["terms"] = not row["missed"] and not row["wrong"]
        out["scores"][label] = row
    rows = out["scores"].values()
    out["predicts"] = all(r.get("predicts", False) for r in rows)
    out["terms"] = all(r.get("terms", False) for r in rows)
    out["strict"] = all(r.get("strict", False) for r in rows)
    out["reached"] = out["predicts"] and out["terms"]
    return out


def load_conclusions(folder: str | Path, screen: str, stage: str) -> Conclusions:
    """The conclusions of a finished pipeline from its output folder's ``results.json``:
    the selection of stage ``screen``, the runs and scores of stage ``stage`` (its bounds are
    its runs' range: the full factorial spans its box)."""
    path = Path(folder) / "results.json"
    try:
        data = json.loads(path.read_text())
        stages = {s["name"]: s for s in data["stages"]}
        sel = stages[screen].get("selected")
        st = stages[stage]
        names = list(st["variables"])
        table = pd.DataFrame([{v: r[v] for v in names} for r in st["runs"]],
                             index=[r["label"] for r in st["runs"]])
        scores = pd.DataFrame({c: pd.Series(v, dtype=float) for c, v in st["scores"].items()})
        runs = int(data["runs"]["total"])
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise AnalysisError(f"{path}: cannot read stages {screen!r} and {stage!r} ({err!r})") \
            from None
    scores = scores.reindex(table.index)
    bounds = [(float(table[v].min()), float(table[v].max())) for v in names]
    return Conclusions(names=names, bounds=bounds, table=table, scores=scores, selected=sel,
                       runs=runs)


def check_study(study, problems: list[tuple[str, str]]) -> None:
    """Problems of ``study``'s ``[agree_with]`` section (``study``: a
    :class:`~sensfw.study.Study` being validated): its stages must exist, the screen
    with a ``select``, the second stage with surrogates. The results folder is read when
    the report is written (a missing one is a note there, not an error here)."""
    spec = study.spec.agree_with
    stages = {s.name: s for s in study.spec.stages}
    for field_name, need in (("screen", "select"), ("stage", "surrogates")):
        name = getattr(spec, field_name)
        st = stages.get(name)
        if st is None:
            problems.append((f"agree_with.{field_name}", f"no stage named {name!r}; the study "
                                                         f"has {', '.join(stages)}"))
        elif not getattr(st, need):
            problems.append((f"agree_with.{field_name}", f"stage {name!r} has no {need}"))


def agreement_for(result) -> dict[str, Any] | None:
    """A study's agreement with the finished pipeline its ``[agree_with]`` names (None
    without the section): run counts, the screen's selection and :func:`agreement` of its
    second stage."""
    spec = result.study.spec.agree_with
    if spec is None:
        return None
    from .paper_comparison import study_path

    folder = study_path(spec.results, result.study)
    ref = load_conclusions(folder, spec.screen, spec.stage)
    stages = {s.name: s for s in result.stages}
    missing = [n for n in (spec.screen, spec.stage) if n not in stages]
    if missing:
        raise AnalysisError(f"agree_with: this study has no stage {', '.join(missing)}")
    screen, second = stages[spec.screen], stages[spec.stage]
    out: dict[str, Any] = {"folder": str(folder), "runs": result.counts.total,
                           "reference_runs": ref.runs, "selected": list(screen.selected or []),
                           "reference_selected": list(ref.selected or [])}
    out["screen"] = set(out["selected"]) == set(out["reference_selected"])
    if not out["screen"] or set(second.space.names) != set(ref.names):
        out.update(reached=False, predicts=False, terms=False, strict=False, scores={})
        return out
    out.update(agreement(ref, second.table, second.scores))
    out["reached"] = out["reached"] and out["screen"]
    return out
