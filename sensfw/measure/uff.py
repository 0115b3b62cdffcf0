"""UFF58 measurement files (pyuff): time records per channel and level, and FRF records
(function type 4) per level and sweep direction.

One record per channel: ``id1`` (or the response entity's name) names it, ``force`` (or
``excitation``, ``input``) is the excitation; ``id2`` carries the level (``level=0.3``) and,
for FRF records, the direction and how they were measured (``direction=down
kind=stepped_sine``), as :func:`write_uff` writes them. Values are converted to SI from the
records' unit labels (:mod:`sensfw.measure.columns`).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import MeasurementError
from ..models.base import Signals
from .columns import ACCEL_UNIT, assemble, factor, sidecar, target
from .measurement import FRFRecord, Measurement

_LEVEL = re.compile(r"level\s*=\s*([-+0-9.eE]+)")
_DIRECTION = re.compile(r"direction\s*=\s*(up|down)", re.IGNORECASE)
_KIND = re.compile(r"kind\s*=\s*([a-z_]+)", re.IGNORECASE)
#: UFF58 specific data types (abscissa, ordinate) by SI unit
_UFF_TYPES = {"s": 17, "Hz": 18, "m": 8, "m/s": 11, "m/s^2": 12, "N": 13, "Pa": 15}


def _uff_label(rec: dict, key: str) -> str | None:
    v = str(rec.get(key) or "").strip()
    return None if not v or v.upper() == "NONE" else v


#: abscissa units a UFF58 record may carry, to seconds (time) or Hz (frequency)
_TIME_UNITS = {"s": 1.0, "sec": 1.0, "second": 1.0, "seconds": 1.0, "ms": 1e-3,
               "msec": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6}
_FREQ_UNITS = {"hz": 1.0, "1/s": 1.0, "khz": 1e3, "rad/s": 1 / (2 * np.pi),
               "rpm": 1 / 60, "cpm": 1 / 60}


def _abscissa(where: str, rec: dict, name: str, frf: bool) -> np.ndarray:
    """The record's abscissa in s (a time record) or Hz (an FRF), from its unit label
    (``abscissa_axis_units_lab``; none: s or Hz); a label of neither kind is refused
    rather than read as s or Hz."""
    x = np.asarray(rec["x"], float)
    label = _uff_label(rec, "abscissa_axis_units_lab")
    if label is None:
        return x
    units = _FREQ_UNITS if frf else _TIME_UNITS
    inner = re.search(r"[\[(]\s*([^\])]+?)\s*[\])]", label)  # "Time (ms)", "f [Hz]"
    unit = (inner.group(1) if inner else label).strip()
    scale = units.get(unit.lower(), units.get(unit))
    if scale is None and unit.lower() in ("time", "t", "frequency", "freq", "f"):
        scale = 1.0  # a quantity named, no unit: the format's own (s, Hz)
    if scale is None:
        raise MeasurementError(where, f"abscissa in {label!r}: expected "
                               + ("a frequency (Hz, kHz, rad/s, RPM)" if frf else
                                  "a time (s, ms, us)"), name)
    return x * scale


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
    side = sidecar(path)
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
            x = _abscissa(where, rec, name, frf=False)
            y = np.asarray(rec["data"], float)
            unit = _uff_label(rec, "ordinate_axis_units_lab")
            key = "force" if name.lower() in ("force", "excitation", "input") else name
            if key in columns:
                raise MeasurementError(where, "two records for the same channel", key)
            columns[key] = y * factor(where, key, unit, target(key, unit))
            unit_map[key] = unit or target(key)
            if t is None:
                t = x
            elif len(x) != len(t) or np.max(np.abs(x - t)) > 1e-9 * max(1.0, abs(t[-1])):
                raise MeasurementError(where, "time axis differs from the first record", key)
        columns["time"] = t
        out.append(assemble(where, columns, unit_map, side.get("fs"),
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
        in_si = target("force", in_u)
        if units.setdefault("force", in_si) != in_si:
            raise MeasurementError(where, f"FRF per {in_u}, the others per "
                                          f"{units['force']}", name)
        units[name] = target(name, out_u)
        scale = factor(where, name, out_u, units[name]) / \
            factor(where, "force", in_u, in_si)
        channels[name] = np.asarray(rec["data"], complex) * scale
        file_units[name], file_units["force"] = out_u or units[name], in_u
        x = _abscissa(where, rec, name, frf=True)
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
            unit = rec.units.get(name, target(name))
            uff.write_sets(pyuff.prepare_58(
                func_type=1, id1=name, id2=tag, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
                data=np.asarray(y, float), x=rec.t, abscissa_spacing=1, abscissa_min=0.0,
                abscissa_inc=1 / rec.fs, abscissa_spec_data_type=17,
                ordinate_spec_data_type=13 if name == "force" else 12,
                orddenom_spec_data_type=13, ordinate_axis_units_lab=unit, binary=0),
                mode="add")
    return path
