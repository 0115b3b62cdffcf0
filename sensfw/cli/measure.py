"""Measurement commands: simulate (synthetic rig data), compare, diagnose, augment."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from ..errors import SensfwError
from .common import (
    Backend,
    Measured,
    OutDir,
    Scheduler,
    ShowProgress,
    StudyFile,
    Workers,
    _running,
    command,
    option_value,
    out,
    say,
)


@command()
def simulate(
    study_file: StudyFile,
    out_file: Annotated[Path, typer.Option(
        "--out", "-o", help="measurement file to write: .csv (one per level) or .uff (all "
                            "levels in one file)")],
    set_: Annotated[list[str] | None, typer.Option("--set", help="NAME=VALUE (paper units)")]
    = None,
    effect: Annotated[list[str] | None, typer.Option(
        help=r"NAME\[@PLACE][:KEY=VALUE,...] hidden physical effect; KEY a parameter of "
             "the effect or one of its options (micro_slip:elements=6)")] = None,
    noise: Annotated[float, typer.Option(help="noise std as a fraction of each RMS")] = 0.0,
    seed: Annotated[int, typer.Option(help="noise seed")] = 0,
    amplitude: Annotated[float | None, typer.Option(help="excitation level (N, or V)")] = None,
    levels: Annotated[str | None, typer.Option(
        help="several levels, e.g. 0.1,0.3,1.0 (one file per level, or one UFF)")] = None,
    excitation: Annotated[str | None, typer.Option(
        help="log_chirp | linear_sweep | random | stepped_sine (default: the study's)")]
    = None,
    offset: Annotated[float, typer.Option(help="DC offset on the force, fraction of the "
                                               "level")] = 0.0,
    drift: Annotated[float, typer.Option(help="slow drift of the applied force amplitude, "
                                              "e.g. 0.2 for +-20 %")] = 0.0,
    delay: Annotated[float, typer.Option(help="pre-trigger delay (s)")] = 0.0,
    channel_gain: Annotated[float | None, typer.Option(
        help="record the amplifier voltage instead of the force: shaker gain in N/V")] = None,
) -> None:
    """Simulate one configuration and write it as a rig would record it (synthetic data)."""
    from ..excitation import KINDS
    from ..measure.io import write_csv, write_uff
    from ..measure.synthetic import Rig, parse_assignments, synthesize
    from ..study import Study

    study = Study.load(study_file)
    sets = parse_assignments(set_ or [], "--set")
    if excitation is not None and (excitation not in KINDS or excitation == "sampled"):
        raise SensfwError(f"--excitation {excitation!r}: use one of log_chirp, linear_sweep, "
                          "random, stepped_sine")
    if levels and amplitude is not None:
        raise SensfwError("give --amplitude or --levels, not both")
    tokens = [v.strip() for v in levels.split(",")] if levels else [None]
    try:
        values = [float(v) for v in tokens] if levels else [amplitude]
    except ValueError:
        raise SensfwError(f"--levels {levels!r}: expected numbers separated by commas") \
            from None
    if len(set(values)) < len(values):
        raise SensfwError(f"--levels {levels!r}: a level is given twice")
    if any(v is not None and not v > 0 for v in values):
        raise SensfwError(f"--levels {levels!r}: levels must be positive" if levels else
                          f"--amplitude {amplitude!r}: must be positive")
    for option, value in (("--noise", noise), ("--drift", drift), ("--delay", delay)):
        if not value >= 0:
            raise SensfwError(f"{option} {value!r}: must be >= 0")
    if not drift < 1:
        raise SensfwError(f"--drift {drift!r}: must be below 1 (a fraction of the level; at "
                          "1 or more the excitation's envelope passes through zero)")
    if channel_gain is not None and not channel_gain > 0:
        raise SensfwError(f"--channel-gain {channel_gain!r}: a shaker gain in N/V must be "
                          "positive")
    if out_file.suffix.lower() not in (".csv", ".uff", ".unv"):
        raise SensfwError(f"--out {out_file}: write a .csv (one file per level) or a .uff")
    records = []
    for i, level in enumerate(values):
        rig = Rig(noise=noise, offset=offset, drift=drift, delay=delay, gain=channel_gain,
                  seed=seed + i)
        sig, info = synthesize(study, sets, effect or [], amplitude=level,
                               excitation=excitation, rig=rig)
        records.append((sig, info))
    out_file.parent.mkdir(parents=True, exist_ok=True)
    meta = {"source": "sensfw simulate", "excitation": excitation or study.excitation.kind,
            "effects": [e for e in effect or []], "noise": noise, "offset": offset,
            "drift": drift, "delay": delay}
    if out_file.suffix.lower() in (".uff", ".unv"):
        write_uff(out_file, [(sig, info["amplitude"]) for sig, info in records])
        written = [out_file]
    else:
        written = []
        for (sig, info), token in zip(records, tokens, strict=True):
            # one file per level, named as the level was written (--levels 0.5,1.0: _1.0)
            path = out_file if len(records) == 1 else \
                out_file.with_name(f"{out_file.stem}_{token}{out_file.suffix}")
            written.append(write_csv(path, sig, level=info["amplitude"], meta=meta))
    paths = written * len(records) if len(written) == 1 else written
    for (sig, info), path in zip(records, paths, strict=True):
        out.print(f"wrote {path} ({len(sig.t)} samples at {sig.fs:g} Hz, {info['excitation']}"
                  f", level {info['amplitude']:g} {info['unit']}, noise {noise:g})")



def _band_option(text: str | None, option: str) -> tuple[float, float] | None:
    """``"LO,HI"`` (Hz) -> ``(LO, HI)``, or a clear error naming the option."""
    if text is None:
        return None
    try:
        lo, hi = (float(x) for x in text.split(","))
    except ValueError:
        raise SensfwError(f"{option} {text!r}: expected LO,HI in Hz (e.g. 80,105)") from None
    if not 0 < lo < hi:
        raise SensfwError(f"{option} {text!r}: expected 0 < LO < HI")
    return lo, hi


@command()
def compare(
    study_file: StudyFile,
    measured: Measured,
    out_dir: OutDir = Path("out/compare"),
    error_band: Annotated[str | None, typer.Option(
        help="the band LO,HI Hz of each record's FRF error (default: the study's band)"
    )] = None,
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
    twins: Annotated[int, typer.Option(
        min=0, help="runs of each record's model on its drive changed by k x 1e-9 (k = 1 .. "
                    "TWINS), for the model's own scatter: what a model whose response its "
                    "drive does not determine (stick-slip under random drive) differs from "
                    "itself by; 0: none")] = 2,
) -> None:
    """See where the model fails: FRF error, resonances, harmonics, THD, up/down jumps,
    levels. Records: time data (sweeps, random, stepped sines) or FRFs alone."""
    from ..measure.compare import compare_measurements
    from ..measure.lines import jump_text
    from ..measure.signatures import THRESHOLDS
    from ..report.measure import write_comparison
    from ..study import Study

    study = Study.load(study_file)
    band = _band_option(error_band, "--error-band")
    meas = _loaded(study, measured)
    for m in meas:
        for note in m.notes:
            if "not the study's" in note or "FRF-only" in note:
                say(f"notice: {m.file}: {note}", style="yellow")
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        result = compare_measurements(study, meas, runner, error_band=band,
                                      twins=twins)
    write_comparison(out_dir, study, result)
    lo, hi = result.error_band
    for c in result.levels:
        thd = "" if c.thd_model is None else \
            f"; THD model {c.thd_model:.2f} % vs measured {c.thd_measured:.2f} %"
        res = "".join(f"; resonance {r['measured_hz']:.4g} Hz measured, "
                      f"{r['model_hz']:.4g} Hz model" for r in c.resonances
                      if r["measured_hz"] and r["model_hz"])
        parts = [] if c.error_noise_db is None else \
            [f"the measurement's noise alone: {c.error_noise_db:.2f} dB"]
        if c.error_scatter_db is not None:
            parts.append(f"the model's own scatter: {c.error_scatter_db:.2f} dB")
        noise = f" ({'; '.join(parts)})" if parts else ""
        shift = THRESHOLDS["shift_pct"]
        loose = [r for r in c.resonances if (r.get("model_scatter_pct") or 0) > shift]
        clo, chi = c.error_band or (lo, hi)  # a record sampled slowly: its own band
        out.print(f"{c.level_text}: FRF error {c.error_db:.2f} dB over {clo:g}-{chi:.4g} Hz"
                  f"{noise}{res}{thd}")
        if loose:
            out.print(f"  {len(loose)} of the model's resonances scatter by more than "
                      f"{shift:g} % when its drive changes by 1e-9: the model does not "
                      "determine them, and no shift of theirs is evidence")
    for b in result.bands:
        if b.resonance_low is None:
            continue
        where = ("inside" if b.contains_resonance else "OUTSIDE") if \
            b.contains_resonance is not None else "no measured resonance"
        out.print(f"  prediction band {b.file}: resonance {b.resonance_low:.2f}-"
                  f"{b.resonance_high:.2f} Hz ({where}; {b.width_db_at_resonance or 0:.2f} "
                  f"dB wide at the resonance)"
                  + (f"; extrapolation: {b.extrapolation}" if b.extrapolation else ""))
    for j in result.jumps:
        out.print("  " + jump_text(j))
    if result.amplitude:
        for line in result.amplitude["summary"]:
            out.print("  " + line)
    out.print(f"-> {out_dir}/compare.json, {out_dir}/report.html")


@command()
def diagnose(
    study_file: StudyFile,
    measured: Measured,
    out_dir: OutDir = Path("out/diagnose"),
    candidates: Annotated[str | None, typer.Option(
        help="comma-separated effects, NAME or NAME@PLACE (default: every registered effect "
             "at every place it fits)")] = None,
    budget: Annotated[int | None, typer.Option(
        min=1, help="simulations for the whole diagnosis, one per point and level (default "
                    "150 + 50 per level)")] = None,
    prune: Annotated[bool, typer.Option(
        help="leave out candidates whose signature classes the levels do not show "
             "(--no-prune: race them all; the classes are read off the model calibrated "
             "without any effect, and a poor fit can hide the truth's class)")] = True,
    global_search: Annotated[bool, typer.Option(
        "--global/--local", help="--local: no space-filling design nor surrogate search, "
        "Levenberg-Marquardt from the start values (bench/recovery.py, 40 cases: 18 of 28 "
        "named against the default's 22, median 335 simulations against 392)")] = True,
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Which effect does the model lack, and where? Recalibrate the base parameters alone and
    with each candidate (global calibrations, or local with --local); rank by BIC and
    held-out levels."""
    from ..measure.diagnose import diagnose as run_diagnose
    from ..report.diagnosis import write_diagnosis
    from ..study import Study

    study = Study.load(study_file)
    meas = _loaded(study, measured)
    t0 = time.perf_counter()
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        names = [c.strip() for c in candidates.split(",")] if candidates else None
        result = run_diagnose(study, meas, runner, names, budget=budget, prune=prune,
                              local="dfols" if global_search else "lm",
                              global_phase=global_search, log=say)
    data = write_diagnosis(out_dir, study, result, time.perf_counter() - t0)
    out.print(f"verdict: {result.verdict}  ({result.reason}; {result.n_simulations} "
              f"simulations, {data['wall_s']:.0f} s)")
    h0 = result.rows[0]
    out.print(f"  parameters only: error {result.errors['nominal']:.2f} -> "
              f"{result.errors['parameters']:.2f} dB, chi2 {h0['chi2']:.1f} for "
              f"{result.n_entries} entries")
    for c in h0["calibration"]:
        flags = f" ({'; '.join(c['flags'])})" if c["flags"] else ""
        out.print(f"    {c['name']} = {c['value']:.4g} {c['unit']} "
                  f"[{c['interval'][0]:.4g}, {c['interval'][1]:.4g}]{flags}")
    for r in [r for r in result.ranking if r["surrogate"]][:6]:
        held = "" if r["heldout_chi2_per_entry"] is None else \
            f", held-out chi2/entry {r['heldout_chi2_per_entry']:.2f}"
        out.print(f"  {r['hypothesis']:28s} chi2 {r['chi2']:.1f}, dBIC {r['delta_bic']:+.1f}"
                  f"{held}")
    out.print(f"-> {out_dir}/diagnose.json, {out_dir}/report.html")


def effect_options(items: list[str]) -> dict[str, object]:
    """``KEY=VALUE`` strings as options (values read by :func:`option_value`)."""
    out: dict[str, object] = {}
    for item in items:
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            raise SensfwError(f"--option {item!r}: expected KEY=VALUE, e.g. elements=6")
        out[key.strip()] = option_value(value.strip())
    return out


@command()
def augment(
    study_file: StudyFile,
    measured: Measured,
    effect: Annotated[str, typer.Option(help=r"effect to add, NAME\[@PLACE]")],
    option: Annotated[list[str] | None, typer.Option(
        "--option", help="an option of the effect, KEY=VALUE (repeatable), e.g. "
                         "elements=6 for micro_slip")] = None,
    out_dir: OutDir = Path("out/augment"),
    start_from: Annotated[Path | None, typer.Option(
        help="diagnose.json: start from the values diagnose found for this effect")] = None,
    budget: Annotated[int | None, typer.Option(
        min=1, help="simulations of the calibrations, one per point and level (default "
                    "100 + 60 per level)")] = None,
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Add a physical effect at its place, calibrate it with the base parameters, write the
    augmented study and the error trajectory per level."""
    from ..measure.augment import augment as run_augment
    from ..measure.augment import diagnosed_start
    from ..report.diagnosis import write_augmentation
    from ..study import Study

    study = Study.load(study_file)
    meas = _loaded(study, measured)
    name, _, attach = effect.partition("@")
    start = base_start = None
    read_also = []
    if start_from is not None:
        start, attach, base_start = diagnosed_start(start_from, name, attach)
        read_also = [start_from.parent / "runs"]  # the diagnosis's runs are reused
    with _running(study, out_dir, workers, backend, scheduler, progress,
                  read_also=read_also) as runner:
        result = run_augment(study, meas, runner, name, attach or None, start=start,
                             base_start=base_start, budget=budget,
                             options=effect_options(option or []),
                             study_text=study_file.read_text(encoding="utf-8"), log=say)
    write_augmentation(out_dir, study, result)
    for t in result["trajectory"]:
        if t["error"] is None:
            out.print(f"  {t['step']:20s} its runs failed (see the run store)")
            continue
        per = per_record(t)
        out.print(f"  {t['step']:20s} residual error {t['error']:.3f} dB" +
                  (f" ({per})" if len(t.get("error_per_level") or []) > 1 else ""))
    out.print(f"-> {out_dir}/study.toml, {out_dir}/augment.json, {out_dir}/report.html")


@command()
def calibrate(
    study_file: StudyFile,
    measured: Measured,
    out_dir: OutDir = Path("out/calibrate"),
    budget: Annotated[int | None, typer.Option(
        min=1, help="simulations, one per point and level (default 60 per level)")] = None,
    global_search: Annotated[bool, typer.Option(
        "--global/--local", help="--local: no space-filling design nor surrogate search, "
        "only the local least squares from the study's nominal values")] = True,
    workers: Workers = None,
    backend: Backend = None,
    scheduler: Scheduler = None,
    progress: ShowProgress = True,
) -> None:
    """Calibrate the study's base parameters (its calibration section) against measurements:
    values with intervals, the error per level before and after, and the calibrated study."""
    from ..measure.recalibrate import recalibrate
    from ..report.diagnosis import write_calibration
    from ..study import Study

    study = Study.load(study_file)
    meas = _loaded(study, measured)
    with _running(study, out_dir, workers, backend, scheduler, progress) as runner:
        result = recalibrate(study, meas, runner, budget=budget, global_phase=global_search,
                             study_text=study_file.read_text(encoding="utf-8"), log=say)
    write_calibration(out_dir, study, result)
    for c in result["calibration"]:
        flags = f" ({'; '.join(c['flags'])})" if c["flags"] else ""
        out.print(f"  {c['name']} = {c['value']:.4g} {c['unit']} "
                  f"[{c['interval'][0]:.4g}, {c['interval'][1]:.4g}]{flags}")
    for t in result["trajectory"]:
        out.print(f"  {t['step']:14s} residual error {t['error']:.3f} dB ({per_record(t)})")
    for n in result.get("notes", []):
        say(f"notice: {n}", style="yellow")
    out.print(f"-> {out_dir}/study.toml, {out_dir}/calibrate.json, {out_dir}/report.html")


def _loaded(study, measured) -> list:
    """The measurements, loaded and prepared; what each warns of printed (a level the
    record contradicts, a record that sweeps little of the study's band)."""
    from ..measure.prepared import load_measurements

    meas = load_measurements(study, [str(m) for m in measured])
    for m in meas:
        for w in getattr(m, "warnings", ()):
            say(f"warning: {m.file}: {w}", style="yellow")
    return meas


def per_record(step: dict) -> str:
    """A trajectory step's error per record: "per level: 3.71, 4.70" when the records are
    of one kind, else "per record: log chirp 0.05 3.71, random 0.05 4.70"."""
    per = step.get("error_per_level") or []
    kinds = step.get("kinds") or []
    if len(set(kinds)) <= 1:
        return "per level: " + ", ".join(f"{e:.2f}" for e in per)
    return "per record: " + ", ".join(
        f"{k.replace('_', ' ')} {lv:g} {e:.2f}"
        for k, lv, e in zip(kinds, step["levels"], per, strict=False))
