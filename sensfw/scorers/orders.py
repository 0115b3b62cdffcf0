"""Order-based scorers: THD (Eq. 12) and the amplitude of one order (Fig. 10's base
frequency and first harmonic). They analyse the sweep only, not a silent tail after it."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from ..options import Bool, Int, PluginOptions
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

    class Options(PluginOptions):
        n_harmonics: Annotated[Int, Field(ge=2)] | None = Field(
            None, description="an integer >= 2 or none (every harmonic below Nyquist)")
        unit: Literal["percent", "dBc"] = Field("percent", description="'percent' or 'dBc'")
        detrend: Bool = Field(False, description="true or false")

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

    class Options(PluginOptions):
        order: Annotated[Int, Field(ge=1)] = Field(1, description="an integer >= 1")
        detrend: Bool = Field(False, description="true or false")

    def score(self, signals, reference=None):
        n = self.options["order"]
        signals = signals.sweep()
        P = harmonic_amplitudes(self.signal(signals), signals.fs, _f_inst(self, signals),
                                harmonics=[n], detrend=bool(self.options["detrend"]))
        return {"value": P[n]}
