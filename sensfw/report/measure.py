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


def write_diagnose_report(study, result, base_cmp, best_cmp, path) -> Path:
    page = Page(f"sensfw: which physical effect is missing? ({study.name})",
                f"verdict: {result['verdict']} ({result['n_simulations']} simulations)")
    crit = result["criteria"]
    page.p(f"Each candidate effect was added to the model and its parameters calibrated "
           f"against the measurement (small design, Gaussian-process surrogate, confirmation "
           f"by simulation). Candidates are ranked by BIC; a verdict needs a BIC gain above "
           f"{crit['min_delta_bic']:g} and an error reduction of at least "
           f"{crit['min_reduction']:.0%}.")
    rows = [{"effect": f"{r['effect']}@{r['attach']}", "error before (dB)": r["error_before"],
             "error after (dB)": r["error_after"], "reduction": r["reduction"],
             "ΔBIC": r["delta_bic"], "parameters": ", ".join(f"{k}={v:.4g}" for k, v in
                                                            r["params"].items())}
            for r in result["ranking"]]
    frame = pd.DataFrame(rows)
    if not frame.empty:
        page.table(frame.set_index("effect"),
                   highlight=pd.Series([r["effect"] == result["verdict"]
                                        for r in result["ranking"]]))
        fig, ax = plt.subplots(figsize=(10, 3.5))
        x = np.arange(len(frame))
        ax.bar(x - 0.2, frame["error before (dB)"], 0.4, label="without the effect")
        ax.bar(x + 0.2, frame["error after (dB)"], 0.4, label="effect calibrated")
        ax.set_xticks(x, frame["effect"], rotation=20, fontsize=8)
        ax.set_ylabel("discrepancy (dB RMS)")
        ax.legend()
        ax.grid(True, axis="y", alpha=0.3)
        page.figure(fig, "Discrepancy with each candidate effect calibrated.")
    for r in result["ranking"][:3]:
        page.h3(f"{r['effect']}@{r['attach']}")
        for line in r["evidence"]:
            page.p(line)
    if best_cmp is not None:
        page.figure(frf_overlay(base_cmp, {f"with {result['ranking'][0]['effect']}": best_cmp}),
                    "Measurement, model, and model with the best candidate (dotted).")
    return page.write(path)


def write_augment_report(study, result, path) -> Path:
    page = Page(f"sensfw: model augmented with {result['effect']} ({study.name})",
                f"{result['n_simulations']} simulations")
    tr = result["trajectory"]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.bar([t["step"] for t in tr], [t["error"] or 0 for t in tr],
           color=["#9aa5b1", "#f0a000", "#1f6fd1"])
    ax.set_ylabel("discrepancy (dB RMS)")
    ax.set_title("The error falls")
    ax.grid(True, axis="y", alpha=0.3)
    for i, t in enumerate(tr):
        if t["error"] is not None:
            ax.text(i, t["error"], f"{t['error']:.2f}", ha="center", va="bottom")
    page.figure(fig, "Error trajectory: baseline, effect added at nominal values, calibrated.")
    page.p("Calibrated: " + ", ".join(f"{k} = {v:.5g}" for k, v in result["params"].items()),
           "ok")
    for line in result["evidence"]:
        page.p(line)
    ev = [e for e in result["evaluations"] if e["error"] is not None]
    if ev and len(result["params"]) <= 2:
        names = list(result["params"])
        fig, ax = plt.subplots(figsize=(7, 3.5))
        if len(names) == 1:
            ax.plot([e["params"][names[0]] for e in ev], [e["error"] for e in ev], "o")
            ax.set_xlabel(names[0])
            ax.set_ylabel("discrepancy (dB)")
        else:
            sc = ax.scatter([e["params"][names[0]] for e in ev],
                            [e["params"][names[1]] for e in ev],
                            c=np.log10([e["error"] for e in ev]), cmap="viridis_r")
            fig.colorbar(sc, ax=ax, label="log10 discrepancy")
            ax.set_xlabel(names[0])
            ax.set_ylabel(names[1])
        ax.set_title("Calibration: every simulated point")
        ax.grid(True, alpha=0.3)
        page.figure(fig, "Design, surrogate-proposed and local-search points.")
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
