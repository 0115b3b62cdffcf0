"""FRF-based scorers: the paper's scalar (Eq. 11, Sect. 3.1) and a robust dB-RMS variant."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, Field

from ..models.base import Signals
from ..options import Float, Int, PluginOptions, choices
from ..plugins import scorers
from ..signal import ESTIMATORS, frf
from .base import Scorer, ScorerError


def _band(band: tuple[float, float]) -> tuple[float, float]:
    if not 0 <= band[0] < band[1] < float("inf"):
        raise ValueError("not 0 <= fmin < fmax")
    return band


class _FRFScorer(Scorer):
    needs_reference = True

    class Options(PluginOptions):
        band: Annotated[tuple[Float, Float], AfterValidator(_band)] = Field(
            (50.0, 5000.0), description="[fmin, fmax] in Hz with 0 <= fmin < fmax")
        estimator: Literal[ESTIMATORS] = Field(
            "Hv", description=choices(ESTIMATORS))
        eps: Annotated[Float, Field(gt=0, allow_inf_nan=False)] = Field(
            1.0, description="a finite number > 0")
        nperseg: Annotated[Int, Field(ge=8)] | None = Field(
            None, description="none or an integer >= 8")
        db_ref: Annotated[Float, Field(gt=0)] = Field(1.0, description="a number > 0")

    def check_excitation(self, excitation) -> None:
        """A band the study sets must lie below the Nyquist frequency and inside the
        excitation's sweep f0..f1 (outside it the FRF is the ratio of noise to nothing). The
        default band (the paper's 50 Hz..5 kHz) is cut to the record's frequencies. Welch's
        ``nperseg`` must fit in the record, and the band must hold a line of the FRF (its
        resolution is fs / nperseg, or 1 / the record's length)."""
        n = excitation.n_samples
        nperseg = self.options["nperseg"]
        if nperseg is not None and nperseg > n:
            raise ScorerError(f"scorer {self.name!r}: nperseg {nperseg} is longer than the "
                              f"record ({n} samples: {n / excitation.fs:g} s at "
                              f"{excitation.fs:g} Hz)", option="nperseg")
        lo, hi = (float(b) for b in self.options["band"])
        df = excitation.fs / (nperseg or n)
        top = min(hi, excitation.fs / 2)
        if np.ceil(lo / df - 1e-9) * df > top + 1e-9 * df:
            raise ScorerError(f"scorer {self.name!r}: band [{lo:g}, {hi:g}] Hz holds no line "
                              f"of the FRF, whose lines are {df:.4g} Hz apart (fs / "
                              f"{nperseg or n} samples)", option="band")
        if "band" not in self.given:
            return
        nyquist = excitation.fs / 2
        if hi > nyquist:
            raise ScorerError(f"scorer {self.name!r}: band [{lo:g}, {hi:g}] Hz reaches above "
                              f"the Nyquist frequency {nyquist:g} Hz (fs = {excitation.fs:g} "
                              "Hz)", option="band")
        f0, f1 = sorted((excitation.f0, excitation.f1))
        tol = 1e-9 * f1
        if lo < f0 - tol or hi > f1 + tol:
            raise ScorerError(f"scorer {self.name!r}: band [{lo:g}, {hi:g}] Hz is not inside "
                              f"the excitation's sweep f0..f1 = [{f0:g}, {f1:g}] Hz",
                              option="band")

    def db(self, signals: Signals) -> tuple[np.ndarray, np.ndarray]:
        """FRF magnitude in dB re ``db_ref`` over the band, and the frequencies."""
        o = self.options
        x = self.signal(signals)
        for what, v in (("the force", signals.force),
                        (f"channel {self.channel_name(signals)!r}", x)):
            if len(v) and not np.any(v):
                raise ScorerError(f"scorer {self.name!r}: {what} is zero throughout: its FRF "
                                  "has no magnitude in dB")
        f, H = frf(signals.force, x, signals.fs, estimator=o["estimator"],
                   eps=float(o["eps"]), nperseg=o["nperseg"], fmin=float(o["band"][0]),
                   fmax=float(o["band"][1]))
        if len(f) == 0:
            raise ScorerError(f"scorer {self.name!r}: band [{o['band'][0]:g}, "
                              f"{o['band'][1]:g}] Hz holds no line of the FRF (fs = "
                              f"{signals.fs:g} Hz, {len(signals.force)} samples)",
                              option="band")
        mag = np.abs(H)
        if not np.all(np.isfinite(mag)) or np.any(mag == 0):
            raise ScorerError(f"scorer {self.name!r}: the FRF is zero or undefined in the band "
                              "(no excitation there?)")
        return f, 20 * np.log10(mag / float(o["db_ref"]))

    def pair(self, signals: Signals, reference: Signals | None):
        if reference is None:
            raise ScorerError(f"scorer {self.name!r} compares with a reference run; none given")
        f, y = self.db(signals)
        f0, y0 = self.db(reference)
        if len(f) != len(f0) or not np.allclose(f, f0):
            raise ScorerError(f"scorer {self.name!r}: run and reference have different "
                              "frequency axes (record length or sample rate differ)")
        return y, y0


@scorers.register("frf_scalar")
class FRFScalar(_FRFScorer):
    """The paper's FRF scalar (Eq. 11, Sect. 3.1).

    ``y_i = <dB|H_i|, dB|H_0|>`` is the dot product of the run's and the reference's FRF
    magnitudes in dB over the band; the score is the run's relative change against the
    reference's own product, ``(y_i - y_0) / y_0`` with ``y_0 = <dB|H_0|, dB|H_0|>`` (zero for
    the reference itself). Caveat: the dot product of dB values depends on the dB reference
    level (``db_ref``): a level near the FRF's magnitude makes dB values small and the scalar
    erratic, and any change of ``db_ref`` changes the scores. ``frf_db_rms`` does not have
    this dependence.
    """

    name = "frf_scalar"

    def score(self, signals, reference=None):
        y, y0 = self.pair(signals, reference)
        ref = float(y0 @ y0)
        return {"value": float((y @ y0 - ref) / ref)}


@scorers.register("frf_db_rms")
class FRFdBRMS(_FRFScorer):
    """Robust variant: RMS over the band of ``dB|H_i| - dB|H_0|`` (dB). Independent of the dB
    reference level, symmetric in run and reference, zero only when the magnitudes agree."""

    name = "frf_db_rms"

    def score(self, signals, reference=None):
        y, y0 = self.pair(signals, reference)
        return {"value": float(np.sqrt(np.mean((y - y0) ** 2)))}
