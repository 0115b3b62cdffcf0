"""Order-based scorers: THD (Eq. 12) and the amplitude of one order (Fig. 10's base
frequency and first harmonic). They analyse the sweep only, not a silent tail after it."""

from __future__ import annotations

from typing import ClassVar

from ..plugins import scorers
from ..signal import harmonic_amplitudes, thd
from .base import Scorer, ScorerError


def _f_inst(scorer, signals):
    if signals.f_inst is None:
        raise ScorerError(f"scorer {scorer.name!r} needs the sweep's instantaneous frequency "
                          "(f_inst) with the signals")
    return signals.f_inst


@scorers.register("thd")
class THD(Scorer):
    """Total harmonic distortion of the output's order spectrum (Eq. 12): percent, or dBc
    (MATLAB's convention) with ``unit="dBc"``; ``detrend`` removes the spectrum's trend
    first (Sect. 2.3)."""

    name = "thd"
    defaults: ClassVar[dict] = {"n_harmonics": None, "unit": "percent", "detrend": False}

    def validate(self):
        if self.options["unit"] not in ("percent", "dBc"):
            raise ScorerError("scorer 'thd': unit must be 'percent' or 'dBc'", option="unit")
        n = self.options["n_harmonics"]
        if n is not None and (isinstance(n, bool) or not isinstance(n, int) or n < 2):
            raise ScorerError("scorer 'thd': n_harmonics must be an integer >= 2",
                              option="n_harmonics")

    def score(self, signals, reference=None):
        o = self.options
        signals = signals.sweep()
        return {"value": thd(self.signal(signals), signals.fs, _f_inst(self, signals),
                             n_harmonics=o["n_harmonics"], unit=o["unit"],
                             detrend=bool(o["detrend"]))}


@scorers.register("order_amplitude")
class OrderAmplitude(Scorer):
    """RMS amplitude ``P_n`` of order ``order`` in the order spectrum (Eq. 16)."""

    name = "order_amplitude"
    defaults: ClassVar[dict] = {"order": 1, "detrend": False}

    def validate(self):
        n = self.options["order"]
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ScorerError(f"scorer 'order_amplitude': order must be an integer >= 1, "
                              f"got {n!r}", option="order")

    def score(self, signals, reference=None):
        n = self.options["order"]
        signals = signals.sweep()
        P = harmonic_amplitudes(self.signal(signals), signals.fs, _f_inst(self, signals),
                                harmonics=[n], detrend=bool(self.options["detrend"]))
        return {"value": P[n]}
