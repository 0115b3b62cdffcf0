"""Figures of the measurement reports (:mod:`sensfw.report.measure`): the FRFs of model and
measurement, where they differ per band, up and down sweeps, order spectra, spectrograms and
the amplitude dependence."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Patch


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
    bars = False
    handles = []  # the legend: each record's colour (its first bar may be a grey one)
    for i, c in enumerate(comparisons):
        pos = {b["centre_hz"]: j for j, b in enumerate(ref.bands)}
        used = {b["centre_hz"] for b in c.used_bands}
        x = np.array([pos.get(b["centre_hz"], np.nan) for b in c.bands]) + i * width
        err = [b["noise_db"] or 0.0 for b in c.bands]
        bars = bars or any(err)
        ax.bar(x, [b["mean_db"] for b in c.bands], width,
               yerr=err if any(err) else None, error_kw={"lw": 0.8, "capsize": 1.5},
               color=[colors[i % 10] if b["centre_hz"] in used else "0.8" for b in c.bands],
               label=getattr(c, "level_text", f"{c.level:.3g} {c.unit}"))
        handles.append(Patch(color=colors[i % 10],
                             label=getattr(c, "level_text", f"{c.level:.3g} {c.unit}")))
    if ref:
        step = max(1, len(centres) // 30)
        ax.set_xticks(np.arange(len(centres))[::step],
                      [f"{x:.0f}" if x >= 100 else f"{x:.3g}" for x in centres][::step],
                      rotation=60, fontsize=7)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("band centre (Hz)")
    ax.set_ylabel("model - measured (dB)")
    ax.set_title("Where the model fails: mean FRF difference per band ("
                 + ("error bars: the measurement's standard error; " if bars else
                    "no error bars: these records carry no standard error (FRFs alone); ")
                 + "grey: bands the measurement cannot speak for)", fontsize=9)
    ax.legend(handles=[*handles, Patch(color="0.8", label="cannot speak for")], fontsize=7)
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


def plotted_tracks(table: dict, min_prominence: float = 10.0, most: int = 4) -> list[dict]:
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
    tracks = plotted_tracks(table)
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


def band_plot(comparisons, bands, error_band=None):
    """Per record (one column each, at most four): above, the measured FRF within the
    prediction band of the calibrated model (shaded) and the calibrated model (dashed) over
    the error band on a log axis; below, the same around the resonance, its band shaded
    orange. A record the calibration saw nothing like is titled an extrapolation."""
    n = min(len(bands), 4)
    fig, axes = plt.subplots(2, n, figsize=(4.6 * n, 6.2), squeeze=False)
    for j, (c, b) in enumerate(zip(comparisons[:n], bands[:n], strict=False)):
        keep = np.ones(len(c.f), bool)
        if error_band is not None:
            keep = (c.f >= error_band[0]) & (c.f <= error_band[1])
        centre = None
        if b.resonance_low is not None:
            centre = 0.5 * (b.resonance_low + b.resonance_high)
        for row, ax in enumerate(axes[:, j]):
            sel = keep.copy()
            if row == 1 and centre is not None:
                half = max(0.06 * centre, 3.0 * (b.resonance_high - b.resonance_low))
                sel &= (c.f >= centre - half) & (c.f <= centre + half)
            ax.fill_between(c.f[sel], b.db_low[sel], b.db_high[sel], color="C0", alpha=0.3,
                            lw=0, label="prediction band")
            ax.plot(c.f[sel], c.db_model[sel], "C0--", lw=1, label="calibrated model")
            ax.plot(c.f[sel], c.db_measured[sel], "k-", lw=1, label="measured")
            if centre is not None:
                ax.axvspan(b.resonance_low, b.resonance_high, color="C1", alpha=0.3, lw=0,
                           label="resonance band")
            if row == 0:
                ax.set_xscale("log")
                title = c.level_text + ("  (extrapolation)" if b.extrapolation else "")
                ax.set_title(title, fontsize=9)
            else:
                ax.set_title("around the resonance", fontsize=8)
            ax.set_xlabel("frequency (Hz)", fontsize=8)
            ax.set_ylabel("|H| (dB)", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    return fig
