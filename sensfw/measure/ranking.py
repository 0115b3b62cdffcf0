"""Ranking of calibrated hypotheses and the verdict of a diagnosis.

* **BIC** with known variances, ``chi2 + k ln n`` (Schwarz 1978), each hypothesis at the
  optimum of its own global calibration, so that an effect is not credited with what
  "parameters only" reaches at its own optimum (a heavier shaft against a stiffer bearing:
  both fits tie, and BIC then prefers the hypothesis with fewer parameters).
* **Held-out levels** (two or more levels): each level left out in turn, the calibration
  moved by one Gauss-Newton step (at most ``MAX_STEP``) to fit the others, the left-out
  level simulated.
* **The verdict**: the candidate of lowest BIC that beats H0 by ``min_delta_bic`` and
  (with several levels) predicts the held-out levels better; else "parameters" when H0
  explains the measurement to its noise (chi-square test), "none" when it does not. The
  test does not come first: an entry's standard error is the measurement's scatter less
  the nominal model's, and an effect's own distortion (which the nominal model lacks)
  counts in it, so where an effect is missing H0 can pass the test while the effect
  beats it by far (``bench/recovery.py`` seed 2046: H0 chi2 173 for 137 entries, the
  true contact hardening 63). Candidates within
  ``TIE_BIC`` of the winner's BIC (Kass & Raftery 1995: a difference "not worth more than
  a bare mention") are named with it: the measured channels cannot tell them apart.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from . import discrepancy
from .hypotheses import Hypothesis
from .residuals import Residuals

Log = Callable[[str], None]

#: BIC difference under which two hypotheses are named together
TIE_BIC = 2.0
#: largest move (coded, max-norm) of a held-out refit's Gauss-Newton step: a parameter the
#: other levels do not see (a stop's gap below the level that crosses it) would otherwise
#: be thrown across its range by a column of the Jacobian that is all noise
MAX_STEP = 0.1


def heldout(res: Residuals, h: Hypothesis) -> float | None:
    """Mean held-out chi2 per entry (module docstring); ``inf`` if a run failed."""
    fit = h.fit
    J, w = fit.jacobian, fit.best.w
    z = fit.z
    total, count = 0.0, 0
    for lev, sl in enumerate(res.level_slices()):
        keep = np.ones(len(w), bool)
        keep[sl] = False
        values = fit.values
        if J is not None and len(z):
            Jk, wk = J[keep], w[keep]
            A = Jk.T @ Jk
            step = -np.linalg.solve(A + 1e-3 * np.diag(np.maximum(np.diag(A), 1e-12)),
                                    Jk.T @ wk)
            big = float(np.max(np.abs(step), initial=0.0))
            if big > MAX_STEP:  # the Jacobian is local: no further than where it holds
                step *= MAX_STEP / big
            values = {**fit.values, **h.coords.decode(np.clip(z + step, -1, 1))}
        (wl,) = res.evaluate(h.effects, [values], f"held-out level {lev + 1} {h.name}",
                             levels=[lev])
        if wl is None:
            return math.inf
        total += float(np.sum(wl * wl))
        count += len(wl)
    return total / max(count, 1)


def verdict(h0: Hypothesis, calibrated: Sequence[Hypothesis], n: int, min_delta_bic: float,
            n_levels: int) -> tuple[str, str, list[Hypothesis]]:
    """(verdict, reason, the hypotheses it names) — module docstring."""
    bic0 = h0.bic(n)
    ok = [h for h in calibrated
          if h.bic(n) < bic0 - min_delta_bic
          and (n_levels < 2 or h0.heldout is None
               or (h.heldout is not None and h.heldout < h0.heldout))]
    if not ok and discrepancy.fits(h0.fit.best.w, h0.k):
        return "parameters", (f"recalibrating the base parameters explains the measurement "
                              f"to its noise (chi2 {h0.fit.chi2:.1f} for {n} entries)"), []
    if not ok:
        return "none", ("no candidate explains the discrepancy clearly better than the "
                        f"recalibrated parameters (dBIC > {min_delta_bic:g}"
                        + (" and a better held-out level" if n_levels >= 2 else "") + ")"), []
    best = min(ok, key=lambda h: h.bic(n))
    ties = [h for h in ok if h is not best and h.bic(n) - best.bic(n) <= TIE_BIC]
    named = [best, *sorted(ties, key=lambda h: h.bic(n))]
    reason = (f"dBIC {bic0 - best.bic(n):.1f} over the recalibrated parameters"
              + (f"; held-out chi2/entry {best.heldout:.2f} vs {h0.heldout:.2f}"
                 if best.heldout is not None and h0.heldout is not None else ""))
    if len(named) > 1:
        reason += ("; " + ", ".join(h.name for h in named[1:]) + f" within dBIC "
                   f"{TIE_BIC:g} of it: these channels cannot tell them apart")
    trades = [t for t in best.fit.trades() if (t["a"] in best.own) != (t["b"] in best.own)]
    if trades:
        reason += "; " + ", ".join(f"{t['a']} trades against {t['b']} (correlation "
                                   f"{t['correlation']:+.2f})" for t in trades[:2])
    return " or ".join(h.name for h in named), reason, named
