"""The discrepancy between a model and the measurements as a weighted residual vector.

For every measured level (a :class:`~sensfw.measure.compare.LevelComparison`) the entries
are the dB differences model - measurement of the FRF in the one-third-octave bands the
measurement can speak for (its ``used_bands``: within the dynamic range and above its own
noise) and of the THD. Each entry is divided by its standard error, so that a correct model
leaves residuals of unit variance:

* a band's standard error (``noise_db`` of the first comparison) combined with
  ``MODEL_DB``, a floor for what no parameter of a good model can fix (the drive's
  interpolation, the band estimator). Two noise models (a study's ``[calibration]
  noise``, :data:`~sensfw.measure.compare.NOISE_MODELS`): ``"scatter"`` (the default), the
  measurement's own random scatter about a local fit
  (:func:`~sensfw.measure.bands.band_noise`) less that of the nominal model's record,
  which shares its nonlinear distortion, floored at a quarter; ``"propagated"``, what the
  record's white noise on its output and on its excitation does to the band's H1
  (:func:`~sensfw.measure.bands.band_white_noise`, from the measurement only);
* the THD's is ``THD_DB`` (harmonic amplitudes of a short sweep scatter by about 1 dB with
  2 % noise). The measured THD holds the record's noise too (noise adds in power); with
  ``"propagated"`` the model's THD is compared combined in power with the record's noise
  floor (:attr:`~sensfw.measure.comparison.LevelComparison.thd_floor`). Without it a
  correct, nearly linear model's THD entry is -5 to -11 dB at a low level and worse at
  higher noise, and an effect that adds distortion is credited with the noise's
  (``bench/whitening.py``; under ``"scatter"`` :func:`noise_thd_note` says where that
  bias carries most of chi2). At 5-10 % noise the scatter model leaves the truth above the
  noise test's bound in 14 of 20 random cases and diagnosis names an effect in 3 of 8
  cases without one; the propagated model, in none (``bench/RECOVERY.md``, stop 61). Its
  noise estimates read 1.1-1.2 times the truth since stop 63 (the output's read 1.6 times,
  up to 5, before: ``bench/noise_estimates.py``); what its errors still hold beyond the
  noise at 1-5 % is ``MODEL_DB`` on the strong bands and ``THD_DB`` (median chi2/n 0.49
  at the truth over the 40 tuned cases). It is not the default: diagnosis's stopping
  rules were set on the scatter model's weights, and on the tuned seeds it names fewer
  truths (``bench/RECOVERY.md``, stops 62-63).

The entries depend on the measurement only, so every hypothesis is scored on the same
vector. Then ``chi2 = sum w^2`` is chi-square distributed with ``n - k`` degrees of freedom
for a correct model with ``k`` calibrated parameters (the goodness-of-fit test of
:func:`fits`), and ``BIC = chi2 + k ln n`` (Schwarz 1978, known variances) ranks
hypotheses.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import chi2 as chi2_dist

#: standard error floor (dB) of a band entry: model-form tolerance
MODEL_DB = 0.1
#: standard error (dB) of the THD entry
THD_DB = 1.5
#: the entry of a band where the model has no finite response
MISSING_DB = 40.0


@dataclass(frozen=True)
class Entries:
    """Which bands (by centre frequency) of which comparison enter the residual vector, and
    the standard error of each entry (fixed once, from the first comparisons, so that every
    hypothesis is scored with the same weights)."""

    bands: tuple[tuple[float, ...], ...]  # per comparison, the centre frequencies used
    thd: tuple[bool, ...]  # per comparison, whether the THD enters
    sigma: tuple[tuple[float, ...], ...] = ()  # per comparison, the entries' standard errors
    #: the noise model the comparisons' band errors came from
    #: (:data:`sensfw.measure.compare.NOISE_MODELS`); ``"propagated"`` also reads the
    #: model's THD against the record's noise floor
    noise: str = "scatter"

    @classmethod
    def of(cls, comparisons, noise: str = "scatter") -> Entries:
        sigma = []
        for c in comparisons:
            s = [math.hypot(b.get("noise_db") or 0.0, MODEL_DB) for b in c.used_bands]
            sigma.append(tuple(s + ([THD_DB] if c.thd_measured else [])))
        return cls(bands=tuple(tuple(b["centre_hz"] for b in c.used_bands)
                               for c in comparisons),
                   thd=tuple(bool(c.thd_measured) for c in comparisons), sigma=tuple(sigma),
                   noise=noise)

    def select(self, keep) -> Entries:
        """The entries of the comparisons at the indices ``keep``."""
        return replace(
            self, bands=tuple(self.bands[i] for i in keep), thd=tuple(self.thd[i] for i in keep),
            sigma=tuple(self.sigma[i] for i in keep) if self.sigma else ())

    def size(self) -> int:
        return sum(len(b) for b in self.bands) + sum(self.thd)

    def level_slices(self) -> list[slice]:
        out, i = [], 0
        for b, t in zip(self.bands, self.thd, strict=True):
            n = len(b) + int(t)
            out.append(slice(i, i + n))
            i += n
        return out


def residuals(comparisons: Sequence, entries: Entries) -> tuple[np.ndarray, np.ndarray]:
    """(dB differences, standard errors) over ``entries`` (see the module docstring). A
    model without harmonics where the measurement has some (THD 0) gets a large but finite
    entry."""
    r = []
    for c, centres, thd in zip(comparisons, entries.bands, entries.thd, strict=True):
        by = {b["centre_hz"]: b for b in c.bands}
        for centre in centres:
            b = by.get(centre)  # None: the model has no response there, a gross misfit
            r.append(MISSING_DB if b is None else b["mean_db"])
        if thd:
            model = max(c.thd_model or 0.0, 1e-3)
            if entries.noise == "propagated":
                # the rig's THD holds its own noise (added in power): so does the model's
                model = math.hypot(model, c.thd_floor or 0.0)
            r.append(20 * math.log10(model / c.thd_measured))
    s = [x for part in entries.sigma for x in part]
    return np.array(r, float), np.array(s, float)


def noise_thd_note(comparisons: Sequence, entries: Entries, w: np.ndarray,
                   channels: Sequence[str] = ()) -> str | None:
    """A line saying how much of ``chi2 = |w|^2`` the THD entries carry where the measured
    THD is no more than its record's own noise reads (``thd_floor``): there the entry
    compares the model's distortion with noise, and a model that is right but nearly
    linear is charged tens of dB for it (the module docstring's known bias). None where
    such entries carry under half of chi2, and under the propagated noise model, whose THD
    entry reads the model against the noise floor (no bias to name). ``channels``: the
    channels of each level, in the comparisons' order (levels outer), to name them."""
    if entries.noise == "propagated":
        return None
    total = float(w @ w)
    i, share, where = 0, 0.0, []
    for k, (c, centres, thd) in enumerate(zip(comparisons, entries.bands, entries.thd,
                                              strict=True)):
        i += len(centres)
        if thd:
            floor = getattr(c, "thd_floor", None)
            if floor and c.thd_measured is not None and c.thd_measured <= floor:
                share += float(w[i] ** 2)
                ch = f"{channels[k % len(channels)]} " if channels else ""
                where.append(f"{ch}at {c.level:g} ({c.thd_measured:.3g} % against "
                             f"{floor:.3g} %)")
            i += 1
    if not total > 0 or share < 0.5 * total:
        return None
    return (f"{share:.4g} of chi2 {total:.4g} comes from THD entries whose measured THD is "
            f"no more than the record's own noise reads ({'; '.join(where[:4])}"
            + (f"; {len(where) - 4} more" if len(where) > 4 else "") + "): there the "
            "measurement shows no distortion to fit, and a nearly linear model is charged "
            "for the noise's; judge the fit by the band entries and compare's FRF error")


def weighted(comparisons: Sequence, entries: Entries) -> np.ndarray:
    r, s = residuals(comparisons, entries)
    return r / s


def chi2(w: np.ndarray) -> float:
    return float(np.sum(np.square(w)))


def bic(w: np.ndarray, k: int) -> float:
    """Schwarz's criterion with known variances: ``chi2 + k ln n``."""
    return chi2(w) + k * math.log(len(w))


def fits(w: np.ndarray, k: int, alpha: float = 1e-3) -> bool:
    """Whether the residuals are what the measurement noise alone explains (chi-square test
    at level ``alpha`` with ``n - k`` degrees of freedom)."""
    dof = max(len(w) - k, 1)
    return chi2(w) <= float(chi2_dist.ppf(1 - alpha, dof))


#: what :func:`rms_db` is, where a report or the CLI prints it: not ``compare``'s FRF
#: error of one channel (:data:`~sensfw.measure.comparison.ERROR_DEFINITION`)
RESIDUAL_ERROR = ("residual error: the RMS of the dB differences model - measurement over "
                  "every entry the calibration weighs (the FRF's fractional-octave band "
                  "levels and the THD, on every channel the model and the records share); "
                  "compare's FRF error is that of the output channel's lines alone")


def rms_db(comparisons: Sequence, entries: Entries) -> float:
    """RMS of the dB differences (unweighted): the error a user reads
    (:data:`RESIDUAL_ERROR`)."""
    r, _ = residuals(comparisons, entries)
    return float(np.sqrt(np.mean(r * r))) if len(r) else 0.0
