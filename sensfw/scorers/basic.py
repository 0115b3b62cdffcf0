"""Time-domain scorers."""

from __future__ import annotations

import numpy as np

from ..plugins import scorers
from ..signal._checks import as_signal
from .base import Scorer


def _samples(scorer: Scorer, signals) -> np.ndarray:
    """The scored channel, one or more finite samples (NaN would pass into the scores)."""
    return as_signal(scorer.signal(signals), f"scorer {scorer.name!r}: channel "
                     f"{scorer.channel_name(signals)!r}", min_len=1)


@scorers.register("rms")
class RMS(Scorer):
    """Root mean square of the chosen channel (the paper mentions RMS acceleration as an
    alternative quality metric, Sect. 2.3)."""

    name = "rms"

    def score(self, signals, reference=None):
        x = _samples(self, signals)
        return {"value": float(np.sqrt(np.mean(x**2)))}


@scorers.register("value")
class Value(Scorer):
    """Mean of a channel: the output of function-type models (one sample per run)."""

    name = "value"

    def score(self, signals, reference=None):
        return {"value": float(np.mean(_samples(self, signals)))}
