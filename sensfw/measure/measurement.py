"""What a measurement is: the records of one file (or one folder of files) at one level.

Time signals (:class:`~sensfw.models.base.Signals`: the excitation and the responses), or,
where a rig exports nothing else, FRFs per channel on frequency lines (:class:`FRFRecord`:
an LMS ``FRF.mat`` alone, UFF58 FRF records, every stepped-sine test). The readers
(:mod:`sensfw.measure.io`, :mod:`sensfw.measure.lms`) build it; the checks
(:mod:`sensfw.measure.checks`) add the estimated excitation and the model's drive.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import MeasurementError
from ..models.base import Signals

#: how an FRF was measured, where the file says so
FRF_KINDS = ("stepped_sine", "sweep", "random")


@dataclass
class FRFRecord:
    """FRFs per channel on frequency lines, without time data.

    ``f`` (Hz, increasing); ``channels[name]`` the complex FRF, output per input in SI
    units (``units[name]`` per ``units["force"]``: N for a force, V for an amplifier
    voltage); ``coherence[name]`` where the file has it (with ``averages``, the standard
    error of each line). ``kind`` says how it was measured where known (one of
    :data:`FRF_KINDS`), ``direction`` (``"up"``, ``"down"``) the order its lines were
    driven in (a stepped sine's or a sweep's), ``estimator`` the FRF estimator (H1 ...).
    The attribute names follow :class:`~sensfw.models.base.Signals` (``channels``,
    ``units``, ``meta``), so code that lists a measurement's channels reads either.
    """

    f: np.ndarray
    channels: dict[str, np.ndarray]
    units: dict[str, str]
    coherence: dict[str, np.ndarray] = field(default_factory=dict)
    kind: str | None = None
    direction: str | None = None
    averages: int | None = None
    estimator: str | None = None
    meta: dict = field(default_factory=dict)

    @classmethod
    def checked(cls, file: str, f, channels: dict, units: dict, **kw) -> FRFRecord:
        """An FRF record whose lines are checked (finite, distinct, positive frequencies;
        finite values; one value per line), sorted by frequency (the order they were
        driven in is ``direction``). Errors name the file and the channel."""
        f = np.asarray(f, float)
        if f.ndim != 1 or len(f) < 2:
            raise MeasurementError(file, "an FRF needs two frequency lines or more")
        if not np.all(np.isfinite(f)) or np.any(f < 0) or len(np.unique(f)) != len(f):
            raise MeasurementError(file, "frequency lines must be finite, non-negative and "
                                         "distinct")
        order = np.argsort(f)
        if kw.get("kind") not in (None, *FRF_KINDS):
            raise MeasurementError(file, f"FRF kind {kw['kind']!r}: one of "
                                         f"{', '.join(FRF_KINDS)}")
        if kw.get("direction") not in (None, "up", "down"):
            raise MeasurementError(file, f"direction {kw['direction']!r}: 'up' or 'down'")
        if not channels:
            raise MeasurementError(file, "no FRF channel")
        out = {}
        for name, h in channels.items():
            h = np.asarray(h, complex)
            if h.shape != f.shape:
                raise MeasurementError(file, f"{h.size} values for {f.size} frequency lines",
                                       name)
            bad = ~np.isfinite(h)
            if bad.any():
                raise MeasurementError(file, f"{int(bad.sum())} NaN/inf value(s), first at "
                                             f"{f[int(np.argmax(bad))]:g} Hz", name)
            out[name] = h[order]
        coh = {k: np.asarray(v, float)[order] for k, v in kw.pop("coherence", {}).items()}
        return cls(f=f[order], channels=out, units=dict(units), coherence=coh, **kw)

    def channel(self, name: str) -> np.ndarray:
        try:
            return self.channels[name]
        except KeyError:
            raise MeasurementError("(FRF record)", f"no channel {name!r}; the record holds "
                                                   f"{', '.join(self.channels)}", name) \
                from None

    def lines_in(self, lo: float, hi: float) -> np.ndarray:
        """The frequency lines in ``[lo, hi]``."""
        return self.f[(self.f >= lo) & (self.f <= hi)]



@dataclass
class Measurement:
    """Signals read from one file (or one folder of files), with where they came from.

    ``signals.force`` holds the excitation; ``signals.units["force"]`` says what it is: N
    for a force, V for an amplifier voltage (a model is then driven through the gain
    parameter ``excitation_gain``, N/V); :attr:`excitation` names it. ``level`` is the
    excitation amplitude in that unit if known; ``units`` the units as the file labels them.

    After :func:`sensfw.measure.checks.prepare`: ``sweep`` is the estimated excitation
    (:class:`~sensfw.signal.sweep.SweepEstimate`) and ``drive`` the excitation that drives the
    model for this measurement (the study's ideal sweep at the measured level, the
    measured record itself, or a stepped sine on an FRF record's lines).

    An FRF-only measurement holds an :class:`FRFRecord` in ``signals`` (``frf`` says so):
    FRFs per channel on frequency lines, no time data; ``level`` is then the sine
    amplitude the FRFs were measured at.
    """

    file: str
    signals: Signals | FRFRecord
    units: dict[str, str] = field(default_factory=dict)
    level: float | None = None  # excitation amplitude (N, or V for a voltage) if known
    notes: list[str] = field(default_factory=list)
    #: what the user must see before trusting a comparison (a declared level the record
    #: contradicts, a record that is not the study's sweep): every command prints these
    warnings: list[str] = field(default_factory=list)
    sweep: Any = None
    drive: Any = None

    @property
    def kind(self) -> str:
        """What kind of record this is: ``"log_chirp"``, ``"linear_sweep"``,
        ``"stepped_sine"``, ``"random"`` (time data, from the estimated excitation; before
        :func:`~sensfw.measure.checks.prepare` every time record is ``"random"``) or
        ``"frf"`` (FRFs alone)."""
        if isinstance(self.signals, FRFRecord):
            return "frf"
        kind = getattr(self.sweep, "kind", None)
        return kind if kind in ("log_chirp", "linear_sweep", "stepped_sine") else "random"

    @property
    def frf(self) -> FRFRecord | None:
        """The FRFs of an FRF-only measurement (None for time data)."""
        return self.signals if isinstance(self.signals, FRFRecord) else None

    @property
    def fs(self) -> float | None:
        """Sample rate of time data (None for an FRF-only measurement)."""
        return None if self.frf is not None else self.signals.fs

    @property
    def input_unit(self) -> str:
        """Unit of the excitation channel: N for a force, V for an amplifier voltage."""
        return self.signals.units.get("force", "N")

    @property
    def excitation(self) -> str:
        """``"voltage"`` when the excitation channel is an amplifier voltage, else
        ``"force"``."""
        return "voltage" if self.input_unit == "V" else "force"
