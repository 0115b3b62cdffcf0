"""Measured files prepared for a study: loaded, checked, their excitation estimated and the
model's drive decided (:func:`~sensfw.measure.checks.prepare`), sorted by level."""

from __future__ import annotations

from collections.abc import Sequence

from ..errors import MeasurementError, SensfwError
from ..study import Study
from .checks import prepare
from .io import Measurement, load_all


def load_measurements(study: Study, files: Sequence[str]) -> list[Measurement]:
    """Load, check and prepare every file (a file may hold several levels), sorted by
    level."""
    if not files:
        raise SensfwError("no measurement file given (--measured FILE ...)")
    out = []
    for f in files:
        for raw in load_all(f):
            meas = prepare(raw, study)
            if not meas.level > 0:
                raise MeasurementError(meas.file, "the excitation is zero", "force")
            out.append(meas)
    return sorted(out, key=lambda m: m.level)
