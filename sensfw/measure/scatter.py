"""The model's own scatter around a calibrated point, added to every entry's standard error.

Stick-slip makes a contact model's response irregular in its parameters: a change of a
fraction of a per cent can move band levels by decibels (measured on the quick study at
the friction velocity 0.65 mm/s), far below any calibration's resolution. The second
differences ``(r(z + delta e_i) + r(z - delta e_i)) / 2 - r(z)`` along each coded axis
cancel the smooth trend; for an irregular part of variance ``rho^2`` they have variance
``1.5 rho^2``; per entry the roughest axis counts. Widening every entry's standard error
by ``rho`` keeps any hypothesis from being credited with fitting the irregular part.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from .calibration import Fit
from .residuals import Residuals

Log = Callable[[str], None]


def roughness(res: Residuals, fit: Fit, effects=(), delta: float = 0.01) -> np.ndarray:
    """The model's scatter per residual entry (dB) around ``fit``'s optimum; costs ``2 d``
    points."""
    coords = fit.coords
    d = len(coords)
    sigma = np.array([x for part in res.entries.sigma for x in part])
    if d == 0 or fit.best.w is None:
        return np.zeros(len(sigma))
    z = coords.code(fit.best.values)
    zs = [np.clip(z + s * delta * np.eye(d)[i], -1, 1) for i in range(d) for s in (-1, 1)]
    ws = res.evaluate(effects, [{**fit.best.values, **coords.decode(zz)} for zz in zs],
                      "model scatter")
    dB = sigma / res.entry_weights()  # weighted residual -> dB
    r0 = fit.best.w * dB
    second = []
    for i in range(d):
        a, b = ws[2 * i], ws[2 * i + 1]
        if a is not None and b is not None:
            second.append((a * dB + b * dB) / 2 - r0)
    if not second:
        return np.zeros(len(sigma))
    # the roughest axis per entry, not the mean over axes: stick-slip makes the response
    # irregular along the parameters that move its resonances (a stiffness) while it stays
    # smooth along others (a damping), and a mean would dilute the first by the second
    return np.sqrt(np.max(np.square(second), axis=0) / 1.5)


def widen(res: Residuals, extra_db: np.ndarray, fits: Sequence[Fit] = ()) -> None:
    """Add ``extra_db`` (one value per entry) to every entry's standard error in
    quadrature; every trial kept by ``res`` and every trial, best point and Jacobian of
    ``fits`` is reweighted."""
    sigma = np.array([x for part in res.entries.sigma for x in part])
    res.add_scatter(extra_db)
    scale = sigma / np.array([x for part in res.entries.sigma for x in part])
    seen = set()
    for fit in fits:
        for t in [fit.best, *fit.trials]:  # the fits' own copies of the trials
            if id(t) not in seen and t.w is not None:
                t.w = t.w * scale
                seen.add(id(t))
        if fit.jacobian is not None and id(fit.jacobian) not in seen:
            fit.jacobian = fit.jacobian * scale[:, None]
            seen.add(id(fit.jacobian))


def widen_for_roughness(res: Residuals, fit: Fit, log: Log = lambda s: None,
                        effects=(), fits: Sequence[Fit] = (),
                        already: np.ndarray | None = None) -> np.ndarray:
    """Add the model's scatter around ``fit``'s optimum (:func:`roughness`, of the model
    with ``effects``) to every entry's standard error, beyond the scatter ``already``
    added (per entry, dB); ``fit`` and ``fits`` are reweighted with every trial kept.
    Returns the scatter per entry now in the errors."""
    rough = roughness(res, fit, effects)
    before = np.zeros_like(rough) if already is None else np.asarray(already, float)
    total = np.maximum(rough, before)
    widen(res, np.sqrt(total**2 - before**2), [fit, *fits])
    log(f"model scatter around {'the calibrated point' if not effects else 'its optimum'}:"
        f" median {float(np.median(rough)) if len(rough) else 0.0:.2f} dB, largest "
        f"{float(np.max(rough, initial=0.0)):.2f} dB")
    return total
