"""Resonances of an FRF: peaks with their half-power damping, single-mode fits, and the
pairing of model and measured peaks.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks

from ..errors import SignalError
from ..signal.modal import sdof_fit


def resonances(f: np.ndarray, db: np.ndarray, prominence: float = 6.0,
               dynamic_range: float = 30.0) -> list[dict]:
    """Peaks of a (smoothed) FRF magnitude with their half-power damping ratio
    ``zeta = (f2 - f1) / (2 fn)`` from the -3 dB crossings. Peaks more than
    ``dynamic_range`` dB below the highest one are ignored (noise ripple where the response
    is weak)."""
    peaks, props = find_peaks(db, prominence=prominence)
    keep = db[peaks] >= np.max(db) - dynamic_range
    peaks, proms = peaks[keep], props["prominences"][keep]
    out = []
    for i, prom in zip(peaks, proms, strict=True):
        target = db[i] - 3.0
        lo = i
        while lo > 0 and db[lo] > target:
            lo -= 1
        hi = i
        while hi < len(db) - 1 and db[hi] > target:
            hi += 1
        zeta = None
        if db[lo] <= target and db[hi] <= target:
            f1 = np.interp(target, [db[lo], db[lo + 1]], [f[lo], f[lo + 1]])
            f2 = np.interp(target, [db[hi], db[hi - 1]], [f[hi], f[hi - 1]])
            zeta = float((f2 - f1) / (2 * f[i]))
        out.append({"frequency": float(f[i]), "peak_db": float(db[i]),
                    "prominence_db": float(prom), "damping_ratio": zeta})
    return out


#: a single-mode fit replaces the half-power values when it explains this fraction of the
#: complex FRF's variance near the peak (below it the peak is no clean mode: a distorted
#: nonlinear response, two modes within a few bandwidths)
MIN_FIT_R2 = 0.9


def fit_resonances(f: np.ndarray, H: np.ndarray, peaks: list[dict],
                   min_r2: float = MIN_FIT_R2) -> list[dict]:
    """Each peak of :func:`resonances` with a single-mode fit of the unsmoothed complex FRF
    ``H`` (:func:`sensfw.signal.modal.sdof_fit`): ``fit_frequency``, ``fit_damping`` and
    ``fit_r2``, or ``None`` where the fit fails or explains less than ``min_r2``. The
    half-power values stay in ``frequency`` and ``damping_ratio``; whoever compares two
    FRFs uses the fitted values only where both sides have them (the half-power damping of
    a 1/24-octave smoothed FRF is biased upwards, see :mod:`sensfw.signal.modal`)."""
    out = []
    for p in peaks:
        fit = None
        try:
            fit = sdof_fit(f, H, p["frequency"], p["damping_ratio"] or 0.02)
        except SignalError:
            pass
        ok = fit is not None and fit.r2 >= min_r2 and \
            abs(np.log(fit.frequency / p["frequency"])) < 0.05
        out.append({**p, "fit_frequency": fit.frequency if ok else None,
                    "fit_damping": fit.damping_ratio if ok else None,
                    "fit_r2": fit.r2 if fit is not None else None})
    return out


def match_resonances(model: list[dict], measured: list[dict], tol: float = 0.25) -> list[dict]:
    """Pair measured and model resonances within ``tol`` (relative) in order of frequency:
    the pairing that leaves the fewest unpaired and, among those, shifts them least (pairs
    never cross: a measured resonance above another is not paired with a model resonance
    below the other's partner); unmatched ones are listed with the other side empty (a
    missing or an extra mode)."""
    fm = np.array([m["frequency"] for m in measured], dtype=float)
    fs = np.array([s["frequency"] for s in model], dtype=float)
    om, os_ = np.argsort(fm, kind="stable"), np.argsort(fs, kind="stable")
    n, k = len(om), len(os_)
    # alignment of the two sorted lists: a pair costs its log distance, a resonance left
    # unpaired tol / 2, so that any pair within tol beats leaving both unpaired
    cost = np.zeros((n + 1, k + 1))
    cost[:, 0] = np.arange(n + 1) * tol / 2
    cost[0, :] = np.arange(k + 1) * tol / 2
    for i in range(1, n + 1):
        for j in range(1, k + 1):
            d = abs(np.log(fs[os_[j - 1]] / fm[om[i - 1]]))
            pair = cost[i - 1, j - 1] + d if d < tol else np.inf
            cost[i, j] = min(pair, cost[i - 1, j] + tol / 2, cost[i, j - 1] + tol / 2)
    partner: dict[int, int] = {}
    i, j = n, k
    while i > 0 and j > 0:
        d = abs(np.log(fs[os_[j - 1]] / fm[om[i - 1]]))
        if d < tol and np.isclose(cost[i, j], cost[i - 1, j - 1] + d):
            partner[int(om[i - 1])] = int(os_[j - 1])
            i, j = i - 1, j - 1
        elif np.isclose(cost[i, j], cost[i - 1, j] + tol / 2):
            i -= 1
        else:
            j -= 1
    rows, used = [], set(partner.values())
    for i, m in enumerate(measured):
        if i not in partner:
            rows.append({"measured_hz": m["frequency"], "model_hz": None, "shift_pct": None,
                         "measured_damping": m["damping_ratio"], "model_damping": None,
                         "note": "no model resonance nearby (missing mode?)"})
        else:
            s = model[partner[i]]
            rows.append({"measured_hz": m["frequency"], "model_hz": s["frequency"],
                         "shift_pct": 100 * (s["frequency"] / m["frequency"] - 1),
                         "measured_damping": m["damping_ratio"],
                         "model_damping": s["damping_ratio"], "note": ""})
    for j, s in enumerate(model):
        if j not in used:
            rows.append({"measured_hz": None, "model_hz": s["frequency"], "shift_pct": None,
                         "measured_damping": None, "model_damping": s["damping_ratio"],
                         "note": "not in the measurement (extra model mode?)"})
    return sorted(rows, key=lambda r: r["measured_hz"] or r["model_hz"])
