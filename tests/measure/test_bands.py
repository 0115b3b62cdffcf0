"""The band errors a record's white noise gives its band H1 (:func:`band_white_noise`),
against their scatter over independent noise realisations of the same record."""

from __future__ import annotations

import numpy as np
import pytest

from sensfw.excitation import Chirp
from sensfw.measure.bands import (
    analysis_bands,
    band_frf_db,
    band_white_noise,
    excitation_noise_sigma,
)
from sensfw.models.analytic import TwoDOF
from sensfw.models.base import Signals

TO_DB = 20 / np.log(10) / np.sqrt(2)
BAND = (50.0, 2000.0)


@pytest.fixture(scope="module")
def record():
    model = TwoDOF()
    return model.simulate(model.parameters().nominal(),
                          Chirp(*BAND, 0.15, 20000.0, 1.0, tail=0.02))


def noisy(sig, y, sp, sx, rng):
    n = len(sig.t)
    return Signals(t=sig.t, force=sig.force + sp * rng.standard_normal(n),
                   channels={"a1": y + sx * rng.standard_normal(n)}, fs=sig.fs)


@pytest.mark.parametrize("distorted", [False, True])
def test_the_band_errors_are_the_scatter_over_noise_realisations(record, distorted):
    """3 % noise on force and output, 300 realisations. ``distorted`` adds the chirp's
    second harmonic at half the response's RMS, a part of the output not coherent with the
    force in any band: input noise multiplies it, so those bands scatter more than the
    output noise alone says. With the true noise levels, the predicted error is the
    measured scatter to within the Monte-Carlo error of a standard deviation from 300
    draws (4 %) and the first-order expansion's (at 3 %: ~1e-3), so +-15 % per band."""
    y = record.channels["a1"]
    if distorted:
        t, T = record.t, 0.15
        phase = 2 * np.pi * BAND[0] * T / np.log(BAND[1] / BAND[0]) * (
            (BAND[1] / BAND[0]) ** (np.minimum(t, T) / T) - 1)
        y = y + np.where(t < T, np.sin(2 * phase), 0.0) * 0.5 * np.std(y)
    sp, sx = 0.03 * np.std(record.force), 0.03 * np.std(y)
    edges = analysis_bands(*BAND)
    rng = np.random.default_rng(1)
    draws = [noisy(record, y, sp, sx, rng) for _ in range(300)]
    scatter = np.std([band_frf_db(s, "a1", edges) for s in draws], axis=0, ddof=1)
    predicted = TO_DB * np.mean([band_white_noise(s, "a1", edges, BAND, sp, sx)
                                 for s in draws[:10]], axis=0)
    assert scatter / predicted == pytest.approx(np.ones(len(edges)), abs=0.15)
    if distorted:  # the output noise alone would say far less in the weakest bands
        alone = TO_DB * band_white_noise(draws[0], "a1", edges, BAND, 0.0, sx)
        assert np.max(scatter / alone) > 2.0


def test_the_excitations_noise_from_its_spectrum_above_the_band(record):
    """At 10 % noise the force's spectrum above the sweep is its noise (within 5 % here);
    at 1 % the sweep's own splatter above its last frequency reads as more noise: an upper
    bound, never below the truth. A record without bins above its band gives 0."""
    rng = np.random.default_rng(2)
    for fraction, (lo, hi) in ((0.10, (0.95, 1.10)), (0.01, (1.0, 4.0))):
        sp = fraction * np.std(record.force)
        est = [excitation_noise_sigma(noisy(record, record.channels["a1"], sp, 0.0, rng),
                                      BAND) / sp for _ in range(5)]
        assert lo <= np.mean(est) <= hi
    assert excitation_noise_sigma(record, (50.0, 9500.0)) == 0.0
