"""Reports of the measurement commands: compare, diagnose, augment."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from .html import Page


def frf_overlay(comparisons, extra=None, title="FRF: model against measurement"):
    fig, ax = plt.subplots(figsize=(10, 4.5))
    colors = plt.cm.tab10(np.arange(10))
    for i, c in enumerate(comparisons):
        ax.semilogx(c.f, c.db_measured, color=colors[i % 10], lw=1.4,
                    label=f"measured {c.level:.3g} {c.unit}")
        ax.semilogx(c.f, c.db_model, color=colors[i % 10], lw=1.0, ls="--",
                    label=f"model {c.level:.3g} {c.unit}")
    for label, cs in (extra or {}).items():
        for c in cs:
            ax.semilogx(c.f, c.db_model, lw=1.0, ls=":",
                        label=f"{label} {c.level:.3g} {c.unit}")
    ax.set_xlabel("frequency (Hz)")
    if comparisons:
        c = comparisons[0]
        ax.set_ylabel(f"|H| (dB re 1 ({c.output_unit})/{c.unit})")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return fig


def band_errors(comparisons):
    fig, ax = plt.subplots(figsize=(10, 3.4))
    width = 0.8 / max(len(comparisons), 1)
    for i, c in enumerate(comparisons):
        x = np.arange(len(c.bands)) + i * width
        ax.bar(x, [b["mean_db"] for b in c.bands], width, label=f"{c.level:.3g} {c.unit}")
    if comparisons:
        ax.set_xticks(np.arange(len(comparisons[0].bands)),
                      [f"{b['centre_hz']:.0f}" for b in comparisons[0].bands], rotation=60,
                      fontsize=7)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("one-third-octave band centre (Hz)")
    ax.set_ylabel("model - measured (dB)")
    ax.set_title("FRF error per one-third-octave band")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
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


def spectrograms(meas, model, channel, level):
    from ..signal import spectrogram

    fig, axes = plt.subplots(1, 2, figsize=(12, 3.8), sharey=True)
    im = None
    for ax, sig, who in ((axes[0], meas, "measured"), (axes[1], model, "model")):
        f, t, S = spectrogram(sig.channel(channel), sig.fs)
        vmax = np.nanmax(S)
        im = ax.pcolormesh(t, f, S, shading="auto", vmin=vmax - 80, vmax=vmax)
        ax.set_title(f"{who}, {level:.3g} {meas.units.get('force', 'N')}")
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

    ax.set_xticks(levels, [f"{x:g}" for x in levels])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())


def amplitude_plot(amplitude: dict, unit: str = "N"):
    """Resonance frequency and damping ratio against level, measured (solid) and model
    (dashed), one row per prominent resonance; harmonic ratios H2/H1, H3/H1 (dB) against
    level with the measured noise floor (dotted) in the last row."""
    table = amplitude["table"]
    tracks = _plotted_tracks(table)
    rows = max(len(tracks), 1) + 1
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
    ax = fig.add_subplot(grid[rows - 1, :])
    harm = table["harmonics"]
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
    """Sentences, plot and tables of :func:`sensfw.measure.signatures.amplitude_dependence`."""
    page.h2("Amplitude dependence")
    found = amplitude.get("classes") or {}
    if found:
        page.p("Signature classes of the discrepancy: " + ", ".join(
            c.replace("_", " ") for c in found) + ".", "note")
    for line in amplitude.get("sentences", []):
        page.p(line, "note" if found else "ok")
    page.figure(amplitude_plot(amplitude, unit),
                "Resonance frequency and damping ratio (single-mode fit where both FRFs "
                "allow it, else half-power) and harmonic ratios against the excitation "
                "level: measured (solid) and model (dashed). The classes judge the "
                "measured trend relative to the model's own.")
    res, harm = amplitude_frames(amplitude)
    if not res.empty:
        page.table(res, index=False)
    page.table(harm, index=False)


def _frame(rows, cols=None) -> pd.DataFrame:
    frame = pd.DataFrame(rows)
    return frame[cols] if cols else frame


def write_compare_report(study, comparisons, pairs, amplitude, notes, path) -> Path:
    page = Page(f"sensfw: model against measurement ({study.name})",
                f"output channel {study.output}; {len(comparisons)} excitation level(s)")
    for n in notes:
        page.note(n)
    page.figure(frf_overlay(comparisons), "Measured (solid) and simulated (dashed) FRFs, Hv, "
                "1/24-octave smoothed.")
    page.figure(band_errors(comparisons), "Where the model fails: FRF error per band.")
    if amplitude:
        unit = comparisons[0].unit if comparisons else "N"
        amplitude_section(page, amplitude, unit)
    for c in comparisons:
        thd = "no THD (not a sweep)" if c.thd_model is None else \
            f"THD model {c.thd_model:.2f} % / measured {c.thd_measured:.2f} %"
        page.h3(f"Level {c.level:.3g} {c.unit} ({c.file}): FRF error {c.frf_rms_db:.2f} dB "
                f"RMS (bands within {c.dynamic_range:g} dB of the strongest and above the "
                f"noise; noise floor {c.noise_floor_db:.2f} dB), {thd}")
        page.table(_frame(c.resonances).fillna(""), index=False)
        page.table(_frame(c.harmonics), index=False)
    page.figure(order_spectra(pairs, study.output), "Order spectra, measured and simulated.")
    for level, meas, model in pairs:
        page.figure(spectrograms(meas, model, study.output, level),
                    "Spectrograms side by side (Fig. 11 style).")
    return page.write(path)


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
