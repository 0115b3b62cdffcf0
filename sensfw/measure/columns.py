"""Measured columns -> a :class:`~sensfw.measure.measurement.Measurement`: units to SI (the
excitation a force or a voltage, a response in the SI unit of its dimension), the sidecar of
a file, and the checks of the time column (uniform, increasing, the declared rate). Shared
by the CSV and UFF readers (:mod:`sensfw.measure.io`, :mod:`sensfw.measure.uff`).
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np

from ..errors import MeasurementError
from ..models.base import Signals
from .measurement import Measurement

TARGET_UNITS = {"time": "s", "force": "N"}
ACCEL_UNIT = "m/s^2"
def quantity(unit: str):
    """A pint quantity of 1 ``unit`` (``g`` is standard gravity)."""
    from ..study import units

    u = unit.strip()
    if u.lower() in ("g", "gn", "g0", "g_n"):
        u = "standard_gravity"
    return units().Quantity(1.0, u)


def factor(file: str, column: str, unit: str | None, target: str) -> float:
    """Multiplier from ``unit`` to ``target``."""
    if not unit or unit == target:  # no unit, or one kept as it is (:func:`target`)
        return 1.0
    try:
        return float(quantity(unit).to(target or "dimensionless").magnitude)
    except Exception as err:
        raise MeasurementError(file, f"unit {unit!r} cannot be converted to {target}: {err}",
                               column) from None


def sidecar(path: Path) -> dict:
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


#: the SI units a response channel is converted to: the first of its dimension (a channel
#: of none, a temperature, is kept in its own unit: offset units do not scale)
SI_UNITS = ("m/s^2", "m/s", "m", "N", "N*m", "V", "A", "Pa", "rad/s^2", "rad/s", "rad")


def fits(unit: str, si: str) -> bool:
    try:
        return quantity(unit).dimensionality == quantity(si).dimensionality
    except Exception:
        return False


def target(column: str, unit: str | None = None) -> str:
    """SI unit a column is converted to: the excitation is a force or a voltage, a response
    is converted to the SI unit of its dimension (:data:`SI_UNITS`; an acceleration where
    no unit is given)."""
    if column in TARGET_UNITS and column != "force":
        return TARGET_UNITS[column]
    if column == "force":
        return "V" if unit and fits(unit, "V") else "N"
    if not unit:
        return ACCEL_UNIT
    si = next((si for si in SI_UNITS if fits(unit, si)), None)
    if si is None and unit.strip() and _dimensionless(unit):
        si = ""  # a strain, a ratio: kept as the number it is
    return si if si is not None else unit


def _dimensionless(unit: str) -> bool:
    try:
        return quantity(unit).dimensionless
    except Exception:
        return False


def _declared(file: str, name: str, value, unit: str) -> float | None:
    """A sidecar's ``fs`` or ``level``: a positive number, or a quantity with units
    (``"20 kHz"``, ``"0.1 N"``) converted to ``unit``."""
    if value is None:
        return None
    from ..study import to_unit

    try:
        x = float(value) if not isinstance(value, str) else to_unit(value, unit)
    except (TypeError, ValueError) as err:
        raise MeasurementError(file, f"the sidecar's {name} = {value!r} is not a number or a "
                                     f"quantity in {unit}: {err}", name) from None
    if not (np.isfinite(x) and x > 0):
        raise MeasurementError(file, f"the sidecar's {name} = {value!r} must be positive", name)
    return x


def assemble(file: str, columns: dict[str, np.ndarray], unit_map: dict, fs_declared,
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
    notes, rounded = [], None
    if np.max(np.abs(dt - step)) > 1e-3 * step:
        rounded = _rounded_grid(t)
        if rounded is None:
            worst = int(np.argmax(np.abs(dt - step)))
            raise MeasurementError(file, f"non-uniform sampling: step {dt[worst]:.6g} s at "
                                         f"row {worst + 2} vs {step:.6g} s elsewhere", "time")
        step = rounded[0]
    fs = 1.0 / step
    fs_declared = _declared(file, "fs", fs_declared, "Hz")
    level = _declared(file, "level", level, target("force", unit_map.get("force")))
    if fs_declared is not None and abs(fs - float(fs_declared)) > 1e-3 * float(fs_declared):
        raise MeasurementError(file, f"sample rate from the time column is {fs:.6g} Hz but the "
                                     f"sidecar declares fs = {fs_declared} Hz", "time")
    if rounded is not None:
        if fs_declared is not None:
            fs = float(fs_declared)
        notes.append(f"the time column is written to {rounded[1]:g} s ({rounded[1] / step:.2%} "
                     f"of a step): fs = {fs:.8g} Hz "
                     + ("as the sidecar declares" if fs_declared is not None else
                        "from its first and last time (declare fs in the sidecar to give it "
                        "exactly)"))
    channels = {k: v for k, v in columns.items() if k not in ("time", "force")}
    grid = np.arange(len(t)) / fs if rounded is not None else t - t[0]  # not the rounding
    sig = Signals(t=grid, force=columns["force"], channels=channels, fs=fs,
                  units={k: target(k, unit_map.get(k)) for k in ("force", *channels)})
    return Measurement(file=file, signals=sig, units=dict(unit_map),
                       level=None if level is None else float(level), notes=notes)


def _rounded_grid(t: np.ndarray) -> tuple[float, float] | None:
    """``(step, quantum)`` where the time column ``t`` is a uniform grid written to a fixed
    number of decimals (``quantum``, e.g. 1e-6 s: a 12.8 kHz record's steps then read
    7.8e-5 and 7.9e-5 s, 1.3 % apart): every time within ``quantum`` of the straight line
    through the first and last, the quantum at most a tenth of the step; else None."""
    n = len(t)
    step = float(t[-1] - t[0]) / (n - 1)
    quantum = None
    for d in range(13):  # the coarsest decimal every time is written to
        q = 10.0**-d
        if np.all(np.abs(t / q - np.round(t / q)) <= 1e-6):
            quantum = q
            break
    if quantum is None or not quantum <= 0.1 * step:
        return None
    line = t[0] + step * np.arange(n)
    return (step, quantum) if np.max(np.abs(t - line)) <= quantum else None
