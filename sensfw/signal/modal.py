"""Natural frequency and damping ratio of a resonance from a measured FRF: a single-mode
fit around the peak.

The half-power bandwidth of a smoothed FRF magnitude, ``zeta = (f2 - f1) / (2 fn)``, is quick
but biased when the smoothing window is not much narrower than the peak: a 1/24-octave
window spans 2.9 % of the frequency, as wide as the half-power band of a mode with 1.5 %
damping, and widens every such peak (the damping ratios of two FRFs are then pulled towards
each other). :func:`sdof_fit` instead fits one mode to the *unsmoothed* complex FRF near the
peak (the rational-fraction form of the SDOF methods, Ewins 2000, *Modal Testing*, Sect.
4.3-4.4; the circle fit is its graphical cousin)::

    H(f) ~ (i w)^p A / (fn^2 - f^2 + 2 i zeta fn f) + B + i w C,   w = 2 pi f        (1)

with complex residue ``A``, ``p`` = 0, 1, 2 for an FRF of displacement, velocity or
acceleration (``quantity``; with ``p = 0`` for any FRF the residue is taken constant over the
band, which is adequate over a few half-power widths), and complex residual terms for the
other modes: a constant ``B`` and, with ``residual_terms=2``, a slope ``C`` (for a wide band,
such as a sweep's whole 86-100 Hz window around the UNESP-BERT beam's mode). All of ``A``,
``B``, ``C`` enter linearly and are eliminated (variable projection, Golub & Pereyra 1973),
so the least-squares problem is two-dimensional in ``(fn, zeta)``
(``scipy.optimize.least_squares``). It needs the modes to be separated by a few half-power
bandwidths; for closely spaced modes or many FRFs at once a global multi-mode estimator
(LSCF/PolyMAX, e.g. sdypy-EMA) is the tool.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import SignalError

#: power ``p`` of ``i w`` in Eq. 1 that turns a displacement FRF into the given quantity
QUANTITY = {"displacement": 0, "velocity": 1, "acceleration": 2}


@dataclass(frozen=True)
class ModeFit:
    """Result of :func:`sdof_fit`: natural frequency (Hz), damping ratio, residue ``A`` and
    residual terms ``B``, ``C`` of Eq. 1, the coefficient of determination ``r2`` of the fit
    on the complex FRF, the number of frequency lines used, and the frequency and magnitude
    of the largest ``|H|`` among them."""

    frequency: float
    damping_ratio: float
    residue: complex
    residual: complex
    r2: float
    lines: int
    peak_frequency: float
    peak: float
    residual_slope: complex = 0j

    def to_dict(self) -> dict:
        return asdict(self)


def _basis(f: np.ndarray, fn: float, zeta: float, p: int, terms: int,
           f_ref: float) -> np.ndarray:
    """Columns of Eq. 1 for ``A``, ``B`` (and ``C``), with ``i f / f_ref`` in place of
    ``i w`` (well scaled; the coefficients are converted back in :func:`sdof_fit`)."""
    x = 1j * f / f_ref
    return np.column_stack([x**p / (fn**2 - f**2 + 2j * zeta * fn * f)]
                           + [x**k for k in range(terms)])


def _project(f, H, fn, zeta, p, terms, f_ref):
    """Residual of the best linear coefficients for ``(fn, zeta)`` and the coefficients."""
    G = _basis(f, fn, zeta, p, terms, f_ref)
    coef, *_ = np.linalg.lstsq(G, H, rcond=None)
    return H - G @ coef, coef


def sdof_fit(f, H, f_peak: float | None = None, zeta0: float = 0.02,
             half_width: float | None = None, min_lines: int = 7, *,
             band: tuple[float, float] | None = None, quantity: str = "displacement",
             residual_terms: int = 1) -> ModeFit:
    """Fit one mode (Eq. 1) to the complex FRF ``H(f)`` around ``f_peak`` or in ``band``.

    Parameters
    ----------
    f, H : array_like
        Frequencies (Hz, increasing) and complex FRF (unsmoothed: its phase carries the
        damping information the magnitude alone spreads over few lines).
    f_peak : float, optional
        Frequency of the peak (e.g. from a smoothed magnitude). Default (with ``band``): the
        largest ``|H|`` in the band.
    zeta0 : float
        Starting damping ratio (a half-power estimate).
    half_width : float, optional
        Half-width of the fitted band around ``f_peak``, Hz; default
        ``max(2.5 zeta0 f_peak, 4 df)``: a band of +-2.5 half-power half-widths holds most
        of the mode's phase change while the neighbours' influence stays in ``B``. Not used
        with ``band``.
    min_lines : int
        Fewest frequency lines in the band; fewer is a :class:`SignalError`.
    band : (float, float), optional
        The fitted band (Hz) instead of ``f_peak +- half_width``: it should hold the
        resonance and a few half-power widths either side.
    quantity : {"displacement", "velocity", "acceleration"}
        What the FRF's output measures (the power ``p`` of Eq. 1).
    residual_terms : {1, 2}
        Residual terms of the other modes: ``B``, or ``B + i w C``.

    Returns
    -------
    ModeFit
    """
    if quantity not in QUANTITY:
        raise SignalError(f"quantity must be one of {', '.join(QUANTITY)}, got {quantity!r}")
    if residual_terms not in (1, 2):
        raise SignalError(f"residual_terms must be 1 or 2, got {residual_terms!r}")
    f = np.asarray(f, float)
    H = np.asarray(H, complex)
    if f.shape != H.shape or f.ndim != 1 or len(f) < min_lines:
        raise SignalError(f"f and H must be 1-D, equally long and hold min_lines = "
                          f"{min_lines} lines or more (got {f.shape}, {H.shape})")
    df = float(np.median(np.diff(f)))
    zeta0 = float(np.clip(zeta0 if zeta0 and np.isfinite(zeta0) else 0.02, 1e-3, 0.2))
    if band is not None:
        sel = (f >= band[0]) & (f <= band[1]) & np.isfinite(H)
        where = f"in {band[0]:g}-{band[1]:g} Hz"
    elif f_peak is None:
        raise SignalError("a mode fit needs f_peak or band")
    elif not (np.isfinite(f_peak) and f[0] < f_peak < f[-1]):
        raise SignalError(f"f_peak = {f_peak} Hz is outside the FRF's {f[0]:g}-{f[-1]:g} Hz")
    else:
        hw = half_width if half_width is not None else max(2.5 * zeta0 * f_peak, 4 * df)
        sel = (np.abs(f - f_peak) <= hw) & np.isfinite(H)
        where = f"within +-{hw:.3g} Hz of {f_peak:.4g} Hz"
    if sel.sum() < min_lines:
        raise SignalError(f"only {int(sel.sum())} frequency lines {where}; a mode fit needs "
                          f"{min_lines}")
    fs_, Hs = f[sel], H[sel]
    i_peak = int(np.argmax(np.abs(Hs)))
    scale = float(np.abs(Hs[i_peak]))
    if not scale > 0:
        raise SignalError(f"the FRF is zero {where}")
    Hn = Hs / scale
    p = QUANTITY[quantity]
    if f_peak is None:
        f_peak = float(fs_[i_peak])

    def residual(x):
        r, _ = _project(fs_, Hn, x[0] * f_peak, x[1], p, residual_terms, f_peak)
        return np.concatenate([r.real, r.imag])

    lo, hi = fs_[0] / f_peak, fs_[-1] / f_peak
    sol = least_squares(residual, [float(np.clip(1.0, lo, hi)), zeta0],
                        bounds=([lo, 1e-4], [hi, 0.5]), x_scale=[zeta0, zeta0])
    fn, zeta = sol.x[0] * f_peak, float(sol.x[1])
    r, coef = _project(fs_, Hn, fn, zeta, p, residual_terms, f_peak)
    total = np.sum(np.abs(Hn - Hn.mean()) ** 2)
    r2 = float(1 - np.sum(np.abs(r) ** 2) / total) if total > 0 else 0.0
    w_ref = 2 * np.pi * f_peak  # (i f / f_peak)^k = (i w)^k / w_ref^k
    slope = complex(coef[2] * scale / w_ref) if residual_terms == 2 else 0j
    return ModeFit(frequency=float(fn), damping_ratio=zeta,
                   residue=complex(coef[0] * scale / w_ref**p),
                   residual=complex(coef[1] * scale), r2=r2, lines=int(sel.sum()),
                   peak_frequency=float(fs_[i_peak]), peak=scale, residual_slope=slope)
