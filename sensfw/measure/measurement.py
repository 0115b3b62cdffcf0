"""What a measurement is: the records of one file (or one folder of files) at one level.

The readers (:mod:`sensfw.measure.io`, :mod:`sensfw.measure.lms`) build it; the checks
(:mod:`sensfw.measure.checks`) add the estimated excitation and the model's drive.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ..models.base import Signals


@dataclass
class Measurement:
    """Signals read from one file (or one folder of files), with where they came from.

    ``signals.force`` holds the excitation; ``signals.units["force"]`` says what it is: N
    for a force, V for an amplifier voltage (a model is then driven through the gain
    parameter ``excitation_gain``, N/V); :attr:`excitation` names it. ``level`` is the
    excitation amplitude in that unit if known; ``units`` the units as the file labels them.

    After :func:`sensfw.measure.checks.prepare`: ``sweep`` is the estimated excitation
    (:class:`~sensfw.signal.sweep.SweepEstimate`) and ``drive`` the excitation that drives the
    model for this measurement (the study's ideal sweep at the measured level, or the
    measured record itself).
    """

    file: str
    signals: Signals
    units: dict[str, str] = field(default_factory=dict)
    level: float | None = None  # excitation amplitude (N, or V for a voltage) if known
    notes: list[str] = field(default_factory=list)
    sweep: Any = None
    drive: Any = None

    @property
    def fs(self) -> float:
        return self.signals.fs

    @property
    def input_unit(self) -> str:
        """Unit of the excitation channel: N for a force, V for an amplifier voltage."""
        return self.signals.units.get("force", "N")

    @property
    def excitation(self) -> str:
        """``"voltage"`` when the excitation channel is an amplifier voltage, else
        ``"force"``."""
        return "voltage" if self.input_unit == "V" else "force"
