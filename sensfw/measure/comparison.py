"""What a comparison of the model with a measured record holds: :class:`LevelComparison`
(one record, one channel) and :class:`Comparison` (every record of a ``compare``), with the
one FRF error figure a record gets (:data:`ERROR_DEFINITION`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: the FRF error of a record, as every report and ``compare.json`` define it
ERROR_DEFINITION = (
    "FRF error: the RMS of the dB difference 20 log10 |H_model / H_measured| over the "
    "frequency lines of the error band that the measurement can speak for (its bands within "
    "35 dB of the strongest, their own noise below 1.5 dB and their scatter below 3 dB), on "
    "the Hv FRFs smoothed to 1/24 octave for swept and random records and on the "
    "steady-state lines for stepped-sine and FRF-only records")


def display_unit(u: str) -> str:
    """``m/s^2`` -> ``m/s²``."""
    return u.replace("^2", "²")


def amount(x: float, unit: str) -> str:
    """``0.00313, "V"`` -> ``"3.13 mV"``: three digits, milli below 0.1."""
    if unit in ("V", "N") and 0 < abs(x) < 0.1:
        return f"{1e3 * x:.3g} m{unit}"
    return f"{x:.3g} {unit}"


#: what the report calls each excitation kind
KIND_NAMES = {"log_chirp": "log sweep", "linear_sweep": "linear sweep", "sweep": "sweep",
              "random": "random", "stepped_sine": "stepped sine", "frf": "FRF record"}


@dataclass
class LevelComparison:
    """Model against measurement at one excitation level, on one channel.

    ``f``, ``db_model``, ``db_measured``: the compared FRFs (dB) on their lines: the
    1/24-octave smoothed Hv FRF of swept and random records, the steady-state lines of
    stepped-sine and FRF-only records. ``kind`` is the record's excitation (``log_chirp``,
    ``linear_sweep``, ``random``, ``stepped_sine``, or ``frf`` for FRFs of an unstated
    excitation), ``direction`` a stepped sine's or sweep's (``up``/``down``), ``level_rms``
    the RMS of the measured excitation in the compared band (time records), ``error_band``
    the band of :attr:`error_db`, the record's one error figure (:data:`ERROR_DEFINITION`).
    """

    level: float
    file: str
    f: np.ndarray
    db_model: np.ndarray
    db_measured: np.ndarray
    bands: list[dict]
    resonances: list[dict]
    harmonics: list[dict]
    thd_model: float | None
    thd_measured: float | None
    #: the THD (%) the measurement's own noise reads (:func:`~.distortion.thd_floor`)
    thd_floor: float | None = None
    notes: list[str] = field(default_factory=list)
    unit: str = "N"  # of the excitation channel (the FRF's denominator)
    output_unit: str = "m/s²"  # of the compared channel (the FRF's numerator)
    dc_model: float = 0.0
    dc_measured: float = 0.0
    dc_standard_error: float = 0.0  # of dc_measured, from the record's noise
    peaks_model: list[dict] = field(default_factory=list)
    peaks_measured: list[dict] = field(default_factory=list)
    kind: str = ""
    #: how an FRF record says it was measured (``sweep``, ``random``; FRF records only)
    measured_by: str | None = None
    direction: str | None = None
    level_rms: float | None = None
    band: tuple[float, float] | None = None  # compared (the study's band)
    error_band: tuple[float, float] | None = None
    #: largest |difference| (dB) between the two halves of a stepped line's fitted periods
    #: (model, measured): a step that had not settled (stepped-sine records only)
    settled_db: dict = field(default_factory=dict)
    #: per line of ``f``: the dB error the measurement's own noise gives a correct model
    #: (:func:`sensfw.measure.bands.line_noise_db`), where known
    line_noise: np.ndarray | None = None
    #: the model's twin runs (its drive scaled by ``1 + k TWIN``,
    #: :func:`~.compare.twin_drive`) on the lines of ``f``, and their peaks: what the model
    #: itself does not determine (empty: no twin run)
    db_twins: list[np.ndarray] = field(default_factory=list)
    peaks_twins: list[list[dict]] = field(default_factory=list)

    dynamic_range: float = 35.0

    #: largest standard error (dB) of a used band from the measurement's own noise
    #: (:func:`band_noise`; 1.5 dB is a relative error of 0.25, an SNR of 12 dB; the
    #: first-order standard error underestimates the spread beyond that)
    noise_limit_db: float = 1.5
    #: largest total scatter (dB) of a used band's measured FRF (noise and distortion, before
    #: the model's share is taken out): beyond it the measured band level says little
    scatter_limit_db: float = 3.0

    @property
    def used_bands(self) -> list[dict]:
        """Bands within ``dynamic_range`` dB of the strongest measured band whose own noise
        error is below ``noise_limit_db`` and whose total scatter is below
        ``scatter_limit_db`` (weaker ones are noise-limited on a shaker rig)."""
        top = max(b["measured_db"] for b in self.bands)

        def ok(b, key, limit):
            return b.get(key) is None or b[key] <= limit

        return [b for b in self.bands if b["measured_db"] >= top - self.dynamic_range
                and ok(b, "noise_db", self.noise_limit_db)
                and ok(b, "scatter_db", self.scatter_limit_db)]

    @property
    def noise_floor_db(self) -> float:
        """The FRF error (RMS over the used bands) that the measurement's noise alone
        exceeds with 0.1 % probability: a correct model stays below it. The band errors of a
        correct model are independent with the standard errors ``noise_db``, so their mean
        square is ``chi^2_n / n`` times the mean square standard error."""
        from scipy.stats import chi2

        v = [b["noise_db"] for b in self.used_bands if b.get("noise_db") is not None]
        if not v:
            return 0.0
        n = len(v)
        return float(np.sqrt(np.mean(np.square(v)) * chi2.ppf(0.999, n) / n))

    @property
    def frf_rms_db(self) -> float:
        """RMS of the band errors within the dynamic range."""
        return float(np.sqrt(np.mean([b["mean_db"] ** 2 for b in self.used_bands])))

    @property
    def error_lines(self) -> np.ndarray:
        """Which lines :attr:`error_db` takes: those of ``error_band`` (every compared line
        without one) inside a band the measurement can speak for (:attr:`used_bands`)."""
        band = self.error_band or (float(self.f[0]), float(self.f[-1]))
        sel = (self.f >= band[0]) & (self.f <= band[1])
        if self.bands:
            inside = np.zeros(len(self.f), bool)
            for b in self.used_bands:
                inside |= (self.f >= b["lower_hz"]) & (self.f < b["upper_hz"])
            sel &= inside
        return sel

    @property
    def error_db(self) -> float:
        """The record's FRF error (:data:`ERROR_DEFINITION`): NaN where no line of the error
        band is one the measurement can speak for."""
        sel = self.error_lines
        if not sel.any():
            return float("nan")
        d = self.db_model[sel] - self.db_measured[sel]
        return float(np.sqrt(np.mean(d * d)))

    @property
    def level_text(self) -> str:
        """The record and its level as what it is: a sine's amplitude (sweeps, stepped
        sines, FRF records, with the direction where known), a random record's RMS in the
        compared band (its ``level`` is then only the rig's setting)."""
        name = KIND_NAMES.get(self.kind, self.kind or "record")
        if self.kind == "frf" and self.measured_by:
            name = f"FRF of a {self.measured_by} test,"
        if self.kind == "random" and self.level_rms is not None:
            band = f" in {self.band[0]:g}-{self.band[1]:g} Hz" if self.band else ""
            return f"random, RMS {amount(self.level_rms, self.unit)}{band}"
        return f"{name} {self.level:.3g} {self.unit}" + \
            (f", {self.direction}" if self.direction else "")

    @property
    def stepped(self) -> bool:
        """Compared on stepped-sine lines (a stepped-sine or FRF-only record)."""
        return self.kind in ("stepped_sine", "frf")

    @property
    def error_noise_db(self) -> float | None:
        """What the measurement's noise alone gives :attr:`error_db` for a correct model
        (the RMS of :attr:`line_noise` over the same lines), where known."""
        sel = self.error_lines
        if self.line_noise is None or not sel.any():
            return None
        return float(np.sqrt(np.mean(self.line_noise[sel] ** 2)))

    @property
    def error_scatter_db(self) -> float | None:
        """The model's own scatter in :attr:`error_db`: the RMS over the same lines of the
        dB differences between the model and its twins (runs whose drives differ by a
        relative ``1e-9``; :func:`~.compare.twin_drive`), where there are twins. A model
        whose response its drive does not determine (stick-slip under a random drive
        diverges from a round-off change within a tenth of a second) differs from a
        record of itself by as much: the error a correct model gets is then about
        ``sqrt(noise_alone^2 + scatter^2)``, not the noise alone."""
        sel = self.error_lines
        if not self.db_twins or not sel.any():
            return None
        d = np.concatenate([self.db_model[sel] - t[sel] for t in self.db_twins])
        return float(np.sqrt(np.mean(d * d)))

    def frf_rms_db_between(self, fmin: float, fmax: float) -> float:
        """RMS over the lines in ``[fmin, fmax]`` of the dB difference model - measurement
        of the smoothed FRFs (:func:`frf_db`): the error of one band as a user states it
        ("dB RMS over 80-105 Hz")."""
        sel = (self.f >= fmin) & (self.f <= fmax)
        if not sel.any():
            raise ValueError(f"no FRF line in {fmin:g}-{fmax:g} Hz (the comparison covers "
                             f"{self.f[0]:g}-{self.f[-1]:g} Hz)")
        d = self.db_model[sel] - self.db_measured[sel]
        return float(np.sqrt(np.mean(d * d)))

    def to_dict(self) -> dict:
        used = {b["centre_hz"] for b in self.used_bands} if self.bands else set()
        bands = [{**b, "used": b["centre_hz"] in used} for b in self.bands]
        band = self.error_band or (float(self.f[0]), float(self.f[-1]))
        return {"level": self.level, "file": self.file,
                "excitation": {"kind": self.kind, "direction": self.direction,
                               "level": self.level, "unit": self.unit,
                               "rms_in_band": self.level_rms},
                "frf_error_db": {"value": self.error_db, "band_hz": list(band),
                                 "definition": ERROR_DEFINITION,
                                 "lines": int(self.error_lines.sum()),
                                 "noise_alone": self.error_noise_db,
                                 "model_scatter": self.error_scatter_db,
                                 "rms_in_band": self.error_db,
                                 "bands": bands,
                                 "bands_rms": self.frf_rms_db if self.bands else None,
                                 "noise_floor_db": self.noise_floor_db if self.bands
                                 else None,
                                 "dynamic_range_db": self.dynamic_range},
                "settled_db": self.settled_db or None,
                "resonances": self.resonances, "harmonics": self.harmonics,
                "thd": {"model": self.thd_model, "measured": self.thd_measured,
                        "measured_noise_floor": self.thd_floor,
                        "difference_db": 20 * np.log10(self.thd_model / self.thd_measured)
                        if self.thd_model and self.thd_measured else None},
                "dc_offset": {"model": self.dc_model, "measured": self.dc_measured,
                              "standard_error": self.dc_standard_error},
                "input_unit": self.unit, "notes": self.notes}


@dataclass
class Comparison:
    """The model against every measured record (what ``sensfw compare`` writes).

    ``pairs``: per record (level, measured, model): the measured record (time signals or
    an FRF record) and the model's signals; ``jumps``: per level measured up and down,
    the jump between the two sweeps (:func:`sensfw.measure.lines.jump`)."""

    study: str
    output: str
    levels: list[LevelComparison]
    pairs: list[tuple]
    amplitude: dict | None  # :func:`sensfw.measure.signatures.amplitude_dependence`
    notes: list[str]
    error_band: tuple[float, float] | None = None
    jumps: list[dict] = field(default_factory=list)
    #: per record, the prediction band of a calibrated study
    #: (:class:`sensfw.measure.prediction.Band`); empty without ``[calibration.result]``
    bands: list = field(default_factory=list)

    def to_dict(self) -> dict:
        return {"study": self.study, "output": self.output,
                "error_definition": ERROR_DEFINITION,
                "error_band_hz": list(self.error_band) if self.error_band else None,
                "levels": [c.to_dict() for c in self.levels], "jumps": self.jumps,
                "amplitude_dependence": self.amplitude, "notes": self.notes,
                "prediction_bands": [b.to_dict() for b in self.bands]}
