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
                    label=f"measured {c.level:.3g} N")
        ax.semilogx(c.f, c.db_model, color=colors[i % 10], lw=1.0, ls="--",
                    label=f"model {c.level:.3g} N")
    for label, cs in (extra or {}).items():
        for c in cs:
            ax.semilogx(c.f, c.db_model, lw=1.0, ls=":", label=f"{label} {c.level:.3g} N")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("|H| (dB re 1 (m/s²)/N)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return fig


def band_errors(comparisons):
    fig, ax = plt.subplots(figsize=(10, 3.4))
    width = 0.8 / max(len(comparisons), 1)
    for i, c in enumerate(comparisons):
        x = np.arange(len(c.bands)) + i * width
        ax.bar(x, [b["mean_db"] for b in c.bands], width, label=f"{c.level:.3g} N")
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
    for level, meas, model in pairs:
        for sig, ls, who in ((meas, "-", "measured"), (model, "--", "model")):
            if sig.f_inst is None:  # not a sweep (random excitation): no orders
                continue
            s = sig.sweep()
            n, P = order_spectrum(s.channel(channel), s.fs, s.f_inst)
            ax.semilogy(n, P, ls=ls, lw=1, label=f"{who} {level:.3g} N")
    ax.set_xlabel("order")
    ax.set_ylabel("RMS amplitude (m/s²)")
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
        ax.set_title(f"{who}, {level:.3g} N")
        ax.set_xlabel("time (s)")
    axes[0].set_ylabel("frequency (Hz)")
    fig.colorbar(im, ax=axes, label="dB")
    return fig


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
    for c in comparisons:
        thd = "no THD (not a sweep)" if c.thd_model is None else \
            f"THD model {c.thd_model:.2f} % / measured {c.thd_measured:.2f} %"
        page.h3(f"Level {c.level:.3g} {c.unit} ({c.file}): FRF error {c.frf_rms_db:.2f} dB "
                f"RMS (bands within {c.dynamic_range:g} dB of the strongest and above the "
                f"noise; noise floor {c.noise_floor_db:.2f} dB), {thd}")
        page.table(_frame(c.resonances).fillna(""), index=False)
        page.table(_frame(c.harmonics), index=False)
    if amplitude:
        page.h2("Amplitude dependence")
        for line in amplitude["summary"]:
            page.p(line, "ok")
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
