"""Time-domain scorers."""

from __future__ import annotations

import numpy as np

from ..plugins import scorers
from .base import Scorer


@scorers.register("rms")
class RMS(Scorer):
    """Root mean square of the chosen channel (the paper mentions RMS acceleration as an
    alternative quality metric, Sect. 2.3)."""

    name = "rms"

    def score(self, signals, reference=None):
        x = self.signal(signals)
        return {"value": float(np.sqrt(np.mean(x**2)))}


@scorers.register("value")
class Value(Scorer):
    """Mean of a channel: the output of function-type models (one sample per run)."""

    name = "value"

    def score(self, signals, reference=None):
        return {"value": float(np.mean(self.signal(signals)))}
