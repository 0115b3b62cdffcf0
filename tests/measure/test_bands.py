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
    noise_sigma,
    tf_noise_sigma,
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
    """At 10 % noise the force's spectrum above the sweep is its noise; at 1 % the sweep's
    own splatter above its last frequency reads as 2-3 times the noise, where the
    short-time spectrum's cells away from the sweep's line hold noise alone: the lower of
    the two reads 1.0-1.3 times the noise (5 draws: their mean to a few per cent), never
    below it. A force without noise gives about 0."""
    rng = np.random.default_rng(2)
    for fraction in (0.10, 0.03, 0.01):
        sp = fraction * np.std(record.force)
        est = [excitation_noise_sigma(noisy(record, record.channels["a1"], sp, 0.0, rng),
                                      BAND) / sp for _ in range(5)]
        assert 0.95 <= np.mean(est) <= 1.3
    assert excitation_noise_sigma(record, (50.0, 9500.0)) < 1e-3 * np.std(record.force)


def test_white_noise_alone_from_the_short_time_spectrum():
    """On white noise every cell of the short-time spectrum is noise: the quantile's
    estimate is unbiased (20 draws of 30000 samples: the mean to +-1 %, each draw +-4 %)."""
    rng = np.random.default_rng(3)
    est = [tf_noise_sigma(2.5 * rng.standard_normal(30000), 1e4) / 2.5 for _ in range(20)]
    assert np.mean(est) == pytest.approx(1.0, abs=0.01)
    assert np.max(np.abs(np.array(est) - 1)) < 0.04


@pytest.mark.parametrize("clip", [0.5, 0.7])
def test_the_output_noise_under_a_distortion_that_fills_every_line(record, clip):
    """The response clipped at ``clip`` of its peak (a stop's impacts: odd harmonics at
    every order up to the Nyquist frequency, as the quick study's contacts give). The
    local fit's residual reads the harmonics as noise (1.6-1.9 times it at 1 %); between
    the sweep's harmonics the short-time spectrum holds noise alone, so the estimate is
    1.0-1.3 times the noise at 1 % and 3 % (5 draws each; an upper bound: the response
    leaks into every cell a little)."""
    y = record.channels["a1"]
    y = np.clip(y, -clip * np.max(np.abs(y)), clip * np.max(np.abs(y)))
    rng = np.random.default_rng(4)
    for fraction in (0.01, 0.03):
        sx = fraction * np.std(y)
        est = [noise_sigma(noisy(record, y, 0.0, sx, rng), "a1") / sx for _ in range(5)]
        assert 1.0 <= np.mean(est) <= 1.3
