"""Measured signals: loading (CSV with units, UFF58, LMS Test.Lab MAT exports) and writing
(synthetic measurements).

CSV: a header row with ``time``, the excitation ``force`` and one column per sensor channel;
units either in the header (``force [N]``, ``crank_axial [m/s^2]``, ``[g]`` meaning standard
gravity) or in a sidecar ``<file>.toml``/``<file>.json`` with ``[units]`` (column -> unit) and
optionally ``fs`` and ``level`` (excitation amplitude, N). UFF58: one record per channel
(pyuff); the record's ``id1`` (or response-entity name) names the channel, ``force`` (or a
record whose response direction/entity says force) is the excitation. LMS Test.Lab MAT v5
exports (a ``.mat`` file or a folder of them): :mod:`sensfw.measure.lms`; their excitation may
be an amplifier voltage (``Measurement.excitation == "voltage"``).

Loaded values are converted to SI (N, m/s^2, s). Problems raise
:class:`~sensfw.errors.MeasurementError` naming the file and the channel.
"""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import numpy as np

from ..errors import MeasurementError
from ..models.base import Signals
from .measurement import Measurement

__all__ = ["Measurement", "load", "load_all", "read_csv", "read_uff", "read_uff_levels",
           "write_csv", "write_uff"]

TARGET_UNITS = {"time": "s", "force": "N"}
ACCEL_UNIT = "m/s^2"
_HEADER = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[([^\]]*)\])?\s*$")


def _quantity(unit: str):
    """A pint quantity of 1 ``unit`` (``g`` is standard gravity)."""
    from ..study import units

    u = unit.strip()
    if u.lower() in ("g", "gn", "g0", "g_n"):
        u = "standard_gravity"
    return units().Quantity(1.0, u)


def _factor(file: str, column: str, unit: str | None, target: str) -> float:
    """Multiplier from ``unit`` to ``target``."""
    if not unit:
        return 1.0
    try:
        return float(_quantity(unit).to(target).magnitude)
    except Exception as err:
        raise MeasurementError(file, f"unit {unit!r} cannot be converted to {target}: {err}",
                               column) from None


def _sidecar(path: Path) -> dict:
    for ext, reader in ((".toml", tomllib.loads), (".json", json.loads)):
        side = path.with_suffix(ext) if path.suffix != ext else None
        side2 = Path(str(path) + ext)
        for candidate in (side, side2):
            if candidate is not None and candidate.exists():
                try:
                    return reader(candidate.read_text(encoding="utf-8"))
                except Exception as err:
                    raise MeasurementError(str(candidate), f"unreadable sidecar: {err}") \
                        from None
    return {}


#: the SI units a response channel is converted to: the first of its dimension
SI_UNITS = ("m/s^2", "m/s", "m", "N", "V", "Pa", "rad/s^2", "rad/s", "rad")


def _fits(unit: str, si: str) -> bool:
    try:
        return _quantity(unit).dimensionality == _quantity(si).dimensionality
    except Exception:
        return False


def _target(column: str, unit: str | None = None) -> str:
    """SI unit a column is converted to: the excitation is a force or a voltage, a response
    is converted to the SI unit of its dimension (:data:`SI_UNITS`; an acceleration where
    no unit is given)."""
    if column in TARGET_UNITS and column != "force":
        return TARGET_UNITS[column]
    if column == "force":
        return "V" if unit and _fits(unit, "V") else "N"
    return next((si for si in SI_UNITS if unit and _fits(unit, si)), ACCEL_UNIT)


def read_csv(path: str | Path) -> Measurement:
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise MeasurementError(file, "file not found") from None
    except UnicodeDecodeError:
        raise MeasurementError(file, "not a text (CSV) file") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if len(lines) < 3:
        raise MeasurementError(file, "needs a header row and at least two data rows")
    delim = ";" if lines[0].count(";") > lines[0].count(",") else ","
    header = [h.strip() for h in lines[0].split(delim)]
    names, header_units = [], {}
    for h in header:
        m = _HEADER.match(h)
        if not m:
            raise MeasurementError(file, f"cannot read column header {h!r}")
        names.append(m.group(1).strip())
        if m.group(2):
            header_units[m.group(1).strip()] = m.group(2).strip()
    if len(set(names)) != len(names):
        raise MeasurementError(file, f"duplicate column names in header {names}")
    try:
        data = np.genfromtxt(lines[1:], delimiter=delim, dtype=float)
    except ValueError as err:
        raise MeasurementError(file, f"malformed data rows: {err}") from None
    data = np.atleast_2d(data)
    if data.shape[1] != len(names):
        raise MeasurementError(file, f"{data.shape[1]} data columns but {len(names)} headers")
    side = _sidecar(path)
    unit_map = {**header_units, **side.get("units", {})}
    columns = {}
    for i, name in enumerate(names):
        unit = unit_map.get(name)
        columns[name] = data[:, i] * _factor(file, name, unit, _target(name, unit))
    return _assemble(file, columns, unit_map, side.get("fs"), side.get("level"))


def _assemble(file: str, columns: dict[str, np.ndarray], unit_map: dict, fs_declared,
              level) -> Measurement:
    if "time" not in columns:
        raise MeasurementError(file, "no 'time' column", "time")
    if "force" not in columns:
        raise MeasurementError(file, "no 'force' column (the excitation force)", "force")
    for name, x in columns.items():
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.argmax(bad))
            raise MeasurementError(file, f"{int(bad.sum())} NaN/inf value(s), first in data "
                                         f"row {i + 1}", name)
    t = columns["time"]
    dt = np.diff(t)
    if len(dt) == 0 or np.any(dt <= 0):
        raise MeasurementError(file, "time is not strictly increasing", "time")
    step = float(np.median(dt))
    if np.max(np.abs(dt - step)) > 1e-3 * step:
        worst = int(np.argmax(np.abs(dt - step)))
        raise MeasurementError(file, f"non-uniform sampling: step {dt[worst]:.6g} s at row "
                                     f"{worst + 2} vs {step:.6g} s elsewhere", "time")
    fs = 1.0 / step
    if fs_declared is not None and abs(fs - float(fs_declared)) > 1e-3 * float(fs_declared):
        raise MeasurementError(file, f"sample rate from the time column is {fs:.6g} Hz but the "
                                     f"sidecar declares fs = {fs_declared} Hz", "time")
    channels = {k: v for k, v in columns.items() if k not in ("time", "force")}
    sig = Signals(t=t - t[0], force=columns["force"], channels=channels, fs=fs,
                  units={k: _target(k, unit_map.get(k)) for k in ("force", *channels)})
    return Measurement(file=file, signals=sig, units=dict(unit_map),
                       level=None if level is None else float(level))


_LEVEL = re.compile(r"level\s*=\s*([-+0-9.eE]+)")


def read_uff_levels(path: str | Path) -> list[Measurement]:
    """Every measurement in a UFF file: one record (UFF58, time series) per channel, and per
    level where the records say so (``id2 = "level=0.3"``, as :func:`write_uff` writes)."""
    import pyuff

    path = Path(path)
    file = str(path)
    if not path.exists():
        raise MeasurementError(file, "file not found")
    try:
        uff = pyuff.UFF(file)
        sets = uff.read_sets()
    except Exception as err:
        raise MeasurementError(file, f"not a readable UFF file: {err}") from None
    if isinstance(sets, dict):
        sets = [sets]
    records = [s for s in sets if s.get("type") == 58]
    if not records:
        raise MeasurementError(file, "no UFF58 (function at nodal DOF) records")
    groups: dict[float | None, list[dict]] = {}
    for rec in records:
        m = _LEVEL.search(str(rec.get("id2") or ""))
        groups.setdefault(float(m.group(1)) if m else None, []).append(rec)
    if None in groups and len(groups) > 1:
        raise MeasurementError(file, "some records carry a level (id2 = 'level=...') and "
                                     "others do not")
    side = _sidecar(path)
    out = []
    for level, recs in groups.items():
        where = file if level is None else f"{file} (level {level:g})"
        columns, unit_map, t = {}, {}, None
        for rec in recs:
            name = str(rec.get("id1") or rec.get("rsp_ent_name") or "").strip()
            if not name:
                raise MeasurementError(where, "a UFF58 record has no name (id1)")
            if np.iscomplexobj(rec["data"]):
                raise MeasurementError(where, "complex (spectral) record; expected a time "
                                              "series", name)
            x = np.asarray(rec["x"], float)
            y = np.asarray(rec["data"], float)
            unit = str(rec.get("ordinate_axis_units_lab") or "").strip() or None
            key = "force" if name.lower() in ("force", "excitation", "input") else name
            if key in columns:
                raise MeasurementError(where, "two records for the same channel", key)
            columns[key] = y * _factor(where, key, unit, _target(key, unit))
            unit_map[key] = unit or _target(key)
            if t is None:
                t = x
            elif len(x) != len(t) or np.max(np.abs(x - t)) > 1e-9 * max(1.0, abs(t[-1])):
                raise MeasurementError(where, "time axis differs from the first record", key)
        columns["time"] = t
        out.append(_assemble(where, columns, unit_map, side.get("fs"),
                             level if level is not None else side.get("level")))
    return sorted(out, key=lambda m: (m.level is None, m.level or 0.0))


def read_uff(path: str | Path) -> Measurement:
    """A UFF file holding one measurement (see :func:`read_uff_levels` for several)."""
    found = read_uff_levels(path)
    if len(found) > 1:
        raise MeasurementError(str(path), f"holds {len(found)} levels; load it with "
                                          "load_all()")
    return found[0]


def write_uff(path: str | Path, measurements: list[tuple[Signals, float | None]]) -> Path:
    """Write one or several levels as UFF58 time records (one per channel and level, the
    level in ``id2``)."""
    import pyuff

    path = Path(path)
    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    for sig, level in measurements:
        tag = "" if level is None else f"level={level:.10g}"
        for name, y in [("force", sig.force), *sig.channels.items()]:
            unit = sig.units.get(name, _target(name))
            uff.write_sets(pyuff.prepare_58(
                func_type=1, id1=name, id2=tag, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
                data=np.asarray(y, float), x=sig.t, abscissa_spacing=1, abscissa_min=0.0,
                abscissa_inc=1 / sig.fs, abscissa_spec_data_type=17,
                ordinate_spec_data_type=13 if name == "force" else 12,
                orddenom_spec_data_type=13, ordinate_axis_units_lab=unit, binary=0),
                mode="add")
    return path


def load(path: str | Path) -> Measurement:
    """A measurement file, by extension: ``.csv``/``.txt``, ``.uff``/``.unv``, or ``.mat``
    (LMS Test.Lab export), or a folder of LMS ``.mat`` exports (one level: e.g.
    ``TimeShaker.mat`` with the excitation and ``Time.mat`` with the responses), read by
    :func:`sensfw.measure.lms.read_lms`."""
    path = Path(path)
    ext = path.suffix.lower()
    if path.is_dir() or ext == ".mat":
        from .lms import read_lms

        return read_lms(path)
    if ext in (".uff", ".unv"):
        return read_uff(path)
    if ext in (".csv", ".txt", ".dat"):
        return read_csv(path)
    raise MeasurementError(str(path), f"unknown file type {ext!r}; use .csv, .uff, .mat (LMS "
                                      f"Test.Lab) or a folder of LMS .mat exports")


def load_all(path: str | Path) -> list[Measurement]:
    """Every measurement in a file or folder: a UFF file may hold several levels; a folder
    of level folders (each with LMS ``.mat`` exports) gives one measurement per level."""
    path = Path(path)
    if path.suffix.lower() in (".uff", ".unv"):
        return read_uff_levels(path)
    if path.is_dir() and not any(path.glob("*.mat")):
        levels = sorted(p for p in path.iterdir() if p.is_dir() and any(p.glob("*.mat")))
        if levels:
            return [load(p) for p in levels]
    return [load(path)]


def write_csv(path: str | Path, signals: Signals, level: float | None = None,
              meta: dict | None = None) -> Path:
    """Write signals as a measurement CSV with units in the header (+ a TOML sidecar with the
    sample rate, level and any ``meta``, written by tomlkit: any string, nested tables and
    arrays round-trip through :func:`load`; a ``None`` anywhere in ``meta`` is an error
    naming its key, since TOML has no null)."""
    path = Path(path)
    side = path.with_suffix(".toml")
    text = sidecar_text(str(side), signals.fs, level, meta)  # checked before writing anything
    cols = ["time [s]", f"force [{signals.units.get('force', 'N')}]",
            *[f"{k} [{signals.units.get(k, ACCEL_UNIT)}]" for k in signals.channels]]
    data = np.column_stack([signals.t, signals.force, *signals.channels.values()])
    np.savetxt(path, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
    side.write_text(text, encoding="utf-8")
    return path


def _null_at(value, where: str) -> str | None:
    """The key path of the first ``None`` inside ``value`` (dicts and lists), or None."""
    if value is None:
        return where
    items = value.items() if isinstance(value, dict) else \
        enumerate(value) if isinstance(value, (list, tuple)) else ()
    for k, v in items:
        found = _null_at(v, f"{where}[{k!r}]" if isinstance(k, str) else f"{where}[{k}]")
        if found:
            return found
    return None


def sidecar_text(file: str, fs: float, level: float | None, meta: dict | None) -> str:
    """The TOML sidecar of a measurement CSV: ``fs``, ``level`` and the entries of ``meta``
    (:func:`write_csv`)."""
    import tomlkit
    from tomlkit.exceptions import ConvertError

    doc = tomlkit.document()
    doc["fs"] = float(fs)
    if level is not None:
        doc["level"] = float(level)
    for key, value in (meta or {}).items():
        where = f"meta[{key!r}]"
        if key in doc or key == "units":
            raise MeasurementError(file, f"{where}: the sidecar's own key; rename it")
        null = _null_at(value, where)
        if null:
            raise MeasurementError(file, f"{null} is None, which TOML cannot hold (it has no "
                                         f"null): leave the key out or give a value")
        try:
            doc[key] = value.item() if isinstance(value, np.generic) else value
        except (ConvertError, TypeError, ValueError) as err:
            raise MeasurementError(file, f"{where} = {value!r} cannot be written as TOML: "
                                         f"{err}") from None
    return tomlkit.dumps(doc)
