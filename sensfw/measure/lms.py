"""LMS Test.Lab MAT v5 exports as measurements: time signals, FRFs and coherences.

The file format and its units: :mod:`sensfw.measure.lms_format`.

Channels are named by their point (``Acc1:+X`` -> ``Acc1``; point plus direction,
``Acc1+X``, where a point has several directions); ``names`` renames them. The excitation
is the channel measured in N (a force) or, failing that, in V (an amplifier voltage, as in
the UNESP-BERT rig, where ``Measurement.excitation == "voltage"``); where several qualify,
the reference channel of an FRF in the same folder decides, or ``excitation=`` names it.

UNESP-BERT (``data/bert/README.md``): ``TimeShaker.mat`` holds ``Time_Shaker__X``
(``Shaker:-X``, channel 8, V); ``Time.mat`` holds ``Signal`` (16384 x 4, ``Acc1:+X`` ...
``Acc4:+X``, channels 3-6, stored in m/s^2, label g) and ``Time_Laser__X`` (``Laser:+X``,
channel 7, m/s). Positions: ``Acc1`` free end, ``Acc2`` below the joint, ``Acc3`` above the
joint, ``Acc4`` near the clamp, ``Laser`` free end (see :data:`BERT_POSITIONS`).
``FRF.mat`` (``FRF``: Acc1-4 / Shaker, g/V; ``FRF_Laser__X_Shaker__X``, (m/s)/V) and
``Coherence.mat`` (``Coherence``, 5 columns) are H1 with a uniform window at 0.0625 Hz
(one 16384-sample segment) and 54 linear averages. The time records carry
``nr_of_averages`` 53 or 54 (LINAVERAGE). The FRF of the exported record equals the stored
FRF to float32 rounding (5e-6 dB), although the stored coherence (1 - 2e-4 ... 1 - 1.2e-3 in
75-108 Hz) says the averaged frames differed by ~0.1 dB: the exported record is not one of
those frames but, most likely, their time-domain average.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..errors import MeasurementError
from ..models.base import Signals
from .lms_format import LMSFunction, _int_or_none, lms_struct, read_functions, si_unit
from .measurement import FRFRecord, Measurement

__all__ = ["BERT_POSITIONS", "LMS_WINDOWS", "LMSFunction", "amplitude", "frf_settings",
           "level_from_name", "lms_struct", "read_functions", "read_lms", "run_excitation",
           "si_unit", "split_ratio"]

EXCITATION_UNITS = {"N": "force", "V": "voltage"}
#: LMS window names -> scipy.signal.get_window names (windows without a parameter)
LMS_WINDOWS = {"UNIFORM": "boxcar", "HANNING": "hann", "HANN": "hann", "HAMMING": "hamming",
               "FLATTOP": "flattop", "BLACKMAN": "blackman"}
#: Sensor positions of the UNESP-BERT rig (data/bert/README.md), by LMS point name.
BERT_POSITIONS = {"Acc1": "free end", "Acc2": "below the joint", "Acc3": "above the joint",
                  "Acc4": "near the clamp", "Laser": "free end (velocity)",
                  "Shaker": "amplifier voltage, shaker at 85 mm from the clamp"}
_LEVEL = re.compile(r"level[_-]?(\d+)(?:p(\d+))?(?:v)?$", re.IGNORECASE)


def _name_channels(funcs: list[LMSFunction], names: Mapping[str, str] | None) -> None:
    points = [f.point for f in funcs]
    for f in funcs:
        f.name = f.point if points.count(f.point) == 1 else f.label.replace(":", "")
        for key in (f.label, f.point, f.name):
            if names and key in names:
                f.name = str(names[key])
                break


def level_from_name(path: str | Path) -> float | None:
    """Excitation level from a folder name such as ``level_0p05`` (0.05), or None."""
    for part in (Path(path).name, Path(path).parent.name):
        m = _LEVEL.search(Path(part).stem)
        if m:
            return float(f"{m.group(1)}.{m.group(2) or 0}")
    return None


def amplitude(x: np.ndarray) -> float:
    """Sine amplitude of a sweep: the median Hilbert envelope where it exceeds half its
    maximum (ignores a silent tail)."""
    from scipy.signal import hilbert

    env = np.abs(hilbert(x - np.mean(x)))
    return float(np.median(env[env >= 0.5 * np.max(env)])) if np.max(env) > 0 else 0.0


def _files_of(path: Path) -> list[Path]:
    if path.is_dir():
        files = sorted(p for p in path.iterdir() if p.suffix.lower() == ".mat")
        if not files:
            raise MeasurementError(str(path), "folder holds no .mat files (LMS exports)")
        return files
    return [path]


def read_lms(path: str | Path | Sequence[str | Path], *, excitation: str | None = None,
             channels: Sequence[str] | None = None, names: Mapping[str, str] | None = None,
             level: float | None = None) -> Measurement:
    """A measurement from LMS Test.Lab MAT exports: one file, several, or a folder.

    Parameters
    ----------
    path
        A ``.mat`` file, a list of them, or a folder (every ``.mat`` in it is read, e.g. a
        UNESP-BERT level folder with ``TimeShaker.mat`` and ``Time.mat``). Time signals
        (x axis in s) become channels; FRF and coherence structs only help to find the
        excitation (their reference channel).
    excitation
        Name or label of the excitation channel (default: the one channel in N, else the
        one in V, else the reference of the folder's FRFs).
    channels
        Response channels to keep (default: all).
    names
        Renames channels, keyed by LMS label (``Acc1:+X``), point (``Acc1``) or name.
    level
        Excitation level in the excitation's unit (default: from a folder name
        ``level_0p05`` -> 0.05, else the sweep amplitude of the excitation).

    Returns
    -------
    Measurement
        ``signals.force`` is the excitation in SI units (``signals.units["force"]`` is
        ``"N"`` or ``"V"``; ``Measurement.excitation`` says ``"force"`` or ``"voltage"``),
        ``signals.channels`` the responses in SI units, ``Measurement.units`` the units as
        Test.Lab labels them, ``signals.meta["lms"]`` per channel its file, struct, column,
        LMS label, channel id and record (averages, run).

    Raises
    ------
    MeasurementError
        Naming the file and channel: missing file, not a MAT file, no LMS struct or no
        time signals (listing what is there), an unknown excitation or channel (listing the
        channels), sampling (increment or start) that differs between channels or files,
        lengths that differ, time signals of different Test.Lab runs (run names), NaN/inf
        values, a complex time signal.
    """
    paths = [Path(p) for p in path] if isinstance(path, (list, tuple)) else [Path(path)]
    if not paths:
        raise MeasurementError("(no file)", "no LMS file given")
    where = str(paths[0]) if len(paths) == 1 else ", ".join(map(str, paths))
    for p in paths:
        if not p.exists():
            raise MeasurementError(str(p), "file not found")
    files = [f for p in paths for f in _files_of(p)]
    funcs = [fn for f in files for fn in read_functions(f)]
    times = [f for f in funcs if f.x_unit == "s"]
    spectral = [f for f in funcs if f.x_unit != "s"]
    if not times:
        frfs = [f for f in spectral if f.kind.upper() == "FRF"]
        if frfs:
            coherence = [f for f in spectral if f.kind.upper() == "COHERENCE"]
            return _frf_only(where, paths, frfs, coherence, channels, names, level)
        found = ", ".join(sorted({f"{f.struct} ({f.kind}, x in {f.x_unit})" for f in funcs}))
        raise MeasurementError(where, f"no time signals (x axis in s) and no FRF; found "
                                      f"{found}")
    _name_channels(times, names)
    seen: dict[str, LMSFunction] = {}
    for f in times:
        if f.name in seen:
            raise MeasurementError(f.file, f"channel appears twice (also in "
                                           f"{seen[f.name].file}, struct "
                                           f"{seen[f.name].struct!r})", f.name)
        seen[f.name] = f
    exc = _excitation(where, times, spectral, excitation)
    resp = [f for f in times if f is not exc]
    resp = _keep(where, resp, channels, f"the files hold {{}} (excitation {exc.name})")
    _check_consistent(exc, resp)
    fs = 1.0 / exc.dx
    n = len(exc.values)
    kind = EXCITATION_UNITS[exc.unit]
    notes = []
    amp = amplitude(exc.values)
    lv, origin = level, "given"
    if lv is None:
        named = [level_from_name(p) for p in paths]
        lv, origin = (named[0], "folder name") if named[0] is not None else (amp, "amplitude")
    if origin != "amplitude" and amp > 0 and lv > 0 and abs(amp / lv - 1) > 0.05:
        notes.append(f"level {lv:g} {exc.unit} ({origin}) but the {kind} sweep amplitude is "
                     f"{amp:.4g} {exc.unit}")
    avg = exc.record.get("averages")
    if avg not in (None, 0, 1):
        notes.append(f"LMS records {avg} averages for these time data: the record may be a "
                     f"time-domain average of repeated frames (lower noise than one frame)")
    meta = {"source": "LMS Test.Lab", "level_from": origin, "excitation_amplitude": amp,
            "t0": exc.x0, "lms": {f.name: _meta(f) for f in [exc, *resp]}}
    sig = Signals(t=np.arange(n) / fs, force=np.asarray(exc.values, float),
                  channels={f.name: np.asarray(f.values, float) for f in resp}, fs=fs,
                  units={"force": exc.unit, **{f.name: f.unit for f in resp}}, meta=meta)
    return Measurement(file=where, signals=sig,
                       units={"force": exc.file_unit, **{f.name: f.file_unit for f in resp}},
                       level=float(lv), notes=notes)


_RATIO = re.compile(r"^\(?(.+?)\)?\s*/\s*([^/()]+)$")
_SPAN = re.compile(r"(\d+(?:p\d+)?)\s*to\s*(\d+(?:p\d+)?)\s*hz", re.IGNORECASE)
_RUN_KINDS = (("step", "stepped_sine"), ("chirp", "sweep"), ("sweep", "sweep"),
              ("rand", "random"), ("noise", "random"))


def split_ratio(unit: str) -> tuple[str, str]:
    """``"(m/s^2)/V"`` -> ``("m/s^2", "V")``: the output and input units of an FRF."""
    m = _RATIO.match(unit.strip())
    if not m:
        return unit, ""
    return m.group(1).strip(), m.group(2).strip()


def run_excitation(run: str) -> tuple[str | None, str | None]:
    """(kind, direction) of the excitation as a Test.Lab run name states it, or None:
    ``Round1_Chirp0p05_70to110Hz_1`` -> ``("sweep", "up")``, ``..._Rand0p30_0to110Hz_1``
    -> ``("random", None)``; words ``step``, ``chirp``/``sweep``, ``rand``/``noise``, a
    span ``AtoBHz`` (up where B > A)."""
    low = run.lower()
    kind = next((k for word, k in _RUN_KINDS if word in low), None)
    direction = None
    m = _SPAN.search(run)
    if m and kind != "random":
        a, b = (float(x.replace("p", ".")) for x in m.groups())
        direction = "up" if b > a else "down" if b < a else None
    return kind, direction


def _frf_only(where: str, paths: list[Path], frfs: list[LMSFunction],
              coherence: list[LMSFunction], channels: Sequence[str] | None,
              names: Mapping[str, str] | None, level: float | None) -> Measurement:
    """An FRF-only measurement from LMS FRF structs (and their coherences, where read)."""
    _name_channels(frfs, names)
    _name_channels(coherence, names)
    first = frfs[0]
    refs = {str(f.record.get("reference") or "") for f in frfs}
    if len(refs) > 1:
        raise MeasurementError(where, f"the FRFs have different references "
                                      f"({', '.join(sorted(refs))}); load them separately")
    for f in frfs:
        if (len(f.values), f.x0, f.dx) != (len(first.values), first.x0, first.dx):
            raise MeasurementError(f.file, f"frequency lines ({len(f.values)} from {f.x0:g} "
                                           f"Hz by {f.dx:g} Hz) differ from "
                                           f"{first.name!r}'s", f.name)
    frfs = _keep(where, frfs, channels, "the FRFs are of {}")
    units, file_units = {}, {}
    for f in frfs:
        out, inp = split_ratio(f.unit)
        if inp not in EXCITATION_UNITS:
            raise MeasurementError(f.file, f"FRF unit {f.unit!r}: the reference must be in N "
                                           f"or V", f.name)
        if units.setdefault("force", inp) != inp:
            raise MeasurementError(f.file, f"FRF per {inp}, the others per "
                                           f"{units['force']}", f.name)
        units[f.name] = out
        file_units[f.name] = split_ratio(f.file_unit)[0]
    file_units["force"] = units["force"]
    notes = []
    lv, origin = level, "given"
    if lv is None:
        lv, origin = level_from_name(paths[0]), "folder name"
    if lv is None:
        notes.append("the level is unknown (no level given, none in the folder name): the "
                     "model cannot be driven as the rig was")
    run = str(first.record.get("run") or "")
    kind, direction = run_excitation(run)
    coh = {c.name: c.values for c in coherence if c.name in units
           and len(c.values) == len(first.values)}
    record = FRFRecord.checked(
        where, first.x, {f.name: f.values for f in frfs}, units, coherence=coh, kind=kind,
        direction=direction, averages=_int_or_none(first.record.get("averages")),
        estimator=str(first.record.get("method") or "") or None,
        meta={"source": "LMS Test.Lab", "run": run, "reference": refs.pop(),
              "level_from": origin if lv is not None else None,
              "lms": {f.name: _meta(f) for f in frfs}})
    if kind or direction:
        notes.append(f"from the run name {run!r}: "
                     + ", ".join(x for x in (kind and kind.replace("_", " "),
                                             direction and f"driven {direction}") if x))
    return Measurement(file=where, signals=record, units=file_units,
                       level=None if lv is None else float(lv), notes=notes)


def _keep(where: str, funcs: list[LMSFunction], channels: Sequence[str] | None,
          listing: str) -> list[LMSFunction]:
    """The functions of ``channels`` (all without), or an error naming a missing one and
    listing (``listing.format(names)``) what is there."""
    if channels is None:
        return funcs
    avail = [f.name for f in funcs]
    for ch in channels:
        if ch not in avail:
            raise MeasurementError(where, "missing channel; " + listing.format(
                ", ".join(avail)), ch)
    return [f for f in funcs if f.name in channels]


def _meta(f: LMSFunction) -> dict:
    return {"label": f.label, "channel_id": f.channel_id, "file": f.file, "struct": f.struct,
            "column": f.column, "unit": f.unit, "file_unit": f.file_unit,
            "display_factor": f.factor, **{k: v for k, v in f.record.items()
                                           if k in ("averages", "average_type", "run")}}


def _excitation(where: str, times: list[LMSFunction], spectral: list[LMSFunction],
                name: str | None) -> LMSFunction:
    listing = ", ".join(f"{f.name} [{f.unit}]" for f in times)
    if name is not None:
        for f in times:
            if name in (f.name, f.label, f.point):
                if f.unit not in EXCITATION_UNITS:
                    raise MeasurementError(f.file, f"excitation must be in N (force) or V "
                                                   f"(voltage), this channel is in {f.unit}",
                                           f.name)
                return f
        raise MeasurementError(where, f"no excitation channel of this name; time signals: "
                                      f"{listing}", name)
    for unit in EXCITATION_UNITS:
        cand = [f for f in times if f.unit == unit]
        if len(cand) == 1:
            return cand[0]
        if len(cand) > 1:
            refs = {str(f.record.get("reference") or "") for f in spectral}
            chosen = [f for f in cand if f.label in refs]
            if len(chosen) == 1:
                return chosen[0]
            raise MeasurementError(where, f"several channels in {unit} could be the "
                                          f"excitation ({', '.join(f.name for f in cand)}); "
                                          f"name it with excitation=")
    raise MeasurementError(where, f"no excitation channel (a force in N or a voltage in V) "
                                  f"among the time signals {listing}; load the folder with "
                                  f"the excitation file too (e.g. TimeShaker.mat)", "force")


def _check_consistent(exc: LMSFunction, resp: list[LMSFunction]) -> None:
    run = str(exc.record.get("run") or "")
    for f in resp:  # files of two runs of one rig have the same sampling and length
        other = str(f.record.get("run") or "")
        if run and other and other != run:
            raise MeasurementError(f.file, f"recorded in the Test.Lab run {other!r}, the "
                                           f"excitation {exc.name!r} in {run!r} ({exc.file}): "
                                           f"files of different runs", f.name)
    for f in [exc, *resp]:
        if np.iscomplexobj(f.values):
            raise MeasurementError(f.file, "complex values in a time signal", f.name)
        bad = ~np.isfinite(f.values)
        if bad.any():
            raise MeasurementError(f.file, f"{int(bad.sum())} NaN/inf value(s), first at "
                                           f"sample {int(np.argmax(bad))}", f.name)
    for f in resp:
        if abs(f.dx - exc.dx) > 1e-9 * exc.dx:
            raise MeasurementError(f.file, f"sampling differs: increment {f.dx:.10g} s "
                                           f"(fs = {1 / f.dx:.6g} Hz) but {exc.dx:.10g} s "
                                           f"(fs = {1 / exc.dx:.6g} Hz) for the excitation "
                                           f"{exc.name!r} in {exc.file}", f.name)
        if abs(f.x0 - exc.x0) > 1e-6 * exc.dx:
            raise MeasurementError(f.file, f"start time {f.x0:.10g} s differs from the "
                                           f"excitation's {exc.x0:.10g} s ({exc.file})", f.name)
        if len(f.values) != len(exc.values):
            raise MeasurementError(f.file, f"{len(f.values)} samples but the excitation "
                                           f"{exc.name!r} in {exc.file} has "
                                           f"{len(exc.values)}: lengths differ", f.name)


def frf_settings(fn: LMSFunction) -> dict:
    """Keyword arguments of :func:`sensfw.signal.frf` that reproduce an LMS FRF/coherence.

    The estimator is ``frf.method`` (coherences: H1, which gives the same coherence), the
    window is ``energy_amplitude_transform.windows`` (it must equal the reference
    channel's: one window for both), the segment length comes from the frequency
    resolution, ``df = x_values.increment`` (``nperseg = fs / df``), with no overlap. LMS
    averages ``nr_of_averages`` acquisition frames; pass them to ``frf`` as rows of 2-D
    inputs where the frames are available (the returned dict holds the count under
    ``"averages"``, which is not an ``frf`` argument).
    """
    if fn.x_unit != "Hz":
        raise MeasurementError(fn.file, f"{fn.kind} has its x axis in {fn.x_unit}, not Hz",
                               fn.name)
    method = str(fn.record.get("method") or "H1")
    est = {"H1": "H1", "H2": "H2", "HV": "Hv"}.get(method.upper())
    if est is None:
        raise MeasurementError(fn.file, f"FRF method {method!r} has no sensfw estimator "
                                        f"(H1, H2, Hv)", fn.name)
    win = str(fn.record.get("window") or "UNIFORM").upper()
    ref_win = str(fn.record.get("reference_window") or win).upper()
    if ref_win != win:
        raise MeasurementError(fn.file, f"response window {win} differs from the reference "
                                        f"window {ref_win}; sensfw.signal.frf applies one "
                                        f"window to both", fn.name)
    if win not in LMS_WINDOWS:
        raise MeasurementError(fn.file, f"LMS window {win!r} has no scipy equivalent here "
                                        f"({', '.join(LMS_WINDOWS)})", fn.name)
    return {"estimator": est, "window": LMS_WINDOWS[win], "df": fn.dx, "noverlap": 0,
            "averages": fn.record.get("averages")}
