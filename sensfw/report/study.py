"""The study report: the figures a reader of the paper expects (Figs. 7-11) per stage.

It reads a :class:`~sensfw.pipeline.StudyResult`: the stages and the run store, never a
runner, so a report can be rebuilt from an output folder (``sensfw report DIR``,
:func:`~sensfw.pipeline.load_result`).

(Over the usual 400 lines: one figure function per figure of the paper and the page that
orders them; the figures share the stage's tables and a split would only scatter them.)"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.ticker import LogFormatter, StrMethodFormatter

from ..params import spaced
from .html import Page


def _signals(result, key):
    res = result.store.load(key)
    return res.signals if res is not None and res.ok else None


def _frf_db(sig, channel, smooth: int = 24):
    """Hv FRF in dB, smoothed over 1/24 octave for display."""
    from ..signal import frf, octave_smooth

    f, H = frf(sig.force, sig.channel(channel), sig.fs, estimator="Hv")
    with np.errstate(divide="ignore"):
        return f, 20 * np.log10(octave_smooth(f, H, smooth))


def frf_overlay(result, stage, channel, top: int = 4):
    """Fig. 7: FRFs of the min/max runs of the most sensitive variables over the reference."""
    ref = _signals(result, stage.reference_key) if stage.reference_key else None
    fig, ax = plt.subplots(figsize=(10, 4.6))
    band = (result.study.excitation.f0, result.study.excitation.f1)
    if ref is not None:
        f, db = _frf_db(ref, channel)
        sel = (f >= band[0]) & (f <= band[1])
        ax.semilogx(f[sel], db[sel], color="k", lw=1.6, label="reference (nominal)", zorder=5)
    ranking = list(stage.screening.ranking[:top]) if stage.screening is not None else []
    colors = plt.cm.tab10(np.linspace(0, 1, 10))
    for i, var in enumerate(ranking):
        for lvl, ls in (("min", "--"), ("max", "-")):
            label = f"{var}:{lvl}"
            if label not in stage.table.index:
                continue
            sig = _signals(result, stage.keys[list(stage.table.index).index(label)])
            if sig is None:
                continue
            f, db = _frf_db(sig, channel)
            sel = (f >= band[0]) & (f <= band[1])
            ax.semilogx(f[sel], db[sel], ls=ls, lw=0.9, color=colors[i % 10],
                        label=f"{var} {lvl}")
    # frequencies as plain numbers (200, 1000), not 10^k: readable, and no mathtext parser
    # to build (0.15 s of `sensfw report`)
    ax.xaxis.set_major_formatter(LogFormatter())
    ax.xaxis.set_minor_formatter(LogFormatter(labelOnlyBase=False))
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"|H| (dB re 1 (m/s²)/N), {channel}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("FRF (Hv, 1/24-octave smoothed) from shaker force to the output: screen runs "
                 "against the reference")
    return fig


def sensitivity_bars(stage, threshold: float | None):
    """Fig. 8: normalised sensitivity with the selection threshold."""
    imp = stage.screening.importance.sort_values(ascending=False)
    fig, ax = plt.subplots(figsize=(10, 0.28 * len(imp) + 1.5))
    selected = set(stage.selected or [])
    colors = ["#1f6fd1" if v in selected else "#9aa5b1" for v in imp.index]
    ax.barh(range(len(imp)), imp.to_numpy() * 100, color=colors)
    ax.set_yticks(range(len(imp)), imp.index, fontsize=8)
    ax.invert_yaxis()
    if threshold is not None:
        ax.axvline(threshold * 100, color="r", ls="--", lw=1, label=f"threshold {threshold:.0%}")
        ax.legend(loc="lower right")
    ax.set_xlabel("normalised sensitivity (%)")
    ax.set_title("Screen: normalised sensitivity (blue: selected)")
    ax.grid(True, axis="x", alpha=0.3)
    return fig


def order_spectrum_mean(result, stage, channel):
    """Fig. 9: averaged order spectrum of the stage's runs."""
    from ..signal import order_spectrum

    spectra, orders = [], None
    for key in stage.keys:
        sig = _signals(result, key)
        if sig is None:
            continue
        sig = sig.sweep()
        n, P = order_spectrum(sig.channel(channel), sig.fs, sig.f_inst)
        if orders is None:
            orders = n
        if len(n) == len(orders):
            spectra.append(P)
    fig, ax = plt.subplots(figsize=(10, 4))
    if spectra:
        P = np.mean(spectra, axis=0)
        ax.semilogy(orders, P, lw=1)
        for k in range(1, int(orders.max()) + 1):
            ax.axvline(k, color="r", lw=0.6, alpha=0.4)
    ax.yaxis.set_major_formatter(StrMethodFormatter("{x:g}"))  # 0.01: no mathtext
    ax.set_xlabel("order")
    ax.set_ylabel("RMS amplitude (m/s²)")
    ax.set_title(f"Averaged order spectrum of {len(spectra)} runs ({channel})")
    ax.grid(True, which="both", alpha=0.3)
    return fig


def actual_vs_predicted(stage):
    """Fig. 10a: actual vs predicted for each score (the first surrogate of each)."""
    labels = [lab for lab in stage.surrogates if stage.surrogates[lab]]
    fig, axes = plt.subplots(1, max(len(labels), 1), figsize=(4.2 * max(len(labels), 1), 4))
    axes = np.atleast_1d(axes)
    for ax, label in zip(axes, labels, strict=False):
        y = stage.scores[label].to_numpy(dtype=float)
        ok = np.isfinite(y)
        X = stage.table.loc[ok, stage.space.names]
        for name, est in stage.surrogates[label].items():
            yp = est.predict(X)
            ax.plot(y[ok], yp, "o", ms=3.5, label=name, alpha=0.8)
        lo, hi = np.nanmin(y), np.nanmax(y)
        ax.plot([lo, hi], [lo, hi], "k--", lw=0.8)
        reg = stage.regression.get(label)
        title = label + (f"  R²adj={reg['r2_adj']:.3f}" if reg else "")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("simulated")
        ax.set_ylabel("predicted")
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def residual_plots(stage, label: str, name: str):
    """Residuals against fitted values and normal Q-Q of one surrogate."""
    v = stage.validation[label][name]
    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.4))
    if "fitted" in v and "residuals" in v:
        a.plot(v["fitted"], v["residuals"], "o", ms=3)
        a.axhline(0, color="k", lw=0.8)
    a.set_xlabel("fitted")
    a.set_ylabel("residual")
    a.set_title(f"{label} / {name}: residuals")
    qq = v.get("qq")
    if qq:
        b.plot(qq["theoretical"], qq["ordered"], "o", ms=3)
        t = np.asarray(qq["theoretical"])
        if "slope" in qq:
            b.plot(t, qq["slope"] * t + qq["intercept"], "r-", lw=0.8)
    b.set_xlabel("theoretical quantile")
    b.set_ylabel("ordered residual")
    b.set_title("normal Q-Q")
    for ax in (a, b):
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def _run_title(stage, label) -> str:
    """A run's label with the design-variable values it ran at, one a line (up to three)."""
    units = {v.name: v.unit for v in stage.space.variables}
    row = stage.table.loc[label]
    if len(row) > 3:
        return f"run {label}"
    return "\n".join([f"run {label}", *(f"{k} = {float(x):.3g}{spaced(units.get(k, ''))}"
                                        for k, x in row.items())])


def spectrograms(result, stage, channel):
    """Fig. 11: spectrograms of the first and last run of the stage."""
    from ..signal import spectrogram

    picks = [(stage.table.index[0], stage.keys[0]), (stage.table.index[-1], stage.keys[-1])]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4), sharey=True)
    for ax, (label, key) in zip(axes, picks, strict=True):
        sig = _signals(result, key)
        if sig is None:
            ax.set_title(f"{label}: failed")
            continue
        f, t, S = spectrogram(sig.channel(channel), sig.fs)
        vmax = np.nanmax(S)
        im = ax.pcolormesh(t, f, S, shading="auto", vmin=vmax - 80, vmax=vmax, cmap="viridis")
        ax.set_title(_run_title(stage, label), fontsize=8)
        ax.set_xlabel("time (s)")
    axes[0].set_ylabel("frequency (Hz)")
    fig.colorbar(im, ax=axes, label="dB")
    return fig


def validation_table(per: dict) -> pd.DataFrame:
    rows = []
    for name, v in per.items():
        conf = v.get("confirmation") or {}
        rows.append({"surrogate": name, "R²": v.get("r2"), "R²adj": v.get("r2_adj"),
                     "Q² LOO": v.get("q2_loo"), "Q² k-fold": v.get("q2_kfold"),
                     "RMSE": v.get("rmse"),
                     "max VIF": max(v["vif"].values()) if v.get("vif") else None,
                     "confirm RMSE": conf.get("rmse"), "PI coverage": conf.get("coverage")})
    return pd.DataFrame(rows).set_index("surrogate").astype(float)


#: The column of :func:`validation_table` a validation's note (by its key) concerns.
VALIDATION_COLUMN = {"r2": "R²", "q2_loo": "Q² LOO", "q2_kfold": "Q² k-fold"}

#: Why a column of :func:`validation_table` can be empty for every surrogate.
EMPTY_COLUMN_REASON = {
    "confirm RMSE": "the stage has no confirmation runs (stage confirmation_runs = 0)",
    "PI coverage": "the stage has no confirmation runs (stage confirmation_runs = 0)",
    "R²adj": "no surrogate of the stage has a parametric form with a number of terms",
    "max VIF": "too few runs for variance inflation factors",
    "Q² k-fold": "too few runs for k-fold refits",
}


def drop_empty_columns(frame: pd.DataFrame, noted: Sequence[str] = ()
                       ) -> tuple[pd.DataFrame, list[str]]:
    """``frame`` without the columns that are NaN in every row, and one line per dropped
    column saying why (:data:`EMPTY_COLUMN_REASON`, or the validation's notes for the
    columns in ``noted``)."""
    empty = [c for c in frame.columns if frame[c].isna().all()]
    by_reason: dict[str, list[str]] = {}
    for c in empty:
        why = "the notes above say why" if c in noted else \
            EMPTY_COLUMN_REASON.get(c, "nothing to show")
        by_reason.setdefault(why, []).append(c)
    why = [f"{' and '.join(cols)}: left out, {reason}." for reason, cols in by_reason.items()]
    return frame.drop(columns=empty), why


def _dropped_shown(frame):
    """The terms table with the p of a dropped coefficient (estimate 0 and p NaN, as
    MATLAB reports one) written as "dropped" instead of "nan"."""
    shown = frame.copy()
    for side in ("paper", "as Fig. 10b:"):
        est, p = f"{side} estimate", f"{side} p"
        dropped = shown[p].isna() & (shown[est] == 0)
        shown[p] = shown[p].astype(object).where(~dropped, "dropped")
    return shown


def comparison_section(page, result) -> None:
    """The study's Eq. 18 results beside the published ones its ``[compare_with]`` names
    (:mod:`sensfw.analysis.paper_comparison`): R²adj and significant terms per response,
    each term's sign and significance, and why terms differ."""
    from ..analysis.paper_comparison import comparison_for

    comp = comparison_for(result)
    ref = comp.reference
    page.h2(f"Beside the paper: stage {comp.stage} and {ref.key} (Fig. 10b)")
    page.p(ref.citation, "meta")
    page.p("Paper: " + "; ".join(f"{k} {v}" for k, v in ref.meta.items()) + f". Factors "
           f"({ref.doe.get('source', '')}): " + "; ".join(
               f"{x} {f['name']} = {comp.factors.get(x, '?')} "
               f"({' / '.join(f'{v:g}' for v in f['levels'])} {f['unit']})"
               for x, f in ref.factors.items()) + ".")
    for n in comp.notes:
        page.note(n)
    page.table(comp.summary.T, index=True)
    page.p(f"Significant: p < {ref.alpha:g}. 'paper Fig. 10b' is the table, 'paper text' the "
           "terms Sect. 3.2 names (a subset of the table's). 'sensfw' is this study's Eq. 18 "
           "(coded fit with an intercept, coefficients in physical units); 'sensfw as Fig. "
           "10b' the same runs fitted the way the paper's table was (physical values, the "
           "columns a MATLAB-style rank check keeps).", "meta")
    page.h3("Why the terms differ")
    for line in comp.reasons:
        page.p(line)
    page.table(comp.effects * 100, floatfmt="{:.2f}")
    page.p("Main effect of each factor in this study: range of its level means in % of the "
           "score's range over the runs.", "meta")
    for r, frame in comp.terms.items():
        pub = ref.responses[r]
        page.h3(f"{pub.name}: every Eq. 18 term ({pub.source}; sensfw score "
                f"{comp.summary.loc[r, 'sensfw score']})")
        page.table(_dropped_shown(frame), highlight=frame["agreement (as Fig. 10b)"]
                   .str.startswith("both significant"))
        page.p("Highlighted: significant in both, as Fig. 10b. Estimates in physical units; "
               "the paper's response units are not stated, so compare signs, not sizes.",
               "meta")


def agreement_section(page, result) -> None:
    """Whether the study reaches the conclusions of the fuller pipeline its ``[agree_with]``
    names (:mod:`sensfw.analysis.agreement`): run counts, the screen's selection, and per
    score the second stage's predictions and significant terms."""
    from ..analysis.agreement import MUST, MUST_NOT, agreement_for
    from ..errors import AnalysisError

    spec = result.study.spec.agree_with
    page.h2(f"Agreement with the full pipeline ({spec.results})")
    try:
        agr = agreement_for(result)
    except AnalysisError as err:
        page.note(f"Not measured: {err}. Run the full pipeline into that folder first "
                  "(e.g. sensfw run studies/paper.toml --out out/paper).")
        return
    page.p(f"This study: {agr['runs']} runs; the full pipeline: {agr['reference_runs']} runs "
           f"({agr['folder']}).")
    page.p(f"Screen: selected {', '.join(agr['selected']) or 'none'}; the full pipeline "
           f"selected {', '.join(agr['reference_selected']) or 'none'}: "
           + ("the same set." if agr["screen"] else "a different set."),
           "ok" if agr["screen"] else "note")
    rows = {}
    for label, a in agr["scores"].items():
        if "error" in a:
            rows[label] = {"surrogate": a["error"]}
            continue
        rows[label] = {"surrogate": a["surrogate"], "Q² LOO": a["q2_loo"],
                       "RMSE on the full factorial's other runs": a["rmse"],
                       "its LOO RMSE": a["rmse_loo_reference"], "ratio": a["ratio"],
                       "predicts": "yes" if a["predicts"] else "no",
                       "terms missed": ", ".join(a["missed"]) or "none",
                       "terms flagged wrongly": ", ".join(a["wrong"]) or "none",
                       "same set at p < 0.05": "yes" if a["strict"] else "no"}
    if rows:
        frame = pd.DataFrame.from_dict(rows, orient="index")
        frame.index.name = "score"
        page.table(frame)
    page.p("Predicts: the surrogate (Eq. 18 or the Gaussian process, whichever has the higher "
           "leave-one-out Q² on this study's runs) predicts the full factorial's runs this "
           "study did not make within the full factorial's own leave-one-out RMSE. Terms: "
           f"Eq. 18 on coded variables flags every term the full factorial has at p < {MUST:g}"
           f" and none it has at p > {MUST_NOT:g}.", "meta")
    verdict = ("reaches the full pipeline's conclusions" if agr["reached"] else
               "does not reach every conclusion of the full pipeline")
    page.p(f"With {agr['runs']} runs instead of {agr['reference_runs']} this study {verdict}.",
           "ok" if agr["reached"] else "note")


def _time_signals(result, stage) -> bool:
    """Whether the stage's runs are swept time signals (not a function model's scalars)."""
    for key in stage.keys:
        sig = _signals(result, key)
        if sig is not None:
            return sig.f_inst is not None and len(sig.t) >= 256
    return False


def _num(value, fmt: str) -> str:
    """``value`` formatted, or "n/a" where it is missing or not finite (a score that does
    not vary has no R² and no F)."""
    if value is None or not np.isfinite(float(value)):
        return "n/a"
    return format(float(value), fmt)


def _coef_table(reg: dict) -> tuple[pd.DataFrame, pd.Series]:
    frame = pd.DataFrame(reg["coefficients"]).set_index("term")
    sig = (pd.to_numeric(frame["p"], errors="coerce") < 0.05).fillna(False)
    frame = frame.astype(object).where(frame.notna(), "n/a")
    return frame, sig


def _step_note(result) -> str:
    """How many runs took a smaller step than the study's, and why (auto_step)."""
    from ..runs.store import run_step

    steps = [run_step(result.store, k) for st in result.stages for k in st.keys]
    adaptive = [s for s in steps if "adaptive" in s.get("integrator", "")]
    verlet = [s for s in steps if s.get("integrator") == "VelocityVerlet"]
    smaller = [s for s in steps if s not in adaptive and s not in verlet
               and s.get("step", result.study.solver.step)
               < result.study.solver.step * (1 - 1e-9)]
    note = ""
    if smaller:
        why = sorted({s.get("step_limited_by", "divergence") for s in smaller})
        note += (f" {len(smaller)} of {len(steps)} runs used a smaller step (down to "
                 f"{min(s['step'] for s in smaller) * 1e6:.3g} µs), set per run so that RK4 "
                 f"resolves the model's fastest linearised eigenvalues (limited by: "
                 f"{'; '.join(why)}).")
    if verlet:
        h = [s["step"] for s in verlet]
        note += (f" {len(verlet)} of {len(steps)} runs, whose over-damped eigenvalues "
                 f"(friction stick band) lie beyond RK4's stability at the study's step, "
                 f"were integrated with velocity Verlet (one right-hand side per step) at "
                 f"{min(h) * 1e6:.3g}-{max(h) * 1e6:.3g} µs.")
    if adaptive:
        mean = [s["mean_step"] for s in adaptive if "mean_step" in s]
        note += (f" {len(adaptive)} of {len(steps)} runs, whose over-damped eigenvalues "
                 f"(friction stick band, damped contacts) would have forced a much smaller "
                 f"fixed step, were integrated with {adaptive[0]['integrator']} steps under "
                 f"error control (tolerance solver.tolerance = {result.study.solver.tolerance:g})"
                 + (f", mean step {min(mean) * 1e6:.3g}-{max(mean) * 1e6:.3g} µs" if mean
                    else "") + ", resampled onto the output grid.")
    return note


def write_study_report(result, path: str | Path) -> Path:
    study = result.study
    ex = study.excitation
    c = result.counts
    page = Page(f"sensfw study report: {study.name}", study.spec.study.description)
    page.p(f"Model {study.spec.model.name}, output channel {study.output}; log chirp "
           f"{ex.f0:g} Hz -> {ex.f1:g} Hz in {ex.duration:g} s at {ex.fs:g} Hz, amplitude "
           f"{ex.amplitude:g} N; solver {study.solver.method}, step {study.solver.step:g} s."
           + _step_note(result))
    page.p(f"Runs: {c.total} in total, {c.new} computed now, {c.cached} from the run store, "
           f"{c.failed} failed.")
    if c.failed:
        page.note(f"{c.failed} run(s) failed; the analyses below use the others (see each "
                  "stage).")
    if result.stopped is not None:
        page.note(f"The study stopped at stage {result.stopped['stage']!r}: "
                  f"{result.stopped['error']}. The stages before it are below; every run is "
                  "in the run store, so the study run again simulates only what is missing.")
    for stage in result.stages:
        groups = stage.spec.groups
        page.h2(f"Stage {stage.name}: {stage.spec.design} on {len(stage.space)} variables"
                + (f" in {len(groups)} groups" if groups else "")
                + f", {len(stage.table)} runs")
        for n in stage.notes:
            page.note(n)
        signals = _time_signals(result, stage)
        if stage.selected is not None and signals:
            page.figure(frf_overlay(result, stage, study.output),
                        "Fig. 7 analogue: FRFs (Hv) of the min (dashed) and max (solid) runs of "
                        "the most sensitive variables over the nominal reference.")
        if stage.selected is not None:
            by = stage.spec.select.by or stage.spec.scorers[0].key
            scorer = next((s for s in stage.spec.scorers if s.key == by), None)
            what = "the FRF scalar" if scorer is not None and scorer.name == "frf_scalar" \
                else f"the score {by}"
            page.figure(sensitivity_bars(stage, stage.spec.select.threshold),
                        f"Fig. 8 analogue: normalised sensitivity from {what}.")
            page.p("Selected for the next stage: " + (", ".join(
                f"{g} ({', '.join(groups[g])})" if g in groups else g
                for g in stage.selected) or "none"), "ok")
        elif stage.screening is not None:
            page.figure(sensitivity_bars(stage, None), f"{stage.spec.design}: importance")
        if stage.screening is not None:
            tab = stage.screening.table
            page.table(tab if isinstance(tab, pd.DataFrame) else pd.DataFrame(tab))
        if stage.surrogates and signals:
            page.figure(order_spectrum_mean(result, stage, study.output),
                        "Fig. 9 analogue: averaged order spectrum of the stage's runs.")
        if any(stage.surrogates.values()):
            page.figure(actual_vs_predicted(stage),
                        "Fig. 10a analogue: simulated against predicted scores.")
            for label, reg in stage.regression.items():
                page.h3(f"{label}: Eq. 18 ({reg['surrogate']}) R²={_num(reg['r2'], '.4f')}, "
                        f"R²adj={_num(reg['r2_adj'], '.4f')}, Q²(LOO)={_num(reg['q2'], '.4f')}, "
                        f"F={_num(reg['f_stat'], '.4g')} (p={_num(reg['f_pvalue'], '.3g')}), "
                        f"n={reg['n_obs']}")
                frame, sig = _coef_table(reg)
                page.table(frame, highlight=sig)
                page.p("Highlighted: p < 0.05. Coefficients in physical units (Fig. 10b).",
                       "meta")
            for label, per in stage.validation.items():
                if not per:  # a section with nothing to show says so in one line
                    page.p(f"{label}: no surrogate could be fitted to this score (the stage's "
                           "notes above say why).", "meta")
                    continue
                used = sorted({v.get("n_obs") for v in per.values()} - {None})
                runs = f"same {used[0]} runs" if len(used) == 1 else \
                    f"{', '.join(map(str, used))} runs"
                failed = stage.table.shape[0] - max(used, default=stage.table.shape[0])
                page.h3(f"{label}: surrogates side by side ({runs}"
                        + (f"; {failed} of the stage's {stage.table.shape[0]} runs have no "
                           "score" if failed > 0 else "") + ")")
                noted = set()
                for name, v in per.items():
                    for key, n in (v.get("notes") or {}).items():
                        column = VALIDATION_COLUMN.get(key, key)
                        page.note(f"{name}: {column}: {n}")
                        noted.add(column)
                frame, dropped = drop_empty_columns(validation_table(per), sorted(noted))
                page.table(frame.astype(object).where(frame.notna(), "n/a"))
                page.p("R²adj and Q² on the scale of the score; Q² from leave-one-out and "
                       "5-fold refits; confirmation = new runs inside the bounds; n/a: the "
                       "surrogate has no such number (no parametric form for R²adj, a run of "
                       "leverage 1 for Q² LOO).", "meta")
                for line in dropped:
                    page.p(line, "meta")
                for name in per:
                    page.figure(residual_plots(stage, label, name),
                                f"{label} / {name}: residuals against fitted values, normal Q-Q.")
            if signals:
                page.figure(spectrograms(result, stage, study.output),
                            "Fig. 11 analogue: spectrograms of the first and last run.")
    if study.spec.compare_with is not None:
        comparison_section(page, result)
    if study.spec.agree_with is not None:
        agreement_section(page, result)
    return page.write(path)
