"""Reports of the measurement commands: compare, diagnose, augment."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from ..measure.prediction import FORM_Z
from .html import Page
from .measure_figures import (
    amplitude_plot,
    band_errors,
    band_plot,
    frf_overlay,
    jump_plot,
    order_spectra,
    plotted_tracks,
    spectrograms,
)


def amplitude_frames(amplitude: dict, output_unit: str | None = None
                     ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The amplitude-dependence table as two frames: resonances per level, harmonics and
    DC per level (in ``output_unit``, the compared channel's, where given)."""
    dc = f" ({output_unit})" if output_unit else ""
    res = []
    for r in amplitude["table"]["resonances"]:
        for x in r["levels"]:
            if x["measured_hz"] is None and x["model_hz"] is None:
                continue
            res.append({"resonance": f"{r['id']} ({r['kind']})", "level": x["level"],
                        "measured Hz": x["measured_hz"], "model Hz": x["model_hz"],
                        "measured vs model %": x["shift_pct"], "measured ζ": x["measured_damping"],
                        "model ζ": x["model_damping"], "ζ ratio": x["damping_ratio"],
                        "method": x["method"],
                        "model's own scatter %": x.get("model_scatter_pct")})
    harm = []
    for h in amplitude["table"]["harmonics"]:
        row = {"level": h["level"]}
        for k in (2, 3):
            row[f"H{k}/H1 measured"] = h[f"h{k}_measured"]
            row[f"H{k}/H1 model"] = h[f"h{k}_model"]
            row[f"H{k}/H1 floor"] = h[f"h{k}_floor"]
        row.update({"THD measured %": h["thd_measured"], "THD model %": h["thd_model"],
                    f"DC measured{dc}": h["dc_measured"], f"DC model{dc}": h["dc_model"],
                    f"DC std. error{dc}": h["dc_standard_error"]})
        harm.append(row)
    def blank(frame):  # empty cells rather than NaN
        return frame.astype(object).where(frame.notna(), "")

    frame = pd.DataFrame(res)
    twins = "model's own scatter %"
    if twins in frame and frame[twins].isna().all():  # no twin runs
        frame = frame.drop(columns=twins)
    elif twins in frame:  # infinite: a twin has no peak there; round-off (1e-13 %) is 0.00
        frame[twins] = frame[twins].map(
            lambda v: v if v is None or np.isnan(v) else
            "a twin has none" if np.isinf(v) else f"{v:.2f}")

    return blank(frame), blank(pd.DataFrame(harm))


def amplitude_section(page, amplitude: dict, unit: str = "N",
                      output_unit: str | None = None) -> None:
    """Sentences, plot and tables of :func:`sensfw.measure.signatures.amplitude_dependence`
    (one line where there is a single level, or nothing to plot)."""
    page.h2("Amplitude dependence")
    levels = amplitude.get("levels") or []
    if len(levels) < 2:
        page.p("One level only: nothing to compare across levels.")
        return
    found = amplitude.get("classes") or {}
    if found:
        page.p("Signature classes of the discrepancy: " + ", ".join(
            c.replace("_", " ") for c in found) + ".", "note")
    for line in amplitude.get("sentences", []):
        page.p(line, "note" if found else "ok")
    table = amplitude["table"]
    has_harm = any(h[f"h{k}_{w}"] for h in table["harmonics"] for k in (2, 3)
                   for w in ("measured", "model"))
    if plotted_tracks(table) or has_harm:
        page.figure(amplitude_plot(amplitude, unit),
                    "Resonance frequency and damping ratio (single-mode fit where both FRFs "
                    "allow it, else half-power)" + (" and harmonic ratios" if has_harm else "")
                    + " against the excitation level: measured (solid) and model (dashed). "
                    "The classes judge the measured trend relative to the model's own.")
    else:
        page.p("No resonance prominent at two levels or more, and no harmonics: no plot.")
    res, harm = amplitude_frames(amplitude, output_unit)
    if not res.empty:
        page.table(res, index=False)
    if has_harm:
        page.table(harm, index=False)


def _resonance_frame(rows) -> pd.DataFrame:
    """A record's resonance table, headed plainly."""
    names = {"measured_hz": "measured (Hz)", "model_hz": "model (Hz)",
             "shift_pct": "model vs measured (%)", "measured_damping": "ζ measured",
             "model_damping": "ζ model", "note": ""}
    frame = pd.DataFrame(rows)[list(names)].rename(columns=names)
    return frame.astype(object).where(frame.notna(), "")


def _harmonic_frame(rows, output_unit: str | None = None) -> pd.DataFrame:
    """A record's harmonic table, headed plainly; the amplitudes in ``output_unit``."""
    unit = f" ({output_unit})" if output_unit else ""
    names = {"order": "order", "model": f"model P_k{unit}", "measured": f"measured P_k{unit}",
             "model_ratio": "model P_k/P_1", "measured_ratio": "measured P_k/P_1",
             "measured_floor_ratio": "measured noise floor", "difference_db":
             "model - measured (dB)"}
    frame = pd.DataFrame(rows)[list(names)].rename(columns=names)
    return frame.astype(object).where(frame.notna(), "")


def _small(x: float) -> str:
    """Two decimals, or two significant digits below 0.1 (a noise floor far below the
    figure beside it reads as its size, not as 0.00)."""
    return f"{x:.2f}" if abs(x) >= 0.1 else f"{x:.2g}"


def _summary(comparisons) -> pd.DataFrame:
    """One row per record: its level as what it is, the error, the resonance."""
    rows = []
    for c in comparisons:
        res = [r for r in c.resonances if r["measured_hz"] and r["model_hz"]]
        peaks = {p["frequency"]: p["peak_db"] for p in c.peaks_measured}
        # the strongest measured peak that has a model partner
        r = max(res, key=lambda r: peaks.get(r["measured_hz"], -np.inf)) if res else None
        rows.append({
            "record": c.level_text, "file": Path(c.file).name if c.file else "",
            "FRF error (dB)": f"{c.error_db:.2f}",
            "noise alone (dB)": "" if c.error_noise_db is None else _small(c.error_noise_db),
            "model's own scatter (dB)": "" if c.error_scatter_db is None
            else f"{c.error_scatter_db:.2f}",
            # as the record's own resonance table prints it (the lines are Hz apart)
            "strongest resonance, measured (Hz)": f"{r['measured_hz']:.4g}" if r else "",
            "model (Hz)": f"{r['model_hz']:.4g}" if r else "",
            "THD measured / model (%)": f"{c.thd_measured:.2f} / {c.thd_model:.2f}"
            + (f" (noise alone {_small(c.thd_floor)})" if c.thd_floor else "")
            if c.thd_measured is not None and c.thd_model is not None else ""})
    frame = pd.DataFrame(rows)
    for col in ("noise alone (dB)", "model's own scatter (dB)", "THD measured / model (%)"):
        if not (frame[col] != "").any():  # no record has one (random records: no THD)
            frame = frame.drop(columns=col)
    return frame


def _band_frame(bands) -> pd.DataFrame:
    rows = []
    for b in bands:
        inside = b.contains_resonance
        rows.append({
            "record": b.file, "kind": b.kind.replace("_", " "), "level": f"{b.level:.3g}",
            "measured resonance (Hz)": b.resonance_measured,
            "model band (Hz)": "" if b.resonance_low is None else
            f"{b.resonance_low:.2f}-{b.resonance_high:.2f}",
            "inside": "" if inside is None else ("yes" if inside else "NO"),
            "band width at resonance": "" if b.width_db_at_resonance is None else
            f"{b.resonance_width_hz:.2f} Hz, {b.width_db_at_resonance:.2f} dB",
            "of it, model form (±)": "" if not b.form_records else
            f"{FORM_Z * b.form_hz:.2f} Hz, {FORM_Z * b.form_db:.2f} dB",
            "extrapolation": b.extrapolation or ""})
    frame = pd.DataFrame(rows)
    if not any(b.form_records for b in bands):
        frame = frame.drop(columns="of it, model form (±)")
    return frame


def prediction_section(page, comparisons, bands, error_band=None) -> None:
    """The prediction band of a calibrated study's model on each record."""
    page.h2("Prediction with the calibration's uncertainty")
    outside = [b for b in bands if b.contains_resonance is False]
    form = next((b for b in bands if b.form_records), None)
    page.p("The band spans the calibrated model at the points where the calibration's 95 % "
           "ellipsoid (its Laplace covariance) meets its principal axes: on each line the "
           "lowest and highest model FRF, and the lowest and highest resonance"
           + (f"; both widened on each side by {FORM_Z} times the RMS misfit of the "
              "calibrated model on the records it was fitted to (of the same kind where it "
              "fitted two or more; the model form's part, a lower bound of it)" if form
              else "; the calibration stored no misfit on its records, so the band holds "
              "the parameters' uncertainty only, not the model form's")
           + ". A measured resonance outside it is not predicted within the calibration's "
           "uncertainty. A record of a kind or at a level the calibration did not see is an "
           "extrapolation.", "note" if outside else "ok")
    page.table(_band_frame(bands), index=False)
    page.figure(band_plot(comparisons, bands, error_band),
                "Measured FRF (black) in the prediction band (blue) of the calibrated model "
                "(dashed); orange: the band of its resonance.")


def write_comparison(out_dir, study, result) -> None:
    """``out_dir/compare.json`` and ``out_dir/report.html`` of a comparison."""
    import json

    from ..results import jsonable

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "compare.json").write_text(json.dumps(jsonable(result.to_dict()), indent=1))
    write_compare_report(study, result, out_dir / "report.html")


def write_compare_report(study, result, path) -> Path:
    """The compare report of a :class:`~sensfw.measure.comparison.Comparison`: a summary
    table (one error figure per record, defined once), the FRFs, where the model fails,
    up/down jumps, the amplitude dependence, then per record its tables, order spectra and
    spectrograms; a section with nothing to show says so in one line."""
    from ..measure.comparison import ERROR_DEFINITION
    from ..measure.lines import jump_text

    comparisons, pairs = result.levels, result.pairs
    band = result.error_band
    page = Page(f"sensfw: model against measurement ({study.name})",
                f"output channel {study.output}; {len(comparisons)} record(s)"
                + (f"; error band {band[0]:g}-{band[1]:g} Hz" if band else ""))
    page.table(_summary(comparisons), index=False)
    page.p(ERROR_DEFINITION + (f" (here {band[0]:g}-{band[1]:g} Hz)" if band else "")
           + ". 'Noise alone': what the measurement's own noise gives a correct model over the "
           "same lines (its noise added to it again, three draws); an error near it is within "
           "the noise."
           + (" 'Model's own scatter': the same error between the model and its twins, runs "
              "whose drives differ by 1e-9 of their level; where it is not near zero the "
              "model's response is not determined by its drive (stick-slip under a random "
              "drive), a correct model gets about the root sum of squares of the two, and a "
              "resonance shift within it is no evidence." if any(
                  c.error_scatter_db is not None for c in comparisons) else ""))
    if result.notes:
        page.h2("Records and how the model was driven")
        for n in result.notes:
            page.p(n)
    lined = [c for c in comparisons if c.stepped]
    page.figure(frf_overlay(comparisons, error_band=band),
                "Measured (solid) and simulated (dashed) FRFs: "
                + ("Hv smoothed to 1/24 octave for time records" if len(lined) <
                   len(comparisons) else "")
                + ("; " if lined and len(lined) < len(comparisons) else "")
                + ("the steady-state lines of stepped-sine and FRF-only records"
                   + (" (markers)" if any(len(c.f) <= 120 for c in lined) else "")
                   if lined else "") + ".")
    if any(c.bands for c in comparisons):
        page.figure(band_errors(comparisons), "Mean FRF difference per band.")
    stepped = [c for c in comparisons if c.stepped]
    if stepped:
        page.h2("Up and down sweeps")
        if result.jumps:
            for j in result.jumps:
                page.p(jump_text(j), "note" if any(j[w] and j[w]["hysteresis_hz"]
                                                   for w in ("measured", "model")) else "ok")
            page.figure(jump_plot(comparisons, result.jumps),
                        "Up (solid) and down (dashed) sweeps at each level measured both "
                        "ways; shaded: where they differ by more than "
                        f"{result.jumps[0]['threshold_db']:g} dB.")
        else:
            page.p("No level was measured both up and down: no jump can be seen.")
    if result.amplitude:
        unit = comparisons[0].unit if comparisons else "N"
        amplitude_section(page, result.amplitude, unit,
                          comparisons[0].output_unit if comparisons else None)
    if result.bands:
        prediction_section(page, comparisons, result.bands, band)
    page.h2("Per record")
    for c in comparisons:
        page.h3(f"{c.level_text} ({c.file}): FRF error {c.error_db:.2f} dB")
        for n in c.notes:
            page.note(n)
        if c.settled_db:
            worst = max(c.settled_db.values())
            who = " and ".join(c.settled_db)
            page.p(f"Stepped lines settled to {worst:.2f} dB ({who}: the largest difference "
                   f"between the first and the second half of a step's fitted periods)"
                   + ("." if worst < 0.1 else ": a transient had not decayed at some line, "
                      "whose value is uncertain by about as much."),
                   "ok" if worst < 0.1 else "note")
        if c.resonances:
            page.table(_resonance_frame(c.resonances), index=False)
        else:
            page.p("No resonance in the band.")
        if c.harmonics:
            page.table(_harmonic_frame(c.harmonics, c.output_unit), index=False)
        elif c.kind == "random":
            page.p("Harmonics: none for a random record (no sweep to follow).")
        elif c.stepped and "measured" not in c.settled_db:
            page.p("Harmonics: none: the record holds FRFs only, no time data.")
        else:
            page.p("Harmonics: none below 0.45 fs.")
    sweeps = [(lv, m, x) for lv, m, x in pairs
              if getattr(m, "f_inst", None) is not None and steps_of_signals(m) is None]
    page.h2("Order spectra")
    if sweeps:
        page.figure(order_spectra(sweeps, study.output),
                    "Order spectra, measured and simulated (harmonics of the sweep at integer "
                    "orders).")
    else:
        page.p("None: no record holds the time data of a sweep (order spectra follow a "
               "sweep's frequency).")
    timed = [(lv, m, x) for lv, m, x in pairs if hasattr(m, "force")]
    page.h2("Spectrograms")
    if timed:
        for (_, meas, model), c in zip(pairs, comparisons, strict=True):
            if hasattr(meas, "force"):
                page.figure(spectrograms(meas, model, study.output, c.level_text),
                            "Spectrograms side by side (Fig. 11 style).")
    else:
        page.p("None: FRF-only records hold no time data.")
    return page.write(path)


def steps_of_signals(sig):
    """The steps of a stepped-sine record (None for a sweep or random record)."""
    from ..signal.stepped import steps_of

    return steps_of(sig.f_inst, sig.fs)


def _q(x) -> str:
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.3f}"


def write_designs_report(study, result, path) -> Path:
    """Design-strategy comparison: table and agreement against runs spent."""
    from ..analysis.compare_designs import agreement_table

    ref = result["reference"]
    page = Page(f"sensfw: design strategies compared ({study.name})",
                f"scorer {result['scorer']}; {len(result['variables'])} variables")
    q2 = ref["q2_kfold"]
    page.p(f"Reference ranking: total Sobol' indices of a {ref['surrogate']} surrogate trained "
           f"on a {ref['runs']}-run Latin hypercube (Q² LOO {_q(ref['q2_loo'])}, k-fold "
           f"{_q(q2)}): " + ", ".join(ref["ranking"]), "ok" if q2 and q2 > 0.8 else "note")
    for n in ref.get("notes", []):
        page.note(n)
    page.table(agreement_table(result))
    best = result["fewest_runs_to_reference_top_k"]
    page.p(f"Fewest runs to the reference top-{result['top_k']}: {best or 'no design'}.",
           "ok" if best else "note")
    fig, ax = plt.subplots(figsize=(8, 4))
    markers = "osD^vP*X"
    for i, r in enumerate(result["designs"]):
        tau = "" if r["kendall_tau"] is None else f", Kendall tau {r['kendall_tau']:.2f}"
        ax.scatter(r["runs"], r["top_k_overlap"] + 0.015 * (i - 2), s=70,
                   marker=markers[i % len(markers)], label=f"{r['design']}{tau}")
    ax.legend(fontsize=8, loc="lower right")
    ax.set_xlabel("runs spent")
    ax.set_ylabel(f"top-{result['top_k']} overlap with the reference")
    ax.set_ylim(-0.05, 1.1)
    ax.grid(True, alpha=0.3)
    page.figure(fig, "Agreement with the reference ranking against runs spent.")
    sob = pd.DataFrame(ref["sobol"]).T
    page.table(sob)
    return page.write(path)
