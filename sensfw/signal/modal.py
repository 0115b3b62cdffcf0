"""Natural frequency and damping ratio of a resonance from a measured FRF: a single-mode
fit around the peak.

The half-power bandwidth of a smoothed FRF magnitude, ``zeta = (f2 - f1) / (2 fn)``, is quick
but biased when the smoothing window is not much narrower than the peak: a 1/24-octave
window spans 2.9 % of the frequency, as wide as the half-power band of a mode with 1.5 %
damping, and widens every such peak (the damping ratios of two FRFs are then pulled towards
each other). :func:`sdof_fit` instead fits one mode to the *unsmoothed* complex FRF near the
peak (the rational-fraction form of the SDOF methods, Ewins 2000, *Modal Testing*, Sect.
4.3-4.4; the circle fit is its graphical cousin)::

    H(f) ~ A / (fn^2 - f^2 + 2 i zeta fn f) + B                                   (1)

with complex residue ``A`` and a complex constant ``B`` for the other modes' residual
contribution. ``A`` and ``B`` enter linearly and are eliminated (variable projection,
Golub & Pereyra 1973), so the least-squares problem is two-dimensional in ``(fn, zeta)``
(``scipy.optimize.least_squares``). It needs the modes to be separated by a few half-power
bandwidths; for closely spaced modes or many FRFs at once a global multi-mode estimator
(LSCF/PolyMAX, e.g. sdypy-EMA) is the tool.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..errors import SignalError


@dataclass(frozen=True)
class ModeFit:
    """Result of :func:`sdof_fit`: natural frequency (Hz), damping ratio, residue and
    residual term of Eq. 1, the coefficient of determination ``r2`` of the fit on the
    complex FRF and the number of frequency lines used."""

    frequency: float
    damping_ratio: float
    residue: complex
    residual: complex
    r2: float
    lines: int


def _basis(f: np.ndarray, fn: float, zeta: float) -> np.ndarray:
    return np.column_stack([1.0 / (fn**2 - f**2 + 2j * zeta * fn * f), np.ones_like(f)])


def _project(f, H, fn, zeta):
    """Residual of the best ``A``, ``B`` for ``(fn, zeta)`` and the coefficients."""
    G = _basis(f, fn, zeta)
    coef, *_ = np.linalg.lstsq(G, H, rcond=None)
    return H - G @ coef, coef


def sdof_fit(f, H, f_peak: float, zeta0: float = 0.02, half_width: float | None = None,
             min_lines: int = 7) -> ModeFit:
    """Fit one mode (Eq. 1) to the complex FRF ``H(f)`` around ``f_peak``.

    Parameters
    ----------
    f, H : array_like
        Frequencies (Hz, increasing) and complex FRF (unsmoothed: its phase carries the
        damping information the magnitude alone spreads over few lines).
    f_peak : float
        Frequency of the peak (e.g. from a smoothed magnitude).
    zeta0 : float
        Starting damping ratio (a half-power estimate).
    half_width : float, optional
        Half-width of the fitted band, Hz; default ``max(2.5 zeta0 f_peak, 4 df)``: a band
        of +-2.5 half-power half-widths holds most of the mode's phase change while the
        neighbours' influence stays in ``B``.
    min_lines : int
        Fewest frequency lines in the band; fewer is a :class:`SignalError`.

    Returns
    -------
    ModeFit
    """
    f = np.asarray(f, float)
    H = np.asarray(H, complex)
    if f.shape != H.shape or f.ndim != 1:
        raise SignalError(f"f and H must be 1-D and equally long (got {f.shape}, {H.shape})")
    if not (np.isfinite(f_peak) and f[0] < f_peak < f[-1]):
        raise SignalError(f"f_peak = {f_peak} Hz is outside the FRF's {f[0]:g}-{f[-1]:g} Hz")
    df = float(np.median(np.diff(f)))
    zeta0 = float(np.clip(zeta0 if zeta0 and np.isfinite(zeta0) else 0.02, 1e-3, 0.2))
    hw = half_width if half_width is not None else max(2.5 * zeta0 * f_peak, 4 * df)
    sel = (np.abs(f - f_peak) <= hw) & np.isfinite(H)
    if sel.sum() < min_lines:
        raise SignalError(f"only {int(sel.sum())} frequency lines within +-{hw:.3g} Hz of "
                          f"{f_peak:.4g} Hz; a mode fit needs {min_lines}")
    fs_, Hs = f[sel], H[sel]
    scale = np.max(np.abs(Hs))
    Hn = Hs / scale

    def residual(x):
        r, _ = _project(fs_, Hn, x[0] * f_peak, x[1])
        return np.concatenate([r.real, r.imag])

    lo, hi = fs_[0] / f_peak, fs_[-1] / f_peak
    sol = least_squares(residual, [1.0, zeta0], bounds=([lo, 1e-4], [hi, 0.5]),
                        x_scale=[zeta0, zeta0])
    fn, zeta = sol.x[0] * f_peak, float(sol.x[1])
    r, coef = _project(fs_, Hn, fn, zeta)
    total = np.sum(np.abs(Hn - Hn.mean()) ** 2)
    r2 = float(1 - np.sum(np.abs(r) ** 2) / total) if total > 0 else 0.0
    return ModeFit(frequency=float(fn), damping_ratio=zeta, residue=complex(coef[0] * scale),
                   residual=complex(coef[1] * scale), r2=r2, lines=int(sel.sum()))
