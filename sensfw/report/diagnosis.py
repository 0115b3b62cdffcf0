"""Reports of ``sensfw diagnose`` (which effect is missing, where, with what base parameters)
and ``sensfw augment`` (the effect added and calibrated: the error falls, per level)."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..measure.discrepancy import RESIDUAL_ERROR
from .html import Page


def _fmt(v) -> str:
    return "" if v is None else f"{v:.4g}"


def calibration_table(rows: list[dict]) -> pd.DataFrame:
    """Calibrated values with their 95 % intervals and flags (bound, identifiability)."""
    return pd.DataFrame([{
        "parameter": r["name"], "unit": r["unit"], "nominal": _fmt(r["nominal"]),
        "calibrated": _fmt(r["value"]),
        "95 % interval": f"[{_fmt(r['interval'][0])}, {_fmt(r['interval'][1])}]",
        "bounds": f"[{_fmt(r['bounds'][0])}, {_fmt(r['bounds'][1])}]",
        "flags": "; ".join(r["flags"])} for r in rows]).set_index("parameter")


def frf_levels(pairs: dict[str, list], title: str):
    """Measured FRF of every level next to the models in ``pairs`` (label -> comparisons)."""
    first = next(iter(pairs.values()))
    n = len(first)
    fig, axes = plt.subplots(1, n, figsize=(min(5.5 * n, 16), 4), squeeze=False)
    styles = ["--", "-.", ":", (0, (5, 1))]
    for i, ax in enumerate(axes[0]):
        c0 = first[i]
        ax.semilogx(c0.f, c0.db_measured, color="k", lw=1.5, label="measured")
        for j, (label, comps) in enumerate(pairs.items()):
            if comps is None:
                continue
            c = comps[i]
            ax.semilogx(c.f, c.db_model, lw=1.1, ls=styles[j % len(styles)], label=label)
        ax.set_title(f"level {c0.level:.3g} {c0.unit}")
        ax.set_xlabel("frequency (Hz)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("|H| (dB, 1/24-octave smoothed)")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(title)
    return fig


def resonance_levels(pairs: dict[str, list]):
    """Frequency of the strongest measured resonances against level, measured and each
    model's nearest peak (within 5 %), as a shift from the measured frequency at the lowest
    level: the amplitude dependence the winner must reproduce."""
    first = next(iter(pairs.values()))
    levels = [c.level for c in first]
    top = sorted(first[0].peaks_measured, key=lambda p: -p["prominence_db"])[:3]
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    colors = plt.cm.tab10(np.arange(10))
    styles = [("--", "x"), (":", "+"), ("-.", "^"), ((0, (1, 3)), "v")]

    def track(comps, which: str, f_ref: float) -> np.ndarray:
        out = []
        for c in comps:
            peaks = c.peaks_measured if which == "measured" else c.peaks_model
            near = [p["frequency"] for p in peaks if abs(np.log(p["frequency"] / f_ref)) < 0.05]
            out.append(min(near, key=lambda f: abs(f - f_ref)) if near else np.nan)
        return 100 * (np.array(out) / f_ref - 1)

    for k, ref in enumerate(top):
        f_ref = ref["frequency"]
        ax.plot(levels, track(first, "measured", f_ref), "o-", color=colors[k], lw=2,
                label=f"measured {f_ref:.0f} Hz")
        for j, (label, comps) in enumerate(pairs.items()):
            if comps is not None:
                ls, marker = styles[j % len(styles)]
                ax.plot(levels, track(comps, "model", f_ref), ls=ls, marker=marker,
                        color=colors[k], lw=1, label=label if k == 0 else None)
    ax.set_xscale("log")
    unit = getattr(first[0], "unit", "")
    ax.set_xlabel(f"excitation level ({unit})" if unit else "excitation level")
    ax.set_ylabel("shift from measured at lowest level (%)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    ax.set_title("Amplitude dependence: resonances against level")
    return fig


def _record_label(level: float, kind: str) -> str:
    return f"{level:.3g}" + (f" {kind.replace('_', ' ')}" if kind else "")


def _search_text(criteria: dict) -> str:
    """How each calibration searched (``diagnose``'s ``global_phase``)."""
    if criteria.get("global_phase", True):
        return ("Each calibration is global: a space-filling design, a surrogate of the "
                "whole residual vector (principal components, one Gaussian process each) "
                "that chooses new runs by its optimum and its lower confidence bound, then "
                "derivative-free least squares (DFO-LS) from the best two points.")
    return ("Each calibration is a local least squares (Levenberg-Marquardt with "
            "finite-difference Jacobians) from the best run of its hypothesis so far "
            "(diagnose --local); the residual surrogate below is fitted afterwards to "
            "every run, to show how regular the response is where the search ended.")


def _surrogate_cell(q: dict | None) -> str:
    """The residual surrogate's leave-one-out error per entry (in standard errors of the
    entries) over its best quarter of runs, and its runs."""
    if not q:
        return ""
    return (f"{q['loo_rms_per_entry_best']:.2f} (all {q['loo_rms_per_entry']:.2f}; "
            f"{q['runs']} runs)")


def write_diagnose_report(study, result, path) -> Path:
    """``result`` is a :class:`sensfw.measure.diagnose.DiagnoseResult`."""
    page = Page(f"sensfw: which physical effect is missing? ({study.name})",
                f"verdict: {result.verdict} — {result.n_simulations} simulations")
    page.p(f"Verdict: {result.verdict}: {result.reason}.", "ok" if result.verdict != "none"
           else "note")
    if result.simulations_by_step:
        page.p(f"Simulations ({result.n_simulations}, one per point and level, stored runs "
               "included) by step: " + ", ".join(
                   f"{k} {v}" for k, v in result.simulations_by_step.items()) + ".")
    page.p("Every hypothesis recalibrates the base parameters "
           f"({', '.join(result.variables)}, from {result.variables_from}): 'parameters' "
           "recalibrates them alone; each candidate effect is calibrated jointly with them. "
           + _search_text(result.criteria) + " Candidates share evidence: the "
           "runs of 'parameters' are every candidate's runs where the effect vanishes. The "
           "candidates are first raced on the level 'parameters' misfits most (their "
           "first look from the recalibrated base values and, where these moved far from "
           "the nominal ones, from the nominal ones too), the best calibrated there and "
           "the finalists at every level; the leading effect is then tried at its other "
           "places from its optimum, and what the verdict names is refined further "
           "where its search stopped on its budget short of the noise. The residuals are the dB "
           "differences per one-third-octave band (and THD) divided by their standard "
           "errors from the measurement's own noise; chi2 is their sum of squares, BIC = "
           "chi2 + k ln n. With several levels each is also judged on levels it was not "
           "calibrated on (held-out chi2 per entry).")
    page.h2("Base parameters recalibrated (hypothesis 'parameters')")
    h0 = result.rows[0]
    page.p(f"Residual error: nominal model {result.errors['nominal']:.2f} dB, recalibrated "
           f"{result.errors['parameters']:.2f} dB (chi2 {h0['chi2']:.1f} for "
           f"{result.n_entries} entries; "
           + ("more than the noise explains" if not h0["fits_noise"] else
              "the noise explains what is left" if not result.named else
              "within the noise's chi-square bound, but the named effect explains far "
              "more of it: an effect's own distortion counts in the measured noise") + ").")
    page.p(RESIDUAL_ERROR[0].upper() + RESIDUAL_ERROR[1:] + ".", "meta")
    page.table(calibration_table(h0["calibration"]))
    page.h2("Candidates")
    if result.signature_classes:
        page.p("Signature classes of the discrepancy across levels: "
               + ", ".join(sorted(result.signature_classes)) + " (candidates whose "
               "signatures do not match were left out).")
    page.p("Surrogate LOO: the leave-one-out error of each hypothesis's residual surrogate "
           "per entry, in standard errors of the entries (1 = the measurement's noise), "
           "over its best quarter of runs, where the search ended: well below 1, the "
           "surrogate saw the optimum's neighbourhood as the runs do; above 1, the search "
           "there was guided by a surrogate that does not know the response, and the "
           "calibration rests on the local refinement alone.")
    calibrated = [r for r in result.rows if r["surrogate"]]
    rows = [{"hypothesis": r["hypothesis"], "k": r["k"],
             "chi2/entry": r["chi2_per_entry"], "ΔBIC": r.get("delta_bic", 0.0),
             "held-out chi2/entry": r["heldout_chi2_per_entry"],
             "surrogate LOO": _surrogate_cell(r["surrogate"]),
             "effect values": ", ".join(
                 f"{c['name']}={c['value']:.4g}" + (f" ({'; '.join(c['flags'])})"
                                                    if c["flags"] else "")
                 for c in r["calibration"] if c["name"] not in result.variables),
             "notes": "; ".join(r["notes"])} for r in calibrated]
    if rows:
        frame = pd.DataFrame(rows).set_index("hypothesis")
        page.table(frame, highlight=pd.Series([r["hypothesis"] in result.named
                                               for r in calibrated]))
    else:
        page.p(f"No candidate was calibrated: the budget ({result.criteria.get('budget')} "
               f"simulations, {result.n_simulations} spent) left no room after the base "
               "parameters and the first looks.", "meta")
    screened = [r for r in result.rows[1:] if not r["surrogate"] and r["screen"]]
    if screened:
        page.p(f"{len(screened)} more candidates were screened on one level only (not "
               "calibrated); best five by their screen's score (chi2 on that level, the "
               "lower of a run and its linearised joint fit, from H0's base values or "
               "from the nominal ones where H0 moved far from them):")
        best = sorted(screened, key=lambda r: r["screen"].get("score", np.inf))[:5]
        page.table(pd.DataFrame([{"hypothesis": r["hypothesis"],
                                  "first look": r["screen"].get("first_look"),
                                  "score": r["screen"].get("score"),
                                  "looked from": r["screen"].get("looked_from", "H0")}
                                 for r in best]).set_index("hypothesis"))
    fig, ax = plt.subplots(figsize=(10, 3.6))
    x = np.arange(len(rows))
    ax.bar(x - 0.2, [r["chi2/entry"] for r in rows], 0.4, label="calibrated (all levels)")
    held = [r["held-out chi2/entry"] for r in rows]
    if any(h is not None for h in held):
        ax.bar(x + 0.2, [h or 0 for h in held], 0.4, label="held-out levels")
    ax.axhline(1.0, color="k", lw=0.8, ls="--", label="noise alone")
    ax.set_xticks(x, [r["hypothesis"] for r in rows], rotation=25, fontsize=7, ha="right")
    ax.set_yscale("log")
    ax.set_ylabel("chi2 per entry")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    page.figure(fig, "Each calibrated hypothesis (1 = what the noise alone leaves).")
    for name in result.named:
        win = next(r for r in result.rows if r["hypothesis"] == name)
        page.h2(f"Named: {name}")
        page.table(calibration_table(win["calibration"]))
        for t in win.get("trades", []):
            page.note(f"{t['a']} and {t['b']} trade against each other (correlation "
                      f"{t['correlation']:+.2f}): these data see a combination of them.")
    pairs = {"nominal model": result.nominal, "parameters recalibrated": result.calibrated}
    if result.best is not None:
        pairs[result.named[0]] = result.best
    page.figure(frf_levels(pairs, "FRF per level"), "Measured (black) against the models.")
    if len(result.nominal) >= 2:
        page.figure(resonance_levels({k: v for k, v in pairs.items() if k != "nominal model"}),
                    "Resonance frequencies against level: measured and models.")
    return page.write(path)


def write_augment_report(study, result: dict, path, comparisons: dict | None = None) -> Path:
    page = Page(f"sensfw: model augmented with {result['effect']}@{result['attach']} "
                f"({study.name})", f"{result['n_simulations']} simulations")
    tr = result["trajectory"]
    levels = tr[0]["levels"]
    fig, ax = plt.subplots(figsize=(9, 3.8))
    width = 0.8 / len(tr)
    for i, t in enumerate(tr):
        per = t["error_per_level"] or [t["error"]] * len(levels)  # None: its runs failed
        x = np.arange(len(per)) + (i - (len(tr) - 1) / 2) * width
        ax.bar(x, [np.nan if e is None else e for e in per], width, label=t["step"])
        for xi, e in zip(x, per, strict=True):
            ax.text(xi, 0 if e is None else e, "failed" if e is None else f"{e:.2f}",
                    ha="center", va="bottom", fontsize=7)
    kinds = tr[0].get("kinds") or [""] * len(levels)
    ax.set_xticks(np.arange(len(levels)), [_record_label(lv, k) for lv, k in
                                           zip(levels, kinds, strict=True)])
    ax.set_xlabel("record (level, kind)")
    ax.set_ylabel("residual error (dB RMS)")
    ax.set_title("The error falls, level by level")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    page.figure(fig, "Error trajectory per level: nominal model, base parameters "
                     "recalibrated, the effect added at its nominal values, jointly "
                     "calibrated.")
    page.table(pd.DataFrame([{"step": t["step"], "residual error (dB RMS)": t["error"]}
                             for t in tr]).set_index("step"))
    page.p(RESIDUAL_ERROR[0].upper() + RESIDUAL_ERROR[1:] + ".", "meta")
    page.h2("Calibrated values")
    page.table(calibration_table(result["calibration"]))
    if result.get("surrogate"):
        page.p("Residual surrogate of the joint calibration, leave-one-out error per entry "
               f"(standard errors): {_surrogate_cell(result['surrogate'])}.")
    for t in result.get("trades", []):
        page.note(f"{t['a']} and {t['b']} trade against each other (correlation "
                  f"{t['correlation']:+.2f}): these data see a combination of them.")
    for n in result.get("notes", []):
        page.note(n)
    if comparisons:
        page.figure(frf_levels({k: v for k, v in comparisons.items() if v is not None},
                               "FRF per level"), "Measured (black) against each step.")
        if len(levels) >= 2:
            page.figure(resonance_levels({k: v for k, v in comparisons.items()
                                          if k != "nominal model" and v is not None}),
                        "Resonance frequencies against level.")
    return page.write(path)


def _fits_plainly(result: dict) -> bool:
    """The calibrated point passes the noise's test, and not only through the model's own
    scatter there (``fits_noise_without_scatter``; absent in older results: not asked)."""
    return bool(result["fits_noise"]) and result.get("fits_noise_without_scatter") is not False


def _noise_verdict(result: dict) -> str:
    if not result["fits_noise"]:
        return "more is left than the noise explains."
    if not _fits_plainly(result):
        return ("the noise explains what is left only with the model's own scatter at "
                "this point counted (notice below).")
    return "the noise explains what is left."


def write_calibrate_report(study, result: dict, path, comparisons: dict | None = None
                           ) -> Path:
    page = Page(f"sensfw: base parameters calibrated ({study.name})",
                f"{result['n_simulations']} simulations")
    tr = result["trajectory"]
    page.p(f"Calibrated {', '.join(result['variables'])} ({result['variables_from']}) on "
           f"{len(tr[0]['levels'])} level(s), channels {', '.join(result['channels'])}: "
           f"residual error {tr[0]['error']:.2f} dB -> {tr[1]['error']:.2f} dB; "
           + _noise_verdict(result), "ok" if _fits_plainly(result) else "note")
    page.p(RESIDUAL_ERROR[0].upper() + RESIDUAL_ERROR[1:] + ".", "meta")
    for n in result.get("notes", []):
        page.note(n)
    page.table(calibration_table(result["calibration"]))
    if result.get("surrogate"):
        page.p("Residual surrogate, leave-one-out error per entry (standard errors): "
               f"{_surrogate_cell(result['surrogate'])}.")
    kinds = tr[0].get("kinds") or [""] * len(tr[0]["levels"])
    page.table(pd.DataFrame([{"record": _record_label(lv, kinds[i]),
                              **{t["step"]: t["error_per_level"][i] for t in tr}}
                             for i, lv in enumerate(tr[0]["levels"])]).set_index("record"))
    if comparisons:
        page.figure(frf_levels(comparisons, "FRF per level"), "Measured (black) against the "
                    "nominal and the calibrated model.")
    return page.write(path)


def _write_json(path: Path, data) -> None:
    import json

    from ..results import jsonable

    path.write_text(json.dumps(jsonable(data), indent=1))


def write_diagnosis(out_dir, study, result, wall_s: float | None = None) -> dict:
    """``out_dir/diagnose.json`` and ``out_dir/report.html`` of a diagnosis; returns the
    JSON data."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    data = {**result.to_dict(), "wall_s": wall_s}
    _write_json(out_dir / "diagnose.json", data)
    write_diagnose_report(study, result, out_dir / "report.html")
    return data


def _write_study_result(out_dir, study, result: dict, json_name: str, write_report) -> None:
    """``out_dir/study.toml`` (``result["study_text"]``, checked to load), ``json_name`` (the
    result without its comparisons and study text) and ``report.html`` by ``write_report``."""
    from ..study import Study

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if result.get("study_text") is not None:
        (out_dir / "study.toml").write_text(result["study_text"], encoding="utf-8")
        Study.load(out_dir / "study.toml")  # the written file must itself be valid
    comps = result.get("_comparisons")
    _write_json(out_dir / json_name, {k: v for k, v in result.items()
                                      if k not in ("_comparisons", "study_text")})
    write_report(study, result, out_dir / "report.html", comps)


def write_augmentation(out_dir, study, result: dict) -> None:
    """``out_dir/study.toml`` (the augmented study, checked to load), ``augment.json`` and
    ``report.html`` of :func:`sensfw.measure.augment.augment`."""
    _write_study_result(out_dir, study, result, "augment.json", write_augment_report)


def write_calibration(out_dir, study, result: dict) -> None:
    """``out_dir/study.toml`` (the calibrated study), ``calibrate.json`` and ``report.html``
    of :func:`sensfw.measure.recalibrate.recalibrate`."""
    _write_study_result(out_dir, study, result, "calibrate.json", write_calibrate_report)
