"""Predictions with uncertainty: the calibrated model's FRF and resonance on a record as a
band that the calibration's parameter uncertainty spans, and whether the record is one the
calibration saw the like of.

The calibration's Laplace covariance (:meth:`sensfw.measure.calibration.Fit.covariance`,
coded) defines an ellipsoid that holds the parameters with probability ``level``
(``(z - z0)^T C^-1 (z - z0) <= chi2_d(level)``). The model is simulated at the ``2 d``
points where that ellipsoid meets its principal axes (the sigma points of an unscented
transform at the ellipsoid's radius; Julier & Uhlmann 2004), clipped to the box, and the
band is the envelope of those runs and the calibrated one: on each frequency line the
lowest and highest model FRF (dB), and the lowest and highest resonance. A record whose
measured resonance lies outside the resonance band is not predicted within the
calibration's uncertainty: the model form is missing something, or the calibration is too
confident. ``2 d`` runs per record, whatever the model's cost (no surrogate is needed for
so few).

The parameters' uncertainty is not the model's: a model form that misses something misfits
even the records it was fitted to. Where the calibration stored its misfit on each record it
fitted (:func:`fitted_records`: the resonance shift, model minus measured, and the FRF
error), the band is widened on both sides by ``FORM_Z`` times the RMS of those misfits (of
the records of the same kind when the calibration fitted two or more, else of all): the
residual term of a regression's prediction interval (e.g. Montgomery, *Design and Analysis of
Experiments*, Sect. 10.6), with the fitted records' misfit as the residual (it tends to be
smaller than the misfit on records not fitted, so the term is a lower bound of the model
form's error). The report states both parts.

A record is an **extrapolation** when its kind of excitation is none the calibration saw,
or its level lies outside the levels of that kind the calibration saw (beyond 10 %).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2 as chi2_dist

from .calibration import Axis, Coordinates

#: two-sided 95 % normal quantile: the model-form term's multiple of the fitted misfit's RMS
FORM_Z = 1.96


@dataclass
class CalibrationResult:
    """A calibrated study's ``[calibration.result]`` with its axes rebuilt."""

    coords: Coordinates
    z: np.ndarray
    covariance: np.ndarray
    records: list[dict]


def calibration_result(study) -> CalibrationResult | None:
    """The calibration a study was written from (``[calibration.result]``: the axes with
    the study's bounds and the stored coding), or None."""
    cal = study.spec.calibration
    if cal is None or cal.result is None:
        return None
    r = cal.result
    space = study.calibration_space(list(r.parameters))
    axes = [Axis(v.name, float(v.low), float(v.high), float(v.nominal), v.unit, scale)
            for v, scale in zip(space.variables, r.scales, strict=True)]
    return CalibrationResult(Coordinates(axes), np.asarray(r.coded, float),
                             np.asarray(r.covariance, float), [dict(x) for x in r.records])


def ellipsoid_points(coords: Coordinates, z: np.ndarray, cov: np.ndarray,
                     level: float = 0.95) -> list[dict[str, float]]:
    """The ``2 d`` points (physical values) where the ``level`` ellipsoid of the coded
    covariance ``cov`` about ``z`` meets its principal axes, clipped to the box."""
    d = len(z)
    r = float(np.sqrt(chi2_dist.ppf(level, d)))
    vals, vecs = np.linalg.eigh(np.asarray(cov, float))
    out = []
    for i in range(d):
        step = r * np.sqrt(max(vals[i], 0.0)) * vecs[:, i]
        for s in (-1.0, 1.0):
            out.append(coords.decode(np.clip(z + s * step, -1.0, 1.0)))
    return out


def extrapolation(kind: str, level: float, seen: Sequence[Mapping]) -> str | None:
    """Why a record of ``kind`` at ``level`` is an extrapolation of a calibration that saw
    the records ``seen`` (``[{"kind", "level"}, ...]``), or None."""
    same = [float(r["level"]) for r in seen if r.get("kind") == kind]
    if not seen:
        return None
    if not same:
        return f"a {kind.replace('_', ' ')} record: the calibration saw none"
    lo, hi = min(same), max(same)
    if level < lo / 1.1 or level > hi * 1.1:
        return (f"level {level:.3g} outside the {kind.replace('_', ' ')} levels the "
                f"calibration saw ({lo:.3g}-{hi:.3g})")
    return None


@dataclass
class Band:
    """The prediction band of one record (see the module docstring)."""

    file: str
    kind: str
    level: float
    f: np.ndarray
    db_low: np.ndarray
    db_high: np.ndarray
    resonance_low: float | None
    resonance_high: float | None
    resonance_measured: float | None
    extrapolation: str | None = None
    #: RMS of the fitted records' resonance shift (Hz) and FRF error (dB) the band was
    #: widened by (times ``FORM_Z``), and how many fitted records they come from
    form_hz: float = 0.0
    form_db: float = 0.0
    form_records: int = 0

    @property
    def contains_resonance(self) -> bool | None:
        """Whether the measured resonance lies in the band (None: no resonance)."""
        if None in (self.resonance_low, self.resonance_high, self.resonance_measured):
            return None
        return self.resonance_low <= self.resonance_measured <= self.resonance_high

    @property
    def resonance_width_hz(self) -> float | None:
        if self.resonance_low is None or self.resonance_high is None:
            return None
        return self.resonance_high - self.resonance_low

    @property
    def width_db_at_resonance(self) -> float | None:
        """The band's width (dB) on the line nearest the measured resonance."""
        if self.resonance_measured is None or not len(self.f):
            return None
        i = int(np.argmin(np.abs(self.f - self.resonance_measured)))
        return float(self.db_high[i] - self.db_low[i])

    def to_dict(self) -> dict:
        return {"file": self.file, "kind": self.kind, "level": self.level,
                "resonance_band_hz": [self.resonance_low, self.resonance_high],
                "resonance_measured_hz": self.resonance_measured,
                "contains_resonance": self.contains_resonance,
                "resonance_width_hz": self.resonance_width_hz,
                "width_db_at_resonance": self.width_db_at_resonance,
                "model_form_hz": self.form_hz, "model_form_db": self.form_db,
                "model_form_records": self.form_records, "model_form_z": FORM_Z,
                "extrapolation": self.extrapolation}


def main_resonance(resonances: Sequence[Mapping], band: tuple[float, float] | None
                   ) -> tuple[float | None, float | None]:
    """(measured, model) frequency of the matched resonance nearest the middle of ``band``
    (the error band), or of the first matched one."""
    rows = [r for r in resonances if r.get("measured_hz") and r.get("model_hz")]
    if band is not None:
        rows = [r for r in rows if band[0] <= r["measured_hz"] <= band[1]] or rows
    if not rows:
        return None, None
    mid = np.sqrt(band[0] * band[1]) if band is not None else rows[0]["measured_hz"]
    r = min(rows, key=lambda r: abs(np.log(r["measured_hz"] / mid)))
    return r["measured_hz"], r["model_hz"]


def fitted_records(records: Sequence[Mapping], comparisons: Sequence | None
                   ) -> list[dict]:
    """``records`` (file, kind, level of each fitted record) with the calibrated model's
    misfit on each, from its comparison: ``resonance_shift_hz`` (model minus measured
    resonance, :func:`main_resonance`; None without one) and ``error_db``."""
    out = []
    for r, c in zip(records, comparisons or [None] * len(records), strict=True):
        if c is None:
            out.append(dict(r))
            continue
        meas, model = main_resonance(c.resonances, c.error_band)
        out.append({**r, "resonance_shift_hz": None if meas is None or model is None
                    else float(model - meas), "error_db": float(c.error_db)})
    return out


def model_form(seen: Sequence[Mapping], kind: str) -> tuple[float, float, int]:
    """RMS of the fitted records' resonance shifts (Hz) and FRF errors (dB), of those of
    ``kind`` where the calibration fitted two or more, else of all; and how many records.
    Zeros where the calibration stored no misfits (a study written before it did)."""
    def rms(rows, key):
        x = [float(r[key]) for r in rows if r.get(key) is not None]
        return (float(np.sqrt(np.mean(np.square(x)))), len(x)) if x else (0.0, 0)

    same = [r for r in seen if r.get("kind") == kind]
    rows = same if sum(r.get("resonance_shift_hz") is not None for r in same) >= 2 else seen
    hz, n = rms(rows, "resonance_shift_hz")
    db, _ = rms(rows, "error_db")
    return hz, db, n


def bands(levels: Sequence, samples: Sequence[Sequence], seen: Sequence[Mapping],
          kinds: Sequence[str]) -> list[Band]:
    """The band of each record from its comparison with the calibrated model (``levels``)
    and with the model at each ellipsoid point (``samples[j][i]``: point ``j``, record
    ``i``; :class:`~sensfw.measure.comparison.LevelComparison`), widened by the model-form
    term of the records the calibration fitted (``seen``; module docstring)."""
    out = []
    for i, c in enumerate(levels):
        runs = [c] + [s[i] for s in samples if s[i] is not None]
        form_hz, form_db, n_form = model_form(seen, kinds[i])
        lo = np.min([r.db_model for r in runs], axis=0) - FORM_Z * form_db
        hi = np.max([r.db_model for r in runs], axis=0) + FORM_Z * form_db
        meas, _ = main_resonance(c.resonances, c.error_band)
        models = [main_resonance(r.resonances, c.error_band)[1] for r in runs]
        models = [m for m in models if m is not None]
        out.append(Band(file=c.file, kind=kinds[i], level=c.level, f=c.f, db_low=lo,
                        db_high=hi,
                        resonance_low=min(models) - FORM_Z * form_hz if models else None,
                        resonance_high=max(models) + FORM_Z * form_hz if models else None,
                        resonance_measured=meas,
                        extrapolation=extrapolation(kinds[i], c.level, seen),
                        form_hz=form_hz, form_db=form_db, form_records=n_form))
    return out
