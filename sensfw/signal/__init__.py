"""Signal analysis: FRF estimators (Eqs. 8-10), order map/spectrum and THD (Eqs. 12-17),
spectrograms (Fig. 11), single-mode fits of a resonance."""

from .frf import ESTIMATORS, coherence, frf, hv_from_spectra, octave_smooth, spectra
from .modal import ModeFit, sdof_fit
from .orders import (
    detrend_spectrum,
    harmonic_amplitudes,
    order_map,
    order_spectrum,
    thd,
    thd_from_spectrum,
)
from .spectrogram import spectrogram

__all__ = ["ESTIMATORS", "ModeFit", "coherence", "detrend_spectrum", "frf",
           "harmonic_amplitudes", "hv_from_spectra", "octave_smooth", "order_map",
           "order_spectrum", "sdof_fit", "spectra", "spectrogram", "thd", "thd_from_spectrum"]
