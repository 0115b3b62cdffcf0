"""Single-mode fit of an FRF around a resonance: natural frequency and damping ratio.

A resonance's half-power width read off a smoothed FRF mixes the smoothing into the damping;
a fit of one mode plus residual terms for the others (a rational-fraction fit of the complex
FRF, e.g. Ewins 2000, *Modal Testing*, Sect. 4.3) gives the natural frequency and damping
ratio to a small fraction of the frequency resolution, from magnitude and phase together.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import SignalError

#: power of ``i w`` that turns a displacement FRF into the given quantity
QUANTITY = {"displacement": 0, "velocity": 1, "acceleration": 2}


@dataclass(frozen=True)
class ModalFit:
    """Result of :func:`modal_fit` (Hz, damping ratio, the FRF's units)."""

    fn_hz: float
    zeta: float
    peak_hz: float
    peak: float
    misfit: float

    def to_dict(self) -> dict:
        return asdict(self)


def modal_fit(f, H, band: tuple[float, float], quantity: str = "velocity") -> ModalFit:
    """Natural frequency and damping ratio of the mode that dominates ``H`` in ``band``.

    Fits ``H(w) = (i w)^p R / (wn^2 - w^2 + 2 i zeta wn w) + A + i w B`` by least squares on
    the complex values in ``band`` (``p`` from ``quantity``: the FRF of a displacement,
    velocity or acceleration; ``R`` the complex modal residue, ``A``, ``B`` complex residual
    terms for the modes outside the band).

    Parameters
    ----------
    f : array_like
        Frequencies (Hz).
    H : array_like
        Complex FRF at ``f``.
    band : (float, float)
        Frequency band of the fit (Hz); it should hold the resonance and a few half-power
        widths either side.
    quantity : {"displacement", "velocity", "acceleration"}
        What the FRF's output measures.

    Returns
    -------
    ModalFit
        ``fn_hz``, ``zeta``, the frequency and magnitude of the largest ``|H|`` in the band
        and the fit's RMS misfit of the magnitude relative to that peak.
    """
    if quantity not in QUANTITY:
        raise SignalError(f"quantity must be one of {', '.join(QUANTITY)}, got {quantity!r}")
    f, H = np.asarray(f, float), np.asarray(H, complex)
    sel = (f >= band[0]) & (f <= band[1])
    if sel.sum() < 8:
        raise SignalError(f"the band {band[0]:g}-{band[1]:g} Hz holds {int(sel.sum())} "
                          "frequencies; a single-mode fit needs at least 8")
    w, h = 2 * np.pi * f[sel], H[sel]
    i = int(np.argmax(np.abs(h)))
    scale = float(np.abs(h[i]))
    if not scale > 0:
        raise SignalError("the FRF is zero in the band")
    p = QUANTITY[quantity]

    def model(x):
        wn, z = x[0], x[1]
        R, A, B = x[2] + 1j * x[3], x[4] + 1j * x[5], x[6] + 1j * x[7]
        return (1j * w) ** p * R / (wn**2 - w**2 + 2j * z * wn * w) + A + 1j * w * B

    def res(x):
        r = (model(x) - h) / scale
        return np.concatenate([r.real, r.imag])

    wn0, z0 = w[i], 0.01
    r0 = h[i] * 2j * z0 * wn0**2 / (1j * wn0) ** p  # the residue that explains the peak
    x0 = [wn0, z0, r0.real, r0.imag, 0.0, 0.0, 0.0, 0.0]
    x_scale = [wn0, z0, abs(r0), abs(r0), scale, scale, scale / wn0, scale / wn0]
    sol = least_squares(res, x0, x_scale=x_scale, max_nfev=4000)
    misfit = float(np.sqrt(np.mean((np.abs(model(sol.x)) - np.abs(h)) ** 2)) / scale)
    return ModalFit(fn_hz=float(sol.x[0] / (2 * np.pi)), zeta=float(abs(sol.x[1])),
                    peak_hz=float(f[sel][i]), peak=scale, misfit=misfit)
