"""Order analysis of a swept response: order map, order spectrum and THD (Eqs. 12-17).

The paper (Sect. 2.3) follows MATLAB's ``rpmordermap`` and ``orderspectrum``: the response is
analysed in the angle domain of the excitation (its phase ``phi(t) = 2 pi int f_r dt`` with
the rotation frequency ``f_r(t) = rpm(t)/60``, Eq. 17), so that the k-th harmonic of the
excitation is a stationary component at order ``k`` (Eqs. 14-15) whatever the sweep rate.

Here each frame spans ``W = 1/order_resolution`` revolutions of the excitation; its spectrum
is the Fourier integral over angle ``X(n) = int x w(phi) exp(-i n phi) dphi`` (Eq. 13 with
``t`` -> ``phi``) evaluated directly on the time samples with ``dphi = 2 pi f_r / fs`` (a
non-uniform angle-domain DFT: no resampling, so no interpolation error). The window is a
flat-top window (as MATLAB's default), making the amplitude of a harmonic independent of
where it falls. Orders above Nyquist anywhere in the record are excluded: the map stops at
``fs / (2 max f_r)`` (MATLAB's limit), so nothing is aliased; with ``fs = 20 kHz`` and
``f1 = 5 kHz`` only orders up to 2 exist, as in the paper.

The order spectrum (Eq. 16) is the square root of the time average of the squared map
(MATLAB ``orderspectrum``). THD (Eq. 12) is ``100 sqrt(sum_{i>=2} P_i^2) / |P_1|`` over the
harmonics inside the map; ``unit="dBc"`` gives MATLAB's ``thd`` convention
``10 log10(sum_{i>=2} P_i^2 / P_1^2)``.
"""

from __future__ import annotations

import numpy as np
from scipy import sparse

from ..errors import SignalError
from ._checks import as_signal, check_fs, same_length

AMPLITUDES = ("rms", "peak", "power")
# flat-top window coefficients (scipy.signal.windows.flattop, Heinzel et al. 2002 / ISO 18431)
_FLATTOP = (0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368)


def _window(name: str, u: np.ndarray) -> np.ndarray:
    """Window on the unit interval ``u in [0, 1)``."""
    if name == "flattop":
        a = _FLATTOP
        c = 2 * np.pi * u
        return a[0] - a[1] * np.cos(c) + a[2] * np.cos(2 * c) - a[3] * np.cos(3 * c) \
            + a[4] * np.cos(4 * c)
    if name == "hann":
        return 0.5 - 0.5 * np.cos(2 * np.pi * u)
    if name == "boxcar":
        return np.ones_like(u)
    raise SignalError(f"unknown window {name!r}; use 'flattop', 'hann' or 'boxcar'")


def _phase(f_inst: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    """Phase of the excitation (rad) and its increment per sample (trapezoid rule)."""
    dphi = 2 * np.pi * f_inst / fs
    phi = np.concatenate([[0.0], np.cumsum(0.5 * (dphi[1:] + dphi[:-1]))])
    return phi, dphi


def _kernel(orders: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """``exp(-i n phi)`` for every order (rows): by recurrence on an evenly spaced order grid
    (one complex multiply per order instead of an exponential; error ~1e-12), directly
    otherwise."""
    d = np.diff(orders)
    if len(orders) > 2 and np.allclose(d, d[0], rtol=0, atol=1e-12) and orders[0] == 0:
        step = np.exp(-1j * d[0] * phi)
        E = np.empty((len(orders), len(phi)), complex)
        E[0] = 1.0
        for j in range(1, len(orders)):
            np.multiply(E[j - 1], step, out=E[j])
        return E
    return np.exp(-1j * np.outer(orders, phi))


def _frames(x: np.ndarray, fs: float, fr: np.ndarray, orders: np.ndarray, W: int,
            window: str, overlap: float):
    """Peak amplitude of each order in each frame of ``W`` revolutions, and frame times."""
    phi, dphi = _phase(fr, fs)
    rev = phi / (2 * np.pi)
    hop = W * (1 - overlap)
    n_frames = int(np.floor((rev[-1] - W) / hop + 1e-9)) + 1
    if n_frames < 1:
        raise SignalError(f"the record spans {rev[-1]:.3g} revolutions, fewer than one frame "
                          f"of {W} revolutions (order_resolution {1 / W:g})")
    # frame membership of every sample, vectorised: sample i lies in frames
    # floor(rev_i / hop) - j for j = 0 .. ceil(W / hop) - 1 when 0 <= u < 1
    base = np.floor(rev / hop).astype(int)
    rows, cols, vals = [], [], []
    for j in range(int(np.ceil(W / hop))):
        k = base - j
        u = (rev - k * hop) / W
        ok = (k >= 0) & (k < n_frames) & (u >= 0) & (u < 1)
        rows.append(k[ok])
        cols.append(np.flatnonzero(ok))
        vals.append(_window(window, u[ok]))
    Wm = sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(n_frames, len(x)))
    X = (Wm @ (_kernel(orders, phi) * (x * dphi)).T).T  # (n_orders, n_frames)
    norm = Wm @ dphi  # integral of the window over each frame's angle
    peak = np.abs(X) / norm
    peak[orders > 0] *= 2.0  # one-sided: a cosine of amplitude A gives |X| = A/2 * int w
    centre_rev = np.arange(n_frames) * hop + W / 2
    t = np.interp(centre_rev, rev, np.arange(len(x)) / fs)
    return peak, t


def _convert(peak: np.ndarray, orders: np.ndarray, amplitude: str) -> np.ndarray:
    rms = np.where((orders > 0)[:, None], peak / np.sqrt(2.0), peak)
    return {"rms": rms, "peak": peak, "power": rms**2}[amplitude]


def _checked(x, fs, f_inst, order_resolution, amplitude, overlap):
    x = as_signal(x, "x")
    fr = as_signal(f_inst, "f_inst")
    same_length(x, fr, "x", "f_inst")
    fs = check_fs(fs)
    if amplitude not in AMPLITUDES:
        raise SignalError(f"unknown amplitude {amplitude!r}; use one of {AMPLITUDES}")
    if np.any(fr <= 0):
        raise SignalError("f_inst must be positive")
    W = 1.0 / order_resolution if order_resolution > 0 else 0.0
    if not np.isfinite(W) or abs(W - round(W)) > 1e-9 or W < 2:
        raise SignalError(f"order_resolution must be 1/W for an integer W >= 2, "
                          f"got {order_resolution}")
    if not 0 <= overlap < 1:
        raise SignalError(f"overlap must be in [0, 1), got {overlap}")
    return x, fs, fr, round(W), fs / (2 * np.max(fr))


def order_map(x, fs: float, f_inst, order_resolution: float = 1 / 16,
              max_order: float | None = None, amplitude: str = "rms",
              window: str = "flattop", overlap: float = 0.5):
    """Order map of ``x`` for the rotation frequency ``f_inst`` (Eqs. 13-15).

    Parameters
    ----------
    x : array_like
        Response samples.
    fs : float
        Sample rate, Hz.
    f_inst : array_like
        Rotation (sweep) frequency per sample, Hz (``rpm(t)/60``, Eq. 17).
    order_resolution : float
        Order spacing ``1/W`` of the map; ``W`` revolutions per frame (1/W integer, so the
        integer orders lie on the grid).
    max_order : float, optional
        Highest order; default and upper limit ``fs / (2 max f_inst)`` (no aliasing).
    amplitude : {"rms", "peak", "power"}
        Amplitude convention (MATLAB ``rpmordermap``: RMS).
    window : {"flattop", "hann", "boxcar"}
        Window over each frame's angle span.
    overlap : float
        Frame overlap as a fraction of the frame (0.5 -> hop of W/2 revolutions).

    Returns
    -------
    orders : ndarray, shape (n_orders,)
    t : ndarray, shape (n_frames,)
        Time of each frame's centre, s.
    M : ndarray, shape (n_orders, n_frames)
        Amplitude of each order in each frame.
    """
    x, fs, fr, W, limit = _checked(x, fs, f_inst, order_resolution, amplitude, overlap)
    max_order = limit if max_order is None else min(float(max_order), limit)
    orders = np.arange(0, np.floor(max_order * W + 1e-9) + 1) / W
    peak, t = _frames(x, fs, fr, orders, W, window, overlap)
    return orders, t, _convert(peak, orders, amplitude)


def order_spectrum(x, fs: float, f_inst, max_order: float | None = None,
                   amplitude: str = "rms", order_resolution: float = 1 / 16,
                   window: str = "flattop", overlap: float = 0.5):
    """Order spectrum ``(orders, P)``: the map of :func:`order_map` averaged over time,
    ``P = sqrt(mean_t M^2)`` for "rms"/"peak" and ``mean_t M`` for "power" (Eq. 16, MATLAB
    ``orderspectrum``)."""
    orders, _, M = order_map(x, fs, f_inst, order_resolution, max_order, amplitude, window,
                             overlap)
    if amplitude == "power":
        return orders, M.mean(axis=1)
    return orders, np.sqrt(np.mean(M**2, axis=1))


def detrend_spectrum(orders: np.ndarray, P: np.ndarray, guard: float = 0.25) -> np.ndarray:
    """Remove the trend of an order spectrum (Sect. 2.3, Fig. 9): a straight line fitted to
    the bins away from the integer orders (farther than ``guard``) is subtracted, negative
    values are clipped to zero. Harmonic peaks then stand on a zero floor, so spectra of
    different runs compare."""
    away = np.abs(orders - np.round(orders)) > guard
    away &= orders > 0
    if away.sum() < 2:
        return P.copy()
    coef = np.polyfit(orders[away], P[away], 1)
    return np.clip(P - np.polyval(coef, orders), 0.0, None)


def harmonic_amplitudes(x, fs: float, f_inst, harmonics=None, detrend: bool = False,
                        amplitude: str = "rms", order_resolution: float = 1 / 16,
                        window: str = "flattop", overlap: float = 0.5) -> dict[int, float]:
    """Amplitudes ``P_k`` of the integer orders ``harmonics`` (default: every order inside
    the map), as in the order spectrum. Without ``detrend`` only those orders are computed
    (fast path for scorers)."""
    if detrend:
        orders, P = order_spectrum(x, fs, f_inst, amplitude=amplitude,
                                   order_resolution=order_resolution, window=window,
                                   overlap=overlap)
        P = detrend_spectrum(orders, P)
        top = int(np.floor(orders[-1] + 1e-9))
        values = {k: float(P[round(k / order_resolution)]) for k in range(1, top + 1)}
    else:
        x, fs, fr, W, limit = _checked(x, fs, f_inst, order_resolution, amplitude, overlap)
        top = int(np.floor(limit + 1e-9))
        ks = np.arange(1, top + 1, dtype=float)
        if len(ks) == 0:
            return {}
        peak, _ = _frames(x, fs, fr, ks, W, window, overlap)
        M = _convert(peak, ks, amplitude)
        P = M.mean(axis=1) if amplitude == "power" else np.sqrt(np.mean(M**2, axis=1))
        values = {int(k): float(v) for k, v in zip(ks, P, strict=True)}
    if harmonics is None:
        return values
    out = {}
    for k in harmonics:
        if k != int(k) or k < 1:
            raise SignalError(f"harmonics are integer orders >= 1, got {k}")
        if int(k) not in values:
            raise SignalError(f"order {k} is above the highest unaliased order {top} "
                              f"(fs/(2 max f_inst))")
        out[int(k)] = values[int(k)]
    return out


def thd_from_spectrum(orders: np.ndarray, P: np.ndarray, n_harmonics: int | None = None,
                      unit: str = "percent") -> float:
    """Eq. 12 from an RMS order spectrum ``(orders, P)`` (as returned by
    :func:`order_spectrum`), over the integer orders it contains."""
    orders, P = np.asarray(orders, float), np.asarray(P, float)
    if orders.ndim != 1 or orders.shape != P.shape or len(orders) < 2:
        raise SignalError(f"orders and P must be 1-D, equally long and hold two or more "
                          f"orders (got shapes {orders.shape} and {P.shape})")
    res = orders[1] - orders[0]
    top = int(np.floor(orders[-1] + 1e-9))
    values = {k: float(P[round(k / res)]) for k in range(1, top + 1)}
    return _thd(values, n_harmonics, unit)


def _thd(P: dict[int, float], n_harmonics: int | None, unit: str) -> float:
    if unit not in ("percent", "dBc"):
        raise SignalError(f"unknown THD unit {unit!r}; use 'percent' or 'dBc'")
    if n_harmonics is not None and not int(n_harmonics) >= 2:  # no harmonic: 0 %, -inf dBc
        raise SignalError(f"n_harmonics must be >= 2 (it counts the fundamental), got "
                          f"{n_harmonics}")
    top = max(P) if P else 0
    if top < 2:
        raise SignalError("no harmonic below Nyquist: THD needs fs > 4 max(f_inst)")
    n = top if n_harmonics is None else min(int(n_harmonics), top)
    if P[1] == 0:
        raise SignalError("the fundamental (order 1) is zero; THD is undefined")
    ratio = sum(P[i] ** 2 for i in range(2, n + 1)) / P[1] ** 2
    return float(100 * np.sqrt(ratio)) if unit == "percent" else float(10 * np.log10(ratio))


def thd(x, fs: float, f_inst, n_harmonics: int | None = None, unit: str = "percent",
        detrend: bool = False, order_resolution: float = 1 / 16) -> float:
    """Total harmonic distortion (Eq. 12) of a swept response.

    ``THD = 100 sqrt(sum_{i=2}^{N} P_i^2) / |P_1|`` (percent) with ``P_i`` the RMS order
    amplitudes of the order spectrum and ``N`` the highest order inside the map (or
    ``n_harmonics``, counting the fundamental: N = n_harmonics); ``unit="dBc"`` returns
    ``10 log10(sum P_i^2 / P_1^2)``. ``detrend`` uses :func:`detrend_spectrum` first.
    """
    if unit not in ("percent", "dBc"):
        raise SignalError(f"unknown THD unit {unit!r}; use 'percent' or 'dBc'")
    P = harmonic_amplitudes(x, fs, f_inst, detrend=detrend, order_resolution=order_resolution)
    return _thd(P, n_harmonics, unit)
