"""The LMS Test.Lab MAT v5 export format: function structs -> channels in SI units.

Layout (read with ``scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)``)
-------------------------------------------------------------------------------------
Every MATLAB variable of an export is one *function* struct holding one or more channels
(columns):

``x_values``
    ``start_value``, ``increment`` and (time signals only) ``number_of_values``; its
    ``quantity`` is the axis: ``s`` for time signals (``fs = 1 / increment``), ``Hz`` for
    spectra (``increment`` is the frequency resolution).
``y_values``
    ``values``: ``(n,)`` for one channel or ``(n, k)`` for ``k`` channels (complex for FRFs
    and coherences). ``quantity``: ``label`` (the unit shown in Test.Lab, e.g. ``g``),
    ``unit_transformation`` (``factor``, ``offset``, ``log_reference``), ``quantity_terms``
    (the SI dimension: exponents ``num/den`` of LENGTH, ANGLE, MASS, TIME, CURRENT, LIGHT,
    TEMPERATURE, MOLCULAR_AMOUNT) and ``info`` (``"Data saved by Test.Lab in MKS"``).
``function_record``
    ``name`` (``"Time Acc1:+X"``), ``type`` (``Signal``, ``FRF``, ``Coherence``),
    ``primary_channel`` (``id``, the acquisition channel number, and ``label``,
    ``"<point>:<direction>"``), for FRFs and coherences ``reference_channel`` (``id``,
    ``label``, ``windows``), ``energy_amplitude_transform.windows`` (``type``, e.g.
    ``UNIFORM``, and ``parameter``), ``frf.method`` (``H1``...), ``average``
    (``nr_of_averages``, ``type`` e.g. ``LINAVERAGE``) and ``TL_export_properties_annotation``
    (project, section, run name). Per-channel fields are arrays of length ``k``.

Units. With ``info`` saying *MKS* the values are stored in SI units, whatever the label:
the unit transformation maps them to the label, ``shown = factor * value + offset``. For an
accelerometer labelled ``g`` the factor is 0.10197 = 1/9.80665 and the stored values are
m/s^2 (checked on the UNESP-BERT data: the free-end accelerometer equals the derivative of
the free-end laser velocity, stored in m/s with factor 1, to 1-2 %; reading the values as
g would make it 9.8 times too large). Exports without *MKS* in ``info`` are taken to hold
the labelled unit and converted with ``value = (shown - offset) / factor``. The SI unit of
each channel comes from its ``quantity_terms``.

The measurement built from these channels (names, excitation, level): :mod:`sensfw.measure.lms`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import MeasurementError

DIMENSIONS = ("LENGTH", "ANGLE", "MASS", "TIME", "CURRENT", "LIGHT", "TEMPERATURE",
              "MOLCULAR_AMOUNT")  # LMS's spelling
_SI_BASE = {"LENGTH": "m", "ANGLE": "rad", "MASS": "kg", "TIME": "s", "CURRENT": "A",
            "LIGHT": "cd", "TEMPERATURE": "K", "MOLCULAR_AMOUNT": "mol"}
_NAMED = {  # exponents (L, angle, M, T, I, ...) -> conventional SI unit
    (0, 0, 0, 0, 0, 0, 0, 0): "1",
    (0, 0, 0, 1, 0, 0, 0, 0): "s",
    (0, 0, 0, -1, 0, 0, 0, 0): "Hz",
    (1, 0, 0, 0, 0, 0, 0, 0): "m",
    (1, 0, 0, -1, 0, 0, 0, 0): "m/s",
    (1, 0, 0, -2, 0, 0, 0, 0): "m/s^2",
    (1, 0, 1, -2, 0, 0, 0, 0): "N",
    (2, 0, 1, -3, -1, 0, 0, 0): "V",
    (0, 0, 0, 0, 1, 0, 0, 0): "A",
    (-1, 0, 1, -2, 0, 0, 0, 0): "Pa",
}


@dataclass
class LMSFunction:
    """One channel of an LMS export: values in SI units and what the struct says of them."""

    name: str  # point name (Acc1), or point+direction where needed
    label: str  # LMS channel label, "<point>:<direction>"
    kind: str  # function_record.type: Signal, FRF, Coherence, ...
    values: np.ndarray  # SI units
    x0: float
    dx: float  # s (time signals) or Hz (spectra)
    x_unit: str  # "s", "Hz", ...
    unit: str  # SI unit of the values ("m/s^2", "V", "(m/s^2)/V" style for ratios)
    file_unit: str  # the label Test.Lab shows ("g")
    factor: float  # shown = factor * SI value + offset
    offset: float
    file: str
    struct: str
    column: int
    channel_id: int | None = None
    record: dict = field(default_factory=dict)  # reference, window, method, averages

    @property
    def x(self) -> np.ndarray:
        return self.x0 + self.dx * np.arange(len(self.values))

    @property
    def point(self) -> str:
        return self.label.split(":")[0].strip()


def _str(x) -> str:
    if isinstance(x, np.ndarray):
        return "" if x.size == 0 else str(x.ravel()[0])
    return str(x)


def _field(obj, path: str, file: str, struct: str):
    cur = obj
    for part in path.split("."):
        if not hasattr(cur, part):
            have = ", ".join(getattr(cur, "_fieldnames", []) or []) or "nothing"
            raise MeasurementError(file, f"struct {struct!r} has no field {path!r} ({part!r} "
                                         f"missing; there: {have})")
        cur = getattr(cur, part)
    return cur


def _opt(obj, path: str, default=None):
    cur = obj
    for part in path.split("."):
        if not hasattr(cur, part):
            return default
        cur = getattr(cur, part)
    return cur


def _per_column(x, k: int) -> list:
    """A per-channel record field as a list of ``k`` entries (scalars are shared)."""
    if isinstance(x, np.ndarray) and x.dtype == object and x.size == k:
        return list(x.ravel())
    if isinstance(x, np.ndarray) and x.dtype != object and x.size == k and k > 1:
        return list(x.ravel())
    return [x] * k


def _exponents(quantity) -> tuple | None:
    terms = _opt(quantity, "quantity_terms")
    if terms is None:
        return None
    exps = dict.fromkeys(DIMENSIONS, 0.0)
    for term in np.atleast_1d(terms).ravel():
        q = _str(_opt(term, "quantity", "")).upper()
        try:
            num, den = float(_opt(term, "num", 0)), float(_opt(term, "den", 1) or 1)
        except (TypeError, ValueError):
            return None
        if q in exps:
            exps[q] = num / den
    return tuple(exps[d] for d in DIMENSIONS)


def si_unit(exponents: tuple | None, fallback: str = "") -> str:
    """SI unit string for LMS ``quantity_terms`` exponents (``m/s^2``, ``V``, ``(m/s^2)/V``)."""
    if exponents is None:
        return fallback
    key = tuple(int(e) if float(e).is_integer() else e for e in exponents)
    if key in _NAMED:
        return _NAMED[key]
    for num, num_unit in _NAMED.items():  # a ratio of two named units (FRFs)
        for den, den_unit in _NAMED.items():
            if den_unit != "1" and tuple(a - b for a, b in zip(num, den, strict=True)) == key:
                if num_unit == "1":
                    return f"1/{den_unit}"
                return f"({num_unit})/{den_unit}" if "/" in num_unit else f"{num_unit}/{den_unit}"
    parts = [f"{_SI_BASE[d]}^{e:g}" if e != 1 else _SI_BASE[d]
             for d, e in zip(DIMENSIONS, exponents, strict=True) if e]
    return " ".join(parts) or "1"


def _load_mat(path: Path) -> dict:
    from scipy.io import loadmat

    file = str(path)
    if not path.exists():
        raise MeasurementError(file, "file not found")
    if path.is_dir():
        raise MeasurementError(file, "is a folder; expected a MAT file")
    try:
        return loadmat(file, squeeze_me=True, struct_as_record=False)
    except NotImplementedError as err:  # v7.3 (HDF5)
        raise MeasurementError(file, f"MAT v7.3 (HDF5) is not an LMS Test.Lab v5 export: "
                                     f"{err}") from None
    except Exception as err:
        raise MeasurementError(file, f"not a MAT file (scipy.io.loadmat: {err})") from None


def _is_function(v) -> bool:
    return all(hasattr(v, f) for f in ("x_values", "y_values", "function_record"))


def read_functions(path: str | Path) -> list[LMSFunction]:
    """Every channel of every function struct in one LMS MAT export, values in SI.

    Raises :class:`~sensfw.errors.MeasurementError` (naming the file and the struct or
    channel) for a missing or unreadable file, a file without LMS function structs (the
    message lists its variables), a struct without a required field (listing the fields
    it has), values that are not ``(n,)`` or ``(n, k)``, and a ``number_of_values`` that
    differs from the number of values.
    """
    path = Path(path)
    file = str(path)
    mat = _load_mat(path)
    variables = {k: v for k, v in mat.items() if not k.startswith("__")}
    structs = {k: v for k, v in variables.items() if _is_function(v)}
    if not structs:
        raise MeasurementError(file, "no LMS Test.Lab function struct (with x_values, "
                                     "y_values, function_record); variables: "
                                     f"{', '.join(variables) or '(none)'}")
    out = []
    for sname, st in structs.items():
        out.extend(_columns(file, sname, st))
    return out


def _num(v, what: str, file: str, sname: str) -> float:
    try:
        return float(_plain(v))
    except (TypeError, ValueError):
        raise MeasurementError(file, f"struct {sname!r}: {what} = {_plain(v)!r} is not a "
                                     f"number") from None


def _columns(file: str, sname: str, st) -> list[LMSFunction]:
    vals = np.asarray(_field(st, "y_values.values", file, sname))
    dx = _num(_field(st, "x_values.increment", file, sname), "x_values.increment", file, sname)
    x0 = _num(_field(st, "x_values.start_value", file, sname), "x_values.start_value", file,
              sname)
    nv = _opt(st, "x_values.number_of_values")
    if nv is not None:
        nv_f = _num(nv, "x_values.number_of_values", file, sname)
        if not (np.isfinite(nv_f) and nv_f >= 0 and nv_f.is_integer()):
            raise MeasurementError(file, f"struct {sname!r}: x_values.number_of_values = "
                                         f"{nv_f!r} is not a count")
        nv = int(nv_f)
    if vals.ndim == 1:
        vals = vals[:, None]
    if vals.ndim != 2 or vals.size == 0 or vals.dtype.kind not in "iufc":
        raise MeasurementError(file, f"struct {sname!r}: y_values.values has shape "
                                     f"{vals.shape} and type {vals.dtype}; expected numbers, "
                                     f"(n,) or (n, channels)")
    if nv is not None and nv != vals.shape[0] and nv == vals.shape[1]:
        vals = vals.T
    n, k = vals.shape
    fr = _field(st, "function_record", file, sname)
    labels = [_str(x) for x in _per_column(_opt(fr, "primary_channel.label", ""), k)]
    fnames = [_str(x) for x in _per_column(_opt(fr, "name", ""), k)]
    ids = _per_column(_opt(fr, "primary_channel.id"), k)
    kind = _str(_opt(fr, "type", "")) or "Signal"
    if nv is not None and nv != n:
        raise MeasurementError(file, f"struct {sname!r}: x_values.number_of_values = {nv} "
                                     f"but y_values.values has {n} rows: lengths differ",
                               labels[0] or None)
    if not (np.isfinite(dx) and dx > 0 and np.isfinite(1.0 / dx)):
        raise MeasurementError(file, f"x_values.increment = {dx!r} is not a positive number",
                               labels[0] or sname)
    if not np.isfinite(x0):
        raise MeasurementError(file, f"x_values.start_value = {x0!r} is not finite",
                               labels[0] or sname)
    yq = _field(st, "y_values.quantity", file, sname)
    xq = _opt(st, "x_values.quantity")
    x_unit = si_unit(_exponents(xq), _str(_opt(xq, "label", "")))
    factor = _num(_opt(yq, "unit_transformation.factor", 1.0), "unit_transformation.factor",
                  file, sname)
    offset = _num(_opt(yq, "unit_transformation.offset", 0.0), "unit_transformation.offset",
                  file, sname)
    label_unit = _str(_opt(yq, "label", ""))
    mks = "MKS" in _str(_opt(yq, "info", "")).upper()
    unit = si_unit(_exponents(yq), label_unit)
    if not mks:
        if factor == 0:
            raise MeasurementError(file, f"struct {sname!r}: unit_transformation.factor is 0")
        vals = (vals - offset) / factor
    if np.iscomplexobj(vals) and kind in ("Coherence", "Signal") and not np.any(vals.imag):
        vals = vals.real
    rec = {k2: _per_column(_opt(fr, p), k) for k2, p in (
        ("reference", "reference_channel.label"), ("reference_id", "reference_channel.id"),
        ("reference_window", "reference_channel.windows.type"),
        ("window", "energy_amplitude_transform.windows.type"),
        ("window_parameter", "energy_amplitude_transform.windows.parameter"),
        ("method", "frf.method"), ("averages", "average.nr_of_averages"),
        ("average_type", "average.type"), ("run", "TL_export_properties_annotation.run_name"))}
    out = []
    for j in range(k):
        label = labels[j] or fnames[j].split(" ", 1)[-1] or f"{sname}[{j}]"
        record = {key: _plain(v[j]) for key, v in rec.items() if v[j] is not None}
        record["function_name"] = fnames[j]
        cid = ids[j]
        out.append(LMSFunction(
            name=label, label=label, kind=kind, values=np.asarray(vals[:, j]), x0=x0, dx=dx,
            x_unit=x_unit, unit=unit, file_unit=label_unit, factor=factor, offset=offset,
            file=file, struct=sname, column=j,
            channel_id=_int_or_none(cid), record=record))
    return out


def _int_or_none(v) -> int | None:
    try:
        return int(_plain(v))
    except (TypeError, ValueError):
        return None


def _plain(v):
    if isinstance(v, np.ndarray):
        return None if v.size == 0 else _plain(v.ravel()[0])
    if isinstance(v, np.generic):
        return v.item()
    return v


def lms_struct(values, increment: float, labels: Sequence[str], unit: str = "g",
               ids: Sequence[int] | None = None, kind: str = "Signal",
               mks: bool = True, start: float = 0.0, reference: str | None = None,
               per: str = "V", run: str | None = None) -> dict:
    """A dict that :func:`scipy.io.savemat` writes as an LMS function struct (for tests and
    examples): ``values`` in SI units, ``(n,)`` or ``(n, k)``; ``unit`` is the label, one of
    g, m/s^2, m/s, m, V, N; with ``mks=False`` the values are stored in the labelled unit.
    ``kind="FRF"``: complex values per ``per`` (N or V) on lines ``start + increment k``
    Hz, H1 against the channel ``reference``; ``run`` the Test.Lab run name."""
    table = {"g": ((1, 0, 0, -2), 1 / 9.80665), "m/s^2": ((1, 0, 0, -2), 1.0),
             "m/s": ((1, 0, 0, -1), 1.0), "m": ((1, 0, 0, 0), 1.0),
             "V": ((2, 0, 1, -3, -1), 1.0), "N": ((1, 0, 1, -2), 1.0)}
    exps, factor = table[unit]
    exps = (*exps, 0, 0, 0, 0, 0)[:8]
    frf = kind.upper() == "FRF"
    label = unit
    if frf:
        den = (*table[per][0], 0, 0, 0, 0, 0)[:8]
        exps = tuple(a - b for a, b in zip(exps, den, strict=True))
        label = f"{unit}/{per}"
    vals = np.asarray(values, complex if frf else float)
    k = 1 if vals.ndim == 1 else vals.shape[1]

    def quantity(label, ex, fac):
        terms = np.empty(8, dtype=object)
        for i, d in enumerate(DIMENSIONS):
            terms[i] = {"num": float(ex[i]), "den": 1.0, "quantity": d}
        info = "Data saved by Test.Lab in MKS" if mks else "Data saved in user units"
        return {"label": label, "unit_transformation": {"offset": 0.0, "factor": fac,
                                                        "log_reference": 1.0},
                "quantity_terms": terms, "info": info}

    def col(items):
        items = list(items)
        if k == 1:
            return items[0]
        arr = np.empty(k, dtype=object)
        arr[:] = items
        return arr

    ids = list(ids) if ids is not None else list(range(1, k + 1))
    record = {"name": col(f"{'FRF' if frf else 'Time'} {lb}" + (f"/{reference}" if frf
                                                                  else "") for lb in labels),
              "type": kind,
              "primary_channel": {"id": col(float(i) for i in ids), "label": col(labels)},
              "average": {"nr_of_averages": col([1.0] * k),
                          "type": col(["LINAVERAGE"] * k)}}
    if frf:
        record["reference_channel"] = {"label": col([reference or "Shaker:-X"] * k),
                                       "id": col([99.0] * k)}
        record["frf"] = {"method": col(["H1"] * k)}
    if run is not None:
        record["TL_export_properties_annotation"] = {"run_name": col([run] * k)}
    x_exps = (0, 0, 0, -1, 0, 0, 0, 0) if frf else (0, 0, 0, 1, 0, 0, 0, 0)
    x_values = {"start_value": float(start), "increment": float(increment)}
    if not frf:
        x_values["number_of_values"] = float(vals.shape[0])
    x_values["quantity"] = quantity("Hz" if frf else "s", x_exps, 1.0)
    return {"x_values": x_values,
            "y_values": {"values": vals if mks else vals * factor,
                         "quantity": quantity(label, exps, factor)},
            "function_record": record}
