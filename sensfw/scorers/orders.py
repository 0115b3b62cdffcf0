"""Order-based scorers: THD (Eq. 12) and the amplitude of one order (Fig. 10's base
frequency and first harmonic). They analyse the sweep only, not a silent tail after it."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from ..options import Bool, Int, PluginOptions
from ..plugins import scorers
from ..signal import harmonic_amplitudes, thd
from .base import Scorer, ScorerError


def _top_order(scorer, excitation) -> tuple[int, float]:
    """The highest order of the excitation's order spectrum, ``fs / (2 max f_inst)``
    (:func:`~sensfw.signal.orders.harmonic_amplitudes`), checked before anything runs: an
    order scorer needs a sweep or stepped sine."""
    f = excitation.f_inst()
    if f is None:
        raise ScorerError(f"scorer {scorer.name!r} analyses orders of a sweep or stepped "
                          f"sine; the excitation is {excitation.kind}")
    fmax = float(np.max(np.asarray(f, float)[: max(1, round(excitation.sweep_end *
                                                          excitation.fs))]))
    return int(np.floor(excitation.fs / (2 * fmax) + 1e-9)), fmax


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

    def check_excitation(self, excitation) -> None:
        """Its second harmonic must lie below the Nyquist frequency at the sweep's top."""
        top, fmax = _top_order(self, excitation)
        if top < 2:
            raise ScorerError(f"scorer {self.name!r}: the second harmonic of the excitation's "
                              f"{fmax:g} Hz lies above the Nyquist frequency "
                              f"{excitation.fs / 2:g} Hz (THD needs fs >= 4 x {fmax:g} Hz)")

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

    def check_excitation(self, excitation) -> None:
        """The order must lie below the Nyquist frequency at the sweep's top."""
        top, fmax = _top_order(self, excitation)
        if self.options["order"] > top:
            raise ScorerError(f"scorer {self.name!r}: order {self.options['order']} is above "
                              f"the highest unaliased order {top} of the excitation (fs / (2 "
                              f"f_max) = {excitation.fs:g} / (2 x {fmax:g}) Hz)",
                              option="order")

    def score(self, signals, reference=None):
        n = self.options["order"]
        signals = signals.sweep()
        P = harmonic_amplitudes(self.signal(signals), signals.fs, _f_inst(self, signals),
                                harmonics=[n], detrend=bool(self.options["detrend"]))
        return {"value": P[n]}
