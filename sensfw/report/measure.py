"""Reports of the measurement commands: compare, diagnose, augment."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from .html import Page


def frf_overlay(comparisons, extra=None, title="FRF: model against measurement",
                error_band=None):
    """Measured (solid) and model (dashed) FRFs of every record; stepped-sine and FRF-only
    records on their lines (markers); the error band shaded."""
    fig, ax = plt.subplots(figsize=(10, 4.5))
    colors = plt.cm.tab10(np.arange(10))
    for i, c in enumerate(comparisons):
        mark = "o" if getattr(c, "stepped", False) and len(c.f) <= 120 else None
        label = getattr(c, "level_text", f"{c.level:.3g} {c.unit}")
        ax.semilogx(c.f, c.db_measured, color=colors[i % 10], lw=1.4, marker=mark, ms=3,
                    label=f"measured, {label}")
        ax.semilogx(c.f, c.db_model, color=colors[i % 10], lw=1.0, ls="--",
                    label=f"model, {label}")
    for label, cs in (extra or {}).items():
        for c in cs:
            ax.semilogx(c.f, c.db_model, lw=1.0, ls=":",
                        label=f"{label} {c.level:.3g} {c.unit}")
    if comparisons:  # the compared lines, not the whole study band of a narrow record
        lo = min(float(c.f[0]) for c in comparisons)
        hi = max(float(c.f[-1]) for c in comparisons)
        ax.set_xlim(lo / 1.02, hi * 1.02)
        if error_band:
            ax.axvspan(max(error_band[0], lo), min(error_band[1], hi), color="0.5",
                       alpha=0.08, lw=0, label="error band")
    ax.set_xlabel("frequency (Hz)")
    if comparisons:
        c = comparisons[0]
        ax.set_ylabel(f"|H| (dB re 1 ({c.output_unit})/{c.unit})")
    _plain_hz(ax, comparisons)
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return fig


def _plain_hz(ax, comparisons) -> None:
    """Frequency ticks written plainly on a log axis that spans less than a decade."""
    from matplotlib.ticker import FormatStrFormatter

    f = [x for c in comparisons for x in (c.f[0], c.f[-1])]
    if f and max(f) / min(f) < 10:
        ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(FormatStrFormatter("%g"))
        ax.tick_params(axis="x", which="both", labelsize=8)


def band_errors(comparisons):
    """Model minus measured FRF per band (bars), with the measurement's standard error of
    each band where it is known (error bars)."""
    fig, ax = plt.subplots(figsize=(10, 3.4))
    width = 0.8 / max(len(comparisons), 1)
    ref = max(comparisons, key=lambda c: len(c.bands)) if comparisons else None
    centres = [b["centre_hz"] for b in ref.bands] if ref else []
    colors = plt.cm.tab10(np.arange(10))
    for i, c in enumerate(comparisons):
        pos = {b["centre_hz"]: j for j, b in enumerate(ref.bands)}
        used = {b["centre_hz"] for b in c.used_bands}
        x = np.array([pos.get(b["centre_hz"], np.nan) for b in c.bands]) + i * width
        err = [b["noise_db"] or 0.0 for b in c.bands]
        ax.bar(x, [b["mean_db"] for b in c.bands], width,
               yerr=err if any(err) else None, error_kw={"lw": 0.8, "capsize": 1.5},
               color=[colors[i % 10] if b["centre_hz"] in used else "0.8" for b in c.bands],
               label=getattr(c, "level_text", f"{c.level:.3g} {c.unit}"))
    if ref:
        step = max(1, len(centres) // 30)
        ax.set_xticks(np.arange(len(centres))[::step],
                      [f"{x:.0f}" if x >= 100 else f"{x:.3g}" for x in centres][::step],
                      rotation=60, fontsize=7)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("band centre (Hz)")
    ax.set_ylabel("model - measured (dB)")
    ax.set_title("Where the model fails: mean FRF difference per band (error bars: the "
                 "measurement's standard error; grey: bands the measurement cannot speak "
                 "for)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(True, axis="y", alpha=0.3)
    return fig


def jump_plot(comparisons, jumps):
    """Up (solid) and down (dashed) FRFs of each level that has both, measured (left) and
    model (right), on the lines both sweeps share."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8), sharey=True)
    colors = plt.cm.tab10(np.arange(10))
    for i, j in enumerate(jumps):
        by = {c.direction: c for c in comparisons if c.level == j["level"] and c.stepped}
        for ax, key, who in ((axes[0], "db_measured", "measured"),
                             (axes[1], "db_model", "model")):
            for d, ls in (("up", "-"), ("down", "--")):
                c = by[d]
                ax.plot(c.f, getattr(c, key), ls=ls, color=colors[i % 10], lw=1.2,
                        marker="." if len(c.f) <= 120 else None,
                        label=f"{j['level']:g} {j['unit']} {d}")
            band = (j[who] or {}).get("hysteresis_hz")
            if band:
                ax.axvspan(*band, color=colors[i % 10], alpha=0.1, lw=0)
            ax.set_title(who, fontsize=9)
            ax.set_xlabel("frequency (Hz)")
            ax.grid(True, alpha=0.3)
    if jumps:
        c = next(c for c in comparisons if c.stepped)
        axes[0].set_ylabel(f"|H| (dB re 1 ({c.output_unit})/{c.unit})")
    axes[0].legend(fontsize=7)
    return fig


def order_spectra(pairs, channel):
    from ..signal import order_spectrum

    fig, ax = plt.subplots(figsize=(10, 3.6))
    unit = out_unit = ""
    for level, meas, model in pairs:
        unit = meas.units.get("force", "N")
        out_unit = meas.units.get(channel, "m/s^2").replace("^2", "²")
        for sig, ls, who in ((meas, "-", "measured"), (model, "--", "model")):
            if sig.f_inst is None:  # not a sweep (random excitation): no orders
                continue
            s = sig.sweep()
            n, P = order_spectrum(s.channel(channel), s.fs, s.f_inst)
            ax.semilogy(n, P, ls=ls, lw=1, label=f"{who} {level:.3g} {unit}")
    ax.set_xlabel("order")
    ax.set_ylabel(f"RMS amplitude ({out_unit})")
    ax.set_title("Order spectra (harmonics of the chirp at integer orders)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return fig


def spectrograms(meas, model, channel, label: str):
    from ..signal import spectrogram

    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8), sharey=True)
    im = None
    for ax, sig, who in ((axes[0], meas, "measured"), (axes[1], model, "model")):
        f, t, S = spectrogram(sig.channel(channel), sig.fs)
        vmax = np.nanmax(S)
        im = ax.pcolormesh(t, f, S, shading="auto", vmin=vmax - 80, vmax=vmax)
        ax.set_title(f"{who}, {label}", fontsize=9)
        ax.set_xlabel("time (s)")
    axes[0].set_ylabel("frequency (Hz)")
    fig.colorbar(im, ax=axes, label="dB")
    return fig


def _plotted_tracks(table: dict, min_prominence: float = 10.0, most: int = 4) -> list[dict]:
    """The resonance tracks worth a plot: prominent (``min_prominence`` dB at some level on
    either side) and seen at two levels or more, the most prominent first."""
    out = []
    for r in table["resonances"]:
        prom = [v for x in r["levels"] for v in (x["measured_prominence_db"],
                                                   x["model_prominence_db"]) if v is not None]
        seen = sum(x["measured_hz"] is not None or x["model_hz"] is not None
                   for x in r["levels"])
        if prom and max(prom) >= min_prominence and seen >= 2:
            out.append((max(prom), r))
    return [r for _, r in sorted(out, key=lambda x: -x[0])[:most]]


def _level_ticks(ax, levels) -> None:
    """The measured levels as the ticks of a log axis, written plainly."""
    from matplotlib.ticker import NullFormatter, NullLocator

    ax.set_xticks(levels, [f"{x:.3g}" for x in levels])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())


def amplitude_plot(amplitude: dict, unit: str = "N"):
    """Resonance frequency and damping ratio against level, measured (solid) and model
    (dashed), one row per prominent resonance; harmonic ratios H2/H1, H3/H1 (dB) against
    level with the measured noise floor (dotted) in the last row."""
    table = amplitude["table"]
    tracks = _plotted_tracks(table)
    harm = table["harmonics"]
    has_harm = any(h[f"h{k}_{w}"] for h in harm for k in (2, 3) for w in ("measured", "model"))
    rows = len(tracks) + int(has_harm)
    fig = plt.figure(figsize=(11, 2.3 * rows + 1.2))
    grid = fig.add_gridspec(rows, 2, hspace=0.55, wspace=0.25)
    colors = plt.cm.tab10(np.arange(10))

    def series(r, key):
        lv = [x["level"] for x in r["levels"] if x[key] is not None]
        return lv, [x[key] for x in r["levels"] if x[key] is not None]

    for i, r in enumerate(tracks):
        c = colors[i % 10]
        for col, (mkey, skey, label) in enumerate((
                ("measured_hz", "model_hz", "frequency (Hz)"),
                ("measured_damping", "model_damping", "damping ratio"))):
            ax = fig.add_subplot(grid[i, col])
            lm, vm = series(r, mkey)
            ls, vs = series(r, skey)
            ax.semilogx(lm, vm, "o-", color=c, label="measured")
            ax.semilogx(ls, vs, "s--", color=c, mfc="none", label="model")
            vals = [*vm, *vs]
            if vals and col == 0:  # at least +-1 % around the values: flat looks flat
                mid = 0.5 * (min(vals) + max(vals))
                half = max(0.5 * (max(vals) - min(vals)) * 1.15, 0.01 * mid)
                ax.set_ylim(mid - half, mid + half)
            elif vals:
                ax.set_ylim(0, 1.2 * max(vals))
            ax.set_ylabel(label, fontsize=8)
            _level_ticks(ax, table["levels"])
            ax.set_title(f"{r['id']}: {r['frequency_hz']:.0f} Hz ({r['kind']})", fontsize=9)
            ax.grid(True, which="both", alpha=0.3)
            ax.tick_params(labelsize=8)
            if i == 0 and col == 0:
                ax.legend(fontsize=7)
    if not has_harm:
        return fig
    ax = fig.add_subplot(grid[rows - 1, :])
    lv = [h["level"] for h in harm]
    for k, c in ((2, colors[3]), (3, colors[4])):
        def db(key, k=k):
            return [20 * np.log10(h[f"h{k}{key}"]) if h[f"h{k}{key}"] else np.nan
                    for h in harm]
        ax.semilogx(lv, db("_measured"), "o-", color=c, label=f"H{k}/H1 measured")
        ax.semilogx(lv, db("_model"), "s--", color=c, mfc="none", label=f"H{k}/H1 model")
        ax.semilogx(lv, db("_floor"), ":", color=c, lw=1, label=f"H{k}/H1 noise floor")
    _level_ticks(ax, lv)
    ax.set_xlabel(f"excitation level ({unit})")
    ax.set_ylabel("P_k / P_1 (dB)")
    ax.set_title("Harmonic ratios", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=3, loc="upper left", bbox_to_anchor=(0, -0.3))
    return fig


def amplitude_frames(amplitude: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The amplitude-dependence table as two frames: resonances per level, harmonics and
    DC per level."""
    res = []
    for r in amplitude["table"]["resonances"]:
        for x in r["levels"]:
            if x["measured_hz"] is None and x["model_hz"] is None:
                continue
            res.append({"resonance": f"{r['id']} ({r['kind']})", "level": x["level"],
                        "measured Hz": x["measured_hz"], "model Hz": x["model_hz"],
                        "measured vs model %": x["shift_pct"], "measured ζ": x["measured_damping"],
                        "model ζ": x["model_damping"], "ζ ratio": x["damping_ratio"],
                        "method": x["method"]})
    harm = []
    for h in amplitude["table"]["harmonics"]:
        row = {"level": h["level"]}
        for k in (2, 3):
            row[f"H{k}/H1 measured"] = h[f"h{k}_measured"]
            row[f"H{k}/H1 model"] = h[f"h{k}_model"]
            row[f"H{k}/H1 floor"] = h[f"h{k}_floor"]
        row.update({"THD measured %": h["thd_measured"], "THD model %": h["thd_model"],
                    "DC measured": h["dc_measured"], "DC model": h["dc_model"],
                    "DC std. error": h["dc_standard_error"]})
        harm.append(row)
    def blank(frame):  # empty cells rather than NaN
        return frame.astype(object).where(frame.notna(), "")

    return blank(pd.DataFrame(res)), blank(pd.DataFrame(harm))


def amplitude_section(page, amplitude: dict, unit: str = "N") -> None:
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
    if _plotted_tracks(table) or has_harm:
        page.figure(amplitude_plot(amplitude, unit),
                    "Resonance frequency and damping ratio (single-mode fit where both FRFs "
                    "allow it, else half-power)" + (" and harmonic ratios" if has_harm else "")
                    + " against the excitation level: measured (solid) and model (dashed). "
                    "The classes judge the measured trend relative to the model's own.")
    else:
        page.p("No resonance prominent at two levels or more, and no harmonics: no plot.")
    res, harm = amplitude_frames(amplitude)
    if not res.empty:
        page.table(res, index=False)
    if has_harm:
        page.table(harm, index=False)


def _frame(rows, cols=None) -> pd.DataFrame:
    frame = pd.DataFrame(rows)
    return frame[cols] if cols else frame


def _resonance_frame(rows) -> pd.DataFrame:
    """A record's resonance table, headed plainly."""
    names = {"measured_hz": "measured (Hz)", "model_hz": "model (Hz)",
             "shift_pct": "model vs measured (%)", "measured_damping": "ζ measured",
             "model_damping": "ζ model", "note": ""}
    frame = pd.DataFrame(rows)[list(names)].rename(columns=names)
    return frame.astype(object).where(frame.notna(), "")


def _harmonic_frame(rows) -> pd.DataFrame:
    """A record's harmonic table, headed plainly."""
    names = {"order": "order", "model": "model P_k", "measured": "measured P_k",
             "model_ratio": "model P_k/P_1", "measured_ratio": "measured P_k/P_1",
             "measured_floor_ratio": "measured noise floor", "difference_db":
             "model - measured (dB)"}
    frame = pd.DataFrame(rows)[list(names)].rename(columns=names)
    return frame.astype(object).where(frame.notna(), "")


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
            "noise alone (dB)": "" if c.error_noise_db is None else f"{c.error_noise_db:.2f}",
            "resonance measured (Hz)": f"{r['measured_hz']:.2f}" if r else "",
            "model (Hz)": f"{r['model_hz']:.2f}" if r else "",
            "THD measured / model (%)": f"{c.thd_measured:.2f} / {c.thd_model:.2f}"
            if c.thd_measured is not None and c.thd_model is not None else ""})
    frame = pd.DataFrame(rows)
    if not (frame["noise alone (dB)"] != "").any():
        frame = frame.drop(columns="noise alone (dB)")
    return frame


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
           "the noise.")
    if result.notes:
        page.h2("Records and how the model was driven")
        for n in result.notes:
            page.p(n)
    page.figure(frf_overlay(comparisons, error_band=band),
                "Measured (solid) and simulated (dashed) FRFs: Hv smoothed to 1/24 octave for "
                "time records, the steady-state lines (markers) of stepped-sine and FRF-only "
                "records.")
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
        amplitude_section(page, result.amplitude, unit)
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
            page.table(_harmonic_frame(c.harmonics), index=False)
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


def write_designs_report(study, result, path) -> Path:
    """Design-strategy comparison: table and agreement against runs spent."""
    from ..analysis.compare_designs import agreement_table

    ref = result["reference"]
    page = Page(f"sensfw: design strategies compared ({study.name})",
                f"scorer {result['scorer']}; {len(result['variables'])} variables")
    q2 = ref["q2_kfold"]
    page.p(f"Reference ranking: total Sobol' indices of a {ref['surrogate']} surrogate trained "
           f"on a {ref['runs']}-run Latin hypercube (Q² LOO {ref['q2_loo']:.3f}, k-fold "
           f"{q2:.3f}): " + ", ".join(ref["ranking"]), "ok" if q2 and q2 > 0.8 else "note")
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
