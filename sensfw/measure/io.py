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
from .measurement import FRFRecord, Measurement

__all__ = ["FRFRecord", "Measurement", "load", "load_all", "read_csv", "read_uff",
           "read_uff_levels", "write_csv", "write_uff"]

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
_DIRECTION = re.compile(r"direction\s*=\s*(up|down)", re.IGNORECASE)
_KIND = re.compile(r"kind\s*=\s*([a-z_]+)", re.IGNORECASE)
#: UFF58 specific data types (abscissa, ordinate) by SI unit
_UFF_TYPES = {"s": 17, "Hz": 18, "m": 8, "m/s": 11, "m/s^2": 12, "N": 13, "Pa": 15}


def _uff_label(rec: dict, key: str) -> str | None:
    v = str(rec.get(key) or "").strip()
    return None if not v or v.upper() == "NONE" else v


def _is_frf(rec: dict) -> bool:
    """A UFF58 record is an FRF (func_type 4), or spectral (complex, or an abscissa in
    Hz), rather than a time series."""
    return rec.get("func_type") == 4 or np.iscomplexobj(rec["data"]) or \
        rec.get("abscissa_spec_data_type") == 18


def read_uff_levels(path: str | Path) -> list[Measurement]:
    """Every measurement in a UFF file: one UFF58 record per channel, and per level where
    the records say so (``id2 = "level=0.3"``, as :func:`write_uff` writes).

    Time series (a ``force`` record and the responses) make a measurement per level; FRF
    records (function type 4, complex, frequency in Hz) an FRF-only one per level and
    direction (``id2 = "level=0.3 direction=down kind=stepped_sine"``), output per input
    as the record's ordinate and denominator labels say."""
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
    groups: dict[tuple, list[dict]] = {}
    for rec in records:
        tag = str(rec.get("id2") or "")
        m, d = _LEVEL.search(tag), _DIRECTION.search(tag)
        key = (_is_frf(rec), float(m.group(1)) if m else None,
               d.group(1).lower() if d and _is_frf(rec) else None)
        groups.setdefault(key, []).append(rec)
    for frf in (False, True):
        levels = {k[1] for k in groups if k[0] == frf}
        if None in levels and len(levels) > 1:
            raise MeasurementError(file, "some records carry a level (id2 = 'level=...') "
                                         "and others do not")
    side = _sidecar(path)
    out = []
    for (frf, level, direction), recs in groups.items():
        where = file if level is None else f"{file} (level {level:g})"
        if frf:
            said = ", ".join(x for x in (level is not None and f"level {level:g}",
                                         direction) if x)
            out.append(_uff_frfs(f"{file} ({said})" if said else file, recs,
                                 level if level is not None else side.get("level"),
                                 direction))
            continue
        columns, unit_map, t = {}, {}, None
        for rec in recs:
            name = _uff_name(where, rec)
            x = np.asarray(rec["x"], float)
            y = np.asarray(rec["data"], float)
            unit = _uff_label(rec, "ordinate_axis_units_lab")
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
    return sorted(out, key=lambda m: (m.level is None, m.level or 0.0, m.frf is not None,
                                      getattr(m.frf, "direction", None) or ""))


def _uff_name(where: str, rec: dict) -> str:
    name = str(rec.get("id1") or rec.get("rsp_ent_name") or "").strip()
    if not name or name.upper() == "NONE":
        raise MeasurementError(where, "a UFF58 record has no name (id1)")
    return name


def _uff_frfs(where: str, recs: list[dict], level, direction: str | None) -> Measurement:
    """An FRF-only measurement from UFF58 FRF records of one level and direction."""
    channels, units, file_units, f = {}, {}, {}, None
    kind = None
    for rec in recs:
        name = _uff_name(where, rec)
        if name in channels:
            raise MeasurementError(where, "two FRF records for the same channel", name)
        out_u = _uff_label(rec, "ordinate_axis_units_lab")
        in_u = _uff_label(rec, "orddenom_axis_units_lab") or "N"
        in_si = _target("force", in_u)
        if units.setdefault("force", in_si) != in_si:
            raise MeasurementError(where, f"FRF per {in_u}, the others per "
                                          f"{units['force']}", name)
        units[name] = _target(name, out_u)
        factor = _factor(where, name, out_u, units[name]) / \
            _factor(where, "force", in_u, in_si)
        channels[name] = np.asarray(rec["data"], complex) * factor
        file_units[name], file_units["force"] = out_u or units[name], in_u
        x = np.asarray(rec["x"], float)
        if f is None:
            f = x
        elif len(x) != len(f) or np.max(np.abs(x - f)) > 1e-9 * max(1.0, abs(f[-1])):
            raise MeasurementError(where, "frequency lines differ from the first record",
                                   name)
        m = _KIND.search(str(rec.get("id2") or ""))
        kind = kind or (m.group(1).lower() if m else None)
    record = FRFRecord.checked(where, f, channels, units, kind=kind, direction=direction,
                               meta={"source": "UFF58"})
    return Measurement(file=where, signals=record, units=file_units,
                       level=None if level is None else float(level))


def read_uff(path: str | Path) -> Measurement:
    """A UFF file holding one measurement (see :func:`read_uff_levels` for several)."""
    found = read_uff_levels(path)
    if len(found) > 1:
        raise MeasurementError(str(path), f"holds {len(found)} measurements (levels or "
                                          f"sweep directions); load it with load_all()")
    return found[0]


def write_uff(path: str | Path, measurements: list[tuple[Signals | FRFRecord, float | None]]
              ) -> Path:
    """Write one or several levels as UFF58 records, one per channel and level (the level
    in ``id2``): time records of :class:`~sensfw.models.base.Signals`, FRF records (function
    type 4, complex, on the record's lines; direction and kind in ``id2`` too) of an
    :class:`~sensfw.measure.measurement.FRFRecord`."""
    import pyuff

    path = Path(path)
    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    for rec, level in measurements:
        tag = "" if level is None else f"level={level:.10g}"
        if isinstance(rec, FRFRecord):
            tag = " ".join(x for x in (tag, rec.direction and f"direction={rec.direction}",
                                       rec.kind and f"kind={rec.kind}") if x)
            inp = rec.units.get("force", "N")
            for name, h in rec.channels.items():
                unit = rec.units.get(name, ACCEL_UNIT)
                uff.write_sets(pyuff.prepare_58(
                    func_type=4, id1=name, id2=tag, rsp_node=1, rsp_dir=1, ref_node=1,
                    ref_dir=1, data=np.asarray(h, complex), x=np.asarray(rec.f, float),
                    abscissa_spacing=0, abscissa_spec_data_type=18,
                    ordinate_spec_data_type=_UFF_TYPES.get(unit, 0),
                    orddenom_spec_data_type=_UFF_TYPES.get(inp, 0),
                    ordinate_axis_units_lab=unit, orddenom_axis_units_lab=inp, binary=0),
                    mode="add")
            continue
        for name, y in [("force", rec.force), *rec.channels.items()]:
            unit = rec.units.get(name, _target(name))
            uff.write_sets(pyuff.prepare_58(
                func_type=1, id1=name, id2=tag, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
                data=np.asarray(y, float), x=rec.t, abscissa_spacing=1, abscissa_min=0.0,
                abscissa_inc=1 / rec.fs, abscissa_spec_data_type=17,
                ordinate_spec_data_type=13 if name == "force" else 12,
                orddenom_spec_data_type=13, ordinate_axis_units_lab=unit, binary=0),
                mode="add")
    return path


def load(path: str | Path) -> Measurement:
    """A measurement file, by extension: ``.csv``/``.txt``, ``.uff``/``.unv``, or ``.mat``
    (LMS Test.Lab export), or a folder of LMS ``.mat`` exports (one level: e.g.
    ``TimeShaker.mat`` with the excitation and ``Time.mat`` with the responses), read by
    :func:`sensfw.measure.lms.read_lms`. A file of FRFs without time data (an LMS
    ``FRF.mat`` alone, UFF58 FRF records) gives an FRF-only measurement
    (``Measurement.frf``)."""
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
