"""A stage's Eq. 18 regression beside a published one (Steinbach et al. 2025, Fig. 10b).

The published numbers live in one data file per reference, ``sensfw/data/<key>.toml``
(:func:`available_references`): the design (Table 2), and per response its R^2adj, the terms
its text calls significant and its coefficient table (Fig. 10b), each with its source. A study
asks for the comparison in its ``[compare_with]`` section (reference, stage, the reference's
factors -> the stage's design variables, its responses -> the stage's scorer labels), which
:func:`check_study` validates with the rest of the study file. ``reference`` is the key of a
shipped file or the path of one in the same format (:func:`study_path`).

Each score of the stage is fitted twice beside the paper's table:

* **sensfw**: Eq. 18 as the study fits it (:class:`~sensfw.surrogates.eq18.Eq18`: coded
  variables, with an intercept; coefficients mapped to physical units);
* **as Fig. 10b**: the same model fitted the way the paper's table was, least squares on the
  physical values with the columns that a pivoted-QR rank check keeps (a MATLAB-style
  rule, ``|R_kk| > max(n, p) eps(|R_11|)``; :func:`fit_as_published`). On Table 2's values the
  ``x2^2`` column is about 1e13 and the rank check drops the intercept, whose R diagonal is
  0.04 against a tolerance of 1.3: Fig. 10b prints the intercept as estimate 0, SE 0 and
  t NaN, the way MATLAB reports a coefficient it dropped. Without an intercept the terms of
  x2, which varies by +-10 % only, stand in for it.

Significance is ``p < alpha`` (the paper's 0.05). Linear terms in physical units test the
slope at x = 0 (outside the design for x2), so their sign and p depend on the fit's form;
interactions and squares are the same in every affine coding.

(Over the usual 400 lines: the reference file's checks, the two fits and the side-by-side
table all follow the one mapping of the paper's factors and responses to the stage's; a
split would pass that mapping around instead of keeping it in one place.)
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..errors import AnalysisError, SensfwError

COLUMNS = ("estimate", "se", "t", "p")


class UnknownReferenceError(SensfwError, KeyError):
    """No data file for the named reference (the message lists the available ones)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


@dataclass(frozen=True)
class PublishedResponse:
    """One response of a reference: R^2adj, the text's significant terms and Fig. 10b."""

    key: str
    name: str
    r2_adj: float
    r2_adj_source: str
    named: tuple[str, ...]
    named_source: str
    source: str
    table: pd.DataFrame  # index = term (x-names), columns estimate, se, t, p

    def significant(self, alpha: float) -> list[str]:
        p = self.table["p"]
        return [t for t in self.table.index if p[t] < alpha]


@dataclass(frozen=True)
class Reference:
    """A published study's numbers (one data file)."""

    key: str
    citation: str
    meta: dict[str, Any]  # model, solver, cost, regression: one sentence each
    alpha: float
    factors: dict[str, dict[str, Any]]  # x-name -> name, unit, levels (Table 2)
    doe: dict[str, Any]
    responses: dict[str, PublishedResponse]
    analogues: dict[str, dict[str, Any]]  # model name -> differences from the paper's model
    path: str


def _data_dir():
    return resources.files("sensfw") / "data"


def available_references() -> list[str]:
    """Keys of the shipped reference data files."""
    return sorted(p.name[:-5] for p in _data_dir().iterdir() if p.name.endswith(".toml"))


def study_path(path: str | Path, study) -> Path:
    """A path a study file names: absolute, or relative to the study file's folder, or, where
    nothing is there, to the working folder (a report rebuilt from an output folder reads the
    study file's copy there; ``--out`` folders are relative to the working folder)."""
    path = Path(path)
    if path.is_absolute():
        return path
    if study.source:
        near = Path(study.source).resolve().parent / path
        if near.exists():
            return near
    return (Path.cwd() / path).resolve()


def load_reference(key: str, study=None) -> Reference:
    """The reference ``key`` (``sensfw/data/<key>.toml``), or the data file at the path
    ``key`` (ending in ``.toml``; relative as :func:`study_path` says for ``study``, else to
    the working folder)."""
    if key.endswith(".toml"):
        res = study_path(key, study) if study is not None else Path(key)
        if not res.is_file():
            raise UnknownReferenceError(f"reference file {str(res)!r} not found")
    else:
        known = available_references()
        if key not in known:
            raise UnknownReferenceError(f"unknown reference {key!r}; available: "
                                        f"{', '.join(known) or '(none)'} (or the path of a "
                                        "data file ending in .toml)")
        res = _data_dir() / f"{key}.toml"
    try:
        data = tomllib.loads(res.read_text(encoding="utf-8"))
        ref = data["reference"]
        responses = {}
        for rkey, r in data["responses"].items():
            table = pd.DataFrame({c: [float(v) for v in r[c]] for c in COLUMNS},
                                 index=pd.Index(r["terms"], name="term"))
            responses[rkey] = PublishedResponse(
                key=rkey, name=r["name"], r2_adj=float(r["r2_adj"]),
                r2_adj_source=r["r2_adj_source"], named=tuple(r["named_significant"]),
                named_source=r["named_source"], source=r["source"], table=table)
        doe = data["doe"]
        factors = {x: dict(doe[x]) for x in doe["factors"]}
    except (KeyError, TypeError, ValueError, UnicodeDecodeError) as err:
        raise SensfwError(f"{res}: not a valid reference data file ({err!r})") from None
    meta = {k: ref[k] for k in ("model", "solver", "cost", "regression") if k in ref}
    return Reference(key=ref["key"], citation=ref["citation"], meta=meta,
                     alpha=float(ref.get("significance", 0.05)), factors=factors,
                     doe={k: v for k, v in doe.items() if k not in factors},
                     responses=responses, analogues=data.get("analogues", {}), path=str(res))


def check_study(study, problems: list[tuple[str, str]]) -> None:
    """Problems of ``study``'s ``[compare_with]`` section (``study``: a
    :class:`~sensfw.study.Study` being validated), at their dotted paths."""
    spec = study.spec.compare_with
    where = "compare_with"
    try:
        ref = load_reference(spec.reference, study)
    except SensfwError as err:
        problems.append((f"{where}.reference", str(err)))
        return
    stages = {s.name: s for s in study.spec.stages}
    stage = stages.get(spec.stage)
    if stage is None:
        problems.append((f"{where}.stage", f"no stage named {spec.stage!r}; the study has "
                                           f"{', '.join(stages)}"))
        return
    missing = [x for x in ref.factors if x not in spec.factors]
    if missing:
        problems.append((f"{where}.factors", f"{ref.key} has the factors "
                         f"{', '.join(ref.factors)}; map {', '.join(missing)} to design "
                         "variables of the stage"))
    known = set(study.variable_names())
    listed = set(stage.variables) if isinstance(stage.variables, list) else None
    for x, var in spec.factors.items():
        if x not in ref.factors:
            problems.append((f"{where}.factors.{x}", f"{ref.key} has no factor {x!r}; it has "
                                                     f"{', '.join(ref.factors)}"))
        elif known and var not in known:
            problems.append((f"{where}.factors.{x}", f"unknown design variable {var!r}"))
        elif listed is not None and var not in listed:
            problems.append((f"{where}.factors.{x}", f"{var!r} is not a variable of stage "
                                                     f"{stage.name!r}"))
    if len(set(spec.factors.values())) < len(spec.factors):
        problems.append((f"{where}.factors", "two factors map to the same design variable"))
    if not spec.responses:
        problems.append((f"{where}.responses", f"map at least one of {', '.join(ref.responses)}"
                                               " to a scorer label of the stage"))
    labels = [sc.key for sc in stage.scorers]
    for r, label in spec.responses.items():
        if r not in ref.responses:
            problems.append((f"{where}.responses.{r}", f"{ref.key} has no response {r!r}; it "
                                                       f"has {', '.join(ref.responses)}"))
        elif label not in labels:
            problems.append((f"{where}.responses.{r}", f"no scorer labelled {label!r} in stage "
                                                       f"{stage.name!r} ({', '.join(labels)})"))


# ---- fits -------------------------------------------------------------------------------------
def fit_as_published(X: np.ndarray, y: np.ndarray, names: list[str]) -> dict[str, Any]:
    """Eq. 18 (products) by least squares on the physical values, keeping the columns a
    pivoted QR declares independent (``|R_kk| > max(n, p) eps(|R_11|)``, a MATLAB-style rule);
    dropped coefficients are reported as MATLAB does: estimate 0, SE 0, t and p NaN.
    R^2 and R^2adj are about the mean with the kept columns as the model's degrees of
    freedom."""
    import scipy.linalg as sl
    from scipy import stats

    from ..surrogates.eq18 import design_matrix

    A, terms = design_matrix(np.asarray(X, float), names)
    y = np.asarray(y, float)
    n, p = A.shape
    _, R, perm = sl.qr(A, mode="economic", pivoting=True)
    diag = np.abs(np.diag(R))
    tol = max(n, p) * np.spacing(diag[0])
    keep = np.sort(perm[diag > tol])
    dropped = [terms[j] for j in sorted(set(range(p)) - set(keep))]
    if n <= len(keep):
        raise AnalysisError(f"{n} runs cannot support {len(keep)} coefficients")
    # least squares by QR of the kept columns scaled to unit norm (the normal equations
    # would square a condition number of order 1e7)
    scale = np.linalg.norm(A[:, keep], axis=0)
    Q, Rk = np.linalg.qr(A[:, keep] / scale)
    coef = sl.solve_triangular(Rk, Q.T @ y) / scale
    resid = y - A[:, keep] @ coef
    dfe = n - len(keep)
    s2 = float(resid @ resid) / dfe
    Rinv = sl.solve_triangular(Rk, np.eye(len(keep)))
    se = np.sqrt(s2 * np.sum(Rinv**2, axis=1)) / scale
    table = pd.DataFrame({"estimate": 0.0, "se": 0.0, "t": np.nan, "p": np.nan},
                         index=pd.Index(terms, name="term"))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = coef / se
    table.iloc[keep] = np.column_stack([coef, se, t, 2 * stats.t.sf(np.abs(t), dfe)])
    sst = float(np.sum((y - y.mean()) ** 2))
    r2 = 1 - float(resid @ resid) / sst if sst > 0 else float("nan")
    return {"table": table, "r2": r2, "r2_adj": 1 - (1 - r2) * (n - 1) / dfe,
            "dropped": dropped, "rank_tolerance": float(tol),
            "r_diagonal": dict(zip([terms[j] for j in perm], diag.tolist(), strict=True))}


def _eq18(X: pd.DataFrame, y: np.ndarray, bounds) -> dict[str, Any]:
    from ..surrogates import make_surrogate

    est = make_surrogate("eq18", bounds=bounds).fit(X, y)
    return {"table": est.coefficient_table_.set_index("term")[list(COLUMNS)],
            "coded": est.coefficient_table_coded_.set_index("term")[list(COLUMNS)],
            "r2": est.summary_["r2"], "r2_adj": est.summary_["r2_adj"]}


# ---- comparison -------------------------------------------------------------------------------
@dataclass
class Comparison:
    """The paper beside a stage: ``summary`` (one row per response), ``terms`` (response ->
    one row per Eq. 18 term), ``effects`` (main effect of each factor on each score),
    ``reasons`` (why terms differ), ``notes``."""

    reference: Reference
    stage: str
    factors: dict[str, str]
    summary: pd.DataFrame
    terms: dict[str, pd.DataFrame]
    effects: pd.DataFrame
    reasons: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _x_term(term: str, to_x: dict[str, str]) -> str | None:
    """A term of the stage's Eq. 18 in the reference's names (``a:b`` -> ``x1:x3``)."""
    if term == "(Intercept)":
        return term
    if term.endswith("^2"):
        x = to_x.get(term[:-2])
        return None if x is None else f"{x}^2"
    parts = [to_x.get(t) for t in term.split(":")]
    if None in parts:
        return None
    return ":".join(sorted(parts, key=lambda s: int(s[1:]) if s[1:].isdigit() else s))


def _sign(v: float) -> int:
    return 0 if not np.isfinite(v) or v == 0 else int(np.sign(v))


def _fmt_terms(terms) -> str:
    return ", ".join(terms) if terms else "none"


def main_effects(X: pd.DataFrame, scores: pd.DataFrame) -> pd.DataFrame:
    """Range of the level means of each factor (rows) on each score (columns), as a share of
    the score's range over the runs."""
    out = {}
    for label in scores.columns:
        y = scores[label].to_numpy(dtype=float)
        span = float(np.nanmax(y) - np.nanmin(y))
        out[label] = {v: float(np.ptp(pd.Series(y).groupby(X[v].to_numpy()).mean()))
                      / span if span > 0 else float("nan") for v in X.columns}
    return pd.DataFrame(out)


def _terms_frame(pub: PublishedResponse, ours: pd.DataFrame, coded: pd.DataFrame,
                 as_pub: pd.DataFrame, alpha: float) -> pd.DataFrame:
    """One row per Eq. 18 term (reference names): the paper's, sensfw's and the as-Fig.-10b
    estimate and p, and whether the paper and the as-Fig.-10b fit agree."""
    idx = ours.index
    frame = pd.DataFrame({
        "paper estimate": pub.table["estimate"].reindex(idx).to_numpy(),
        "paper p": pub.table["p"].reindex(idx).to_numpy(),
        "named in text": [t in pub.named for t in idx],
        "sensfw estimate": ours["estimate"].to_numpy(),
        "sensfw p": ours["p"].to_numpy(),
        "sensfw p, coded": coded["p"].to_numpy(),
        "as Fig. 10b: estimate": as_pub["estimate"].reindex(idx).to_numpy(),
        "as Fig. 10b: p": as_pub["p"].reindex(idx).to_numpy(),
    }, index=pd.Index(idx, name="term"))
    sig_paper = (frame["paper p"] < alpha).to_numpy()
    sig_as = (frame["as Fig. 10b: p"] < alpha).to_numpy()
    same = [_sign(a) == _sign(b) for a, b in zip(frame["paper estimate"],
                                                 frame["as Fig. 10b: estimate"], strict=True)]
    frame["agreement (as Fig. 10b)"] = [
        ("both significant, " + ("same sign" if s else "opposite sign")) if a and b else
        "both not significant" if not a and not b else "paper only" if a else "sensfw only"
        for a, b, s in zip(sig_paper, sig_as, same, strict=True)]
    return frame


def compare(reference: Reference, table: pd.DataFrame, scores: pd.DataFrame,
            factors: dict[str, str], responses: dict[str, str], bounds=None,
            model: str | None = None) -> Comparison:
    """Fit Eq. 18 to each mapped score of a stage (``table``: physical values, ``scores``:
    scorer labels) and set it beside ``reference``.

    Parameters
    ----------
    factors : reference factor (x1..) -> design variable of ``table``
    responses : reference response -> column of ``scores``
    bounds : design variable -> (low, high), the coding of the Eq. 18 fit (default: the
        data range)
    model : the study's model name, to list how it differs from the paper's
    """
    alpha = reference.alpha
    xs = [x for x in reference.factors if x in factors]
    names = [factors[x] for x in xs]
    to_x = {v: x for x, v in factors.items()}
    notes: list[str] = []
    rows, per_term, fits = {}, {}, {}
    for r, label in responses.items():
        pub = reference.responses[r]
        if label not in scores:
            notes.append(f"{r}: the stage has no score {label!r}")
            continue
        y = scores[label].to_numpy(dtype=float)
        ok = np.isfinite(y)
        if ok.sum() <= 1 + 2 * len(names) + len(names) * (len(names) - 1) // 2:
            notes.append(f"{r}: {ok.sum()} finished runs are too few for Eq. 18")
            continue
        if not ok.all():
            notes.append(f"{r}: {(~ok).sum()} failed runs left out of the fits")
        X = table.loc[ok, names]
        ours = _eq18(X, y[ok], None if bounds is None else [bounds[v] for v in names])
        as_pub = fit_as_published(X.to_numpy(), y[ok], xs)
        fits[r] = as_pub
        rename = {t: _x_term(t, to_x) for t in ours["table"].index}
        frame = _terms_frame(pub, ours["table"].rename(index=rename),
                             ours["coded"].rename(index=rename), as_pub["table"], alpha)
        per_term[r] = frame
        sig = {c: [t for t in frame.index if frame.loc[t, c] < alpha]
               for c in ("paper p", "sensfw p", "as Fig. 10b: p")}
        rows[r] = {
            "response": pub.name, "sensfw score": label,
            "R²adj paper": pub.r2_adj, "R²adj sensfw": ours["r2_adj"],
            "R²adj sensfw as Fig. 10b": as_pub["r2_adj"],
            "significant: paper text": _fmt_terms(pub.named),
            "significant: paper Fig. 10b": _fmt_terms(sig["paper p"]),
            "significant: sensfw": _fmt_terms(sig["sensfw p"]),
            "significant: sensfw as Fig. 10b": _fmt_terms(sig["as Fig. 10b: p"]),
            "named in the text, not by sensfw": _fmt_terms(
                [t for t in pub.named if t not in sig["sensfw p"]]),
            "named in the text, not by sensfw as Fig. 10b": _fmt_terms(
                [t for t in pub.named if t not in sig["as Fig. 10b: p"]]),
            "rank check drops": _fmt_terms(as_pub["dropped"]),
        }
    summary = pd.DataFrame.from_dict(rows, orient="index")
    summary.index.name = "paper response"
    finished = scores[[responses[r] for r in per_term]].notna().all(axis=1).to_numpy()
    effects = main_effects(table.loc[finished, names],
                           scores.loc[finished, [responses[r] for r in per_term]])
    effects.index = [f"{to_x[v]} {v}" for v in effects.index]
    reasons = _reasons(reference, per_term, fits, responses, effects, xs, names, alpha,
                       table.loc[:, names], model) if per_term else []
    return Comparison(reference=reference, stage="", factors=dict(factors), summary=summary,
                      terms=per_term, effects=effects, reasons=reasons, notes=notes)


def _reasons(reference, per_term, fits, responses, effects, xs, names, alpha, X,
             model) -> list[str]:
    """Why the paper names terms the study does not: the fit's form (measured here), the
    factors' effects in this model (measured here), the model's differences (data file)."""
    out = []
    dropped_pub = [r for r in per_term if _dropped(reference.responses[r].table)]
    if dropped_pub:
        fit = fits[dropped_pub[0]]
        d = fit["r_diagonal"]
        lo, hi = X.min().to_numpy(), X.max().to_numpy()
        rel = (hi - lo) / np.abs(hi + lo)  # half range over mid-point
        j = int(np.argmin(rel))
        ours = [r for r in dropped_pub if "(Intercept)" in fits[r]["dropped"]]
        x2 = [t for t in per_term[dropped_pub[0]].index if xs[j] in t.replace("^2", "")
              .split(":")]
        flips = [f"{responses[r]} {t}" for r in per_term for t in x2
                 if per_term[r].loc[t, "as Fig. 10b: p"] < alpha
                 <= per_term[r].loc[t, "sensfw p"]]
        out.append(
            f"The intercept. Fig. 10b prints it as estimate 0, SE 0, t NaN ({len(dropped_pub)}"
            f" of {len(per_term)} responses), the way MATLAB reports a coefficient its rank "
            "check dropped. The same check (pivoted QR, |R_kk| > max(n, p) eps |R_11|) on "
            f"this study's physical values drops {'the intercept' if ours else 'nothing'}: "
            f"its R diagonal is {d.get('(Intercept)', float('nan')):.3g} against a tolerance "
            f"of {fit['rank_tolerance']:.3g}, because the largest column, "
            f"{max(d, key=d.get)}, is of order {max(d.values()):.0e}. Without an intercept "
            f"the terms of {xs[j]} ({reference.factors[xs[j]]['name']}, +-{100 * rel[j]:.0f} "
            f"% about {(hi[j] + lo[j]) / 2:.3g}) carry the mean level: fitted that way, "
            f"{_fmt_terms(flips)} become significant here although they are not with an "
            "intercept. The paper's significant terms of x2 need not be effects of the "
            f"{reference.factors[xs[j]]['name']}.")
    for x, var in zip(xs, names, strict=True):
        terms_x = [t for t in next(iter(per_term.values())).index
                   if x in t.replace("^2", "").split(":")]
        if any((f.loc[terms_x, "sensfw p"] < alpha).any() for f in per_term.values()):
            continue
        named = [responses[r] for r in per_term
                 if (reference.responses[r].table["p"].reindex(terms_x) < alpha).any()]
        if named:
            share = effects.loc[f"{x} {var}"]
            out.append(f"{x} ({var}) has no significant term for any score here, while the "
                       f"paper flags terms of it for {', '.join(named)}: its main effect (range"
                       " of the level means) is " + ", ".join(f"{k} {100 * v:.2g} %" for k, v
                                                              in share.items())
                       + " of each score's range in this model.")
    lin = {}
    for r, frame in per_term.items():
        for t in frame.index:
            if t in xs and t in reference.responses[r].named and frame.loc[t, "sensfw p"] \
                    >= alpha:
                lin.setdefault(t, []).append(f"{responses[r]} p = "
                                             f"{frame.loc[t, 'sensfw p, coded']:.2g}")
    for t, where in lin.items():
        low = float(X[names[xs.index(t)]].min())
        out.append(f"{t} linear: the paper names it and its physical-unit coefficient is not "
                   f"significant here, but that coefficient is the slope at {t} = 0, outside "
                   f"the box (which starts at {low:.3g}). The slope at the box's centre (coded "
                   "fit) has " + ", ".join(where) + ".")
    for r, frame in per_term.items():
        sq = [t for t in frame.index if t.endswith("^2")
              and frame.loc[t, "agreement (as Fig. 10b)"] == "both significant, opposite sign"]
        if sq:
            out.append(f"{responses[r]}: {', '.join(sq)} significant in both with opposite "
                       "signs: the score's curvature along "
                       + ("that factor" if len(sq) == 1 else "those factors")
                       + " is the opposite of the paper's.")
    differences = reference.analogues.get(model or "", {}).get("differences", [])
    if differences:
        out.append("The model is an analogue of the paper's, not its Adams model. "
                   + " ".join(differences))
    return out


def _dropped(table: pd.DataFrame) -> bool:
    """Whether a published table reports its intercept as a dropped coefficient."""
    if "(Intercept)" not in table.index:
        return False
    row = table.loc["(Intercept)"]
    return row["estimate"] == 0 and row["se"] == 0 and math.isnan(row["t"])


def comparison_for(result) -> Comparison | None:
    """The comparison a study's ``[compare_with]`` asks for, from its
    :class:`~sensfw.pipeline.StudyResult` (None without the section)."""
    spec = result.study.spec.compare_with
    if spec is None:
        return None
    stage = next((s for s in result.stages if s.name == spec.stage), None)
    if stage is None:
        raise AnalysisError(f"compare_with.stage: stage {spec.stage!r} did not run")
    ref = load_reference(spec.reference, result.study)
    missing = [v for v in spec.factors.values() if v not in stage.space.names]
    if missing:
        raise AnalysisError(f"compare_with.factors: {', '.join(missing)} are not variables of "
                            f"stage {stage.name!r} ({', '.join(stage.space.names)})")
    bounds = {v: (stage.space[v].low, stage.space[v].high) for v in spec.factors.values()}
    out = compare(ref, stage.table, stage.scores, spec.factors, spec.responses, bounds=bounds,
                  model=result.study.spec.model.name)
    out.stage = stage.name
    return out
