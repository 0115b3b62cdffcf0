"""Measured signals: loading (CSV with units, UFF58, LMS Test.Lab MAT exports) and writing
(synthetic measurements).

CSV: a header row with ``time``, the excitation ``force`` and one column per sensor channel;
units either in the header (``force [N]``, ``crank_axial [m/s^2]``, ``[g]`` meaning standard
gravity) or in a sidecar ``<file>.toml``/``<file>.json`` with ``[units]`` (column -> unit) and
optionally ``fs`` and ``level`` (excitation amplitude, N). UFF58 (time records and FRF
records): :mod:`sensfw.measure.uff`. LMS Test.Lab MAT v5 exports (a ``.mat`` file or a
folder of them): :mod:`sensfw.measure.lms`; their excitation may be an amplifier voltage
(``Measurement.excitation == "voltage"``). :func:`load` and :func:`load_all` read any of
them.

Loaded values are converted to SI (:mod:`sensfw.measure.columns`). Problems raise
:class:`~sensfw.errors.MeasurementError` naming the file and the channel.
"""

from __future__ import annotations

import difflib
import re
from pathlib import Path

import numpy as np

from ..errors import MeasurementError
from ..models.base import Signals
from .columns import ACCEL_UNIT, assemble, factor, sidecar, target
from .measurement import FRFRecord, Measurement
from .uff import read_uff, read_uff_levels, write_uff

__all__ = ["FRFRecord", "Measurement", "load", "load_all", "read_csv", "read_uff",
           "read_uff_levels", "write_csv", "write_uff"]

_HEADER = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[([^\]]*)\])?\s*$")


def read_csv(path: str | Path) -> Measurement:
    path = Path(path)
    file = str(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a byte-order mark, as Excel writes
    except FileNotFoundError:
        raise MeasurementError(file, "file not found") from None
    except UnicodeDecodeError:
        raise MeasurementError(file, "not a text (CSV) file") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if len(lines) < 3:
        raise MeasurementError(file, "needs a header row and at least two data rows")
    first = lines[0]
    delim = max(("\t", ";", ","), key=first.count) if any(c in first for c in "\t;,") else ","
    header = [h.strip().strip('"').strip("'").strip() for h in first.split(delim)]
    if len(header) > 1 and header[-1] == "" and all(
            ln.rstrip().endswith(delim) for ln in lines[:20]):
        # a separator at the end of every line (some exports): no column there
        header = header[:-1]
        lines = [ln.rstrip()[:-1] for ln in lines]
    if all(_is_number(h) for h in header):
        raise MeasurementError(file, "the first row holds numbers: no header row; name the "
                               "columns, e.g. 'time [s],force [N],a1 [m/s^2]'")
    if delim in ";\t" and any(_is_number(v.strip().replace(",", ".")) and "," in v
                              for ln in lines[1:6] for v in ln.split(delim)):
        raise MeasurementError(file, "decimal commas (e.g. '0,5'): write numbers with a "
                               "decimal point, or save the sheet as CSV in an English locale")
    names, header_units = [], {}
    for h in header:
        m = _HEADER.match(h)
        if not m:
            raise MeasurementError(file, f"cannot read column header {h!r} (a name, its unit "
                                   "in square brackets: 'a1 [m/s^2]')")
        name = m.group(1).strip()
        if name.lower() in ("time", "force"):  # "Time [s]", "FORCE [N]"
            name = name.lower()
        names.append(name)
        if m.group(2):
            header_units[name] = m.group(2).strip()
    if len(set(names)) != len(names):
        raise MeasurementError(file, f"duplicate column names in header {names}")
    try:
        data = np.genfromtxt([ln.replace('"', "") for ln in lines[1:]], delimiter=delim,
                             dtype=float)  # numbers written quoted, as some exports do
    except ValueError as err:
        raise MeasurementError(file, f"malformed data rows: {err}") from None
    data = np.atleast_2d(data)
    if data.shape[1] != len(names):
        raise MeasurementError(file, f"{data.shape[1]} data columns but {len(names)} headers")
    side = sidecar(path)
    side_units = _sidecar_units(file, side, names)
    for name, unit in side_units.items():
        said = header_units.get(name)
        if said is not None and said != unit:
            raise MeasurementError(file, f"the header says {said!r}, the sidecar "
                                   f"{path.with_suffix('.toml').name} says {unit!r}", name)
    unit_map = {**header_units, **side_units}
    columns = {}
    for i, name in enumerate(names):
        unit = unit_map.get(name)
        columns[name] = data[:, i] * factor(file, name, unit, target(name, unit))
    return assemble(file, columns, unit_map, side.get("fs"), side.get("level"))


def _sidecar_units(file: str, side: dict, names: list[str]) -> dict[str, str]:
    """The sidecar's ``[units]`` (column -> unit; ``Time``, ``FORCE`` as the header reads
    them), each of a column the file has: a unit for a misspelt column would be dropped
    and the column read in the default unit (a response in g taken as m/s^2, 9.8 times
    too small)."""
    given = side.get("units", {})
    if not isinstance(given, dict):
        raise MeasurementError(file, f"the sidecar's units = {given!r}: a table of column "
                                     "-> unit ([units] a1 = \"g\")")
    out = {}
    for name, unit in given.items():
        key = name.lower() if name.lower() in ("time", "force") else name
        if key not in names:
            close = difflib.get_close_matches(key, names, n=1, cutoff=0.5)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise MeasurementError(file, f"the sidecar gives the unit {unit!r} for a column "
                                         f"the file does not have (columns: "
                                         f"{', '.join(names)}){hint}", name)
        out[key] = str(unit)
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


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
