"""Screening of candidate effects for diagnosis: from which base points each candidate is
tried, at which probes, and where its joint calibration starts (:mod:`sensfw.measure.diagnose`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .calibrate import Evaluation
from .evaluate import Evaluator


def base_points(h0, nominal: Mapping[str, float] | None, extra: int = 1
           ) -> list[dict[str, float]]:
    """Base points to try each candidate from: H0's optimum, the nominal values, and up to
    ``extra`` points of H0's own search far (in coded distance) from its optimum with a chi2
    within three times its best. H0 may have bent the base variables to mimic the missing
    effect (a softer bearing for a heavier shaft); its search passed nearer the true values
    on its way, and from there the effect can show what it explains."""
    fit = h0.fit
    out = [dict(fit.values)]
    if nominal is not None:
        out.append(dict(nominal))
    z_best = fit.z
    pool = [e for e in fit.evaluations if e.w is not None and e.chi2 <= 3 * fit.chi2]
    pool.sort(key=lambda e: -float(np.max(np.abs(h0.coords.code(e.values) - z_best))))
    for e in pool:
        if len(out) >= 2 + extra:
            break
        z = h0.coords.code(e.values)
        if all(np.max(np.abs(z - h0.coords.code(b))) > 0.1 for b in out):
            out.append(dict(e.values))
    return out


def screen(ev: Evaluator, h0, hyps: Sequence, h0_cmp, log,
           nominal: Mapping[str, float] | None = None, keep: int = 6) -> None:
    """Each candidate at its probes (the neutral values make it vanish) from the base points
    of :func:`base_points`, and at the point the linearised joint fit predicts from H0: the base
    variables moved by H0's Jacobian and the effect scaled along the probe's direction, so
    that they share what they explain (``min |w0 + J0 dtheta + c d|``, ``0 <= c <= 2``).
    The candidate's score is the lowest chi2 simulated; its best point starts its joint
    calibration. Costs about ten simulations per candidate.

    More than ``keep`` candidates (every effect at every place: 44 on the shaft model) get a
    first look of two simulations each, the middle probe from H0's optimum and its
    linearised joint fit, and only the ``keep`` best of that look are screened fully."""
    bases = base_points(h0, nominal)
    for h in hyps:
        h.screened = []
    if len(hyps) > keep:
        for h in hyps:
            probes = h.effect.probes(h0_cmp)
            _probe(ev, h0, h, bases[:1], probes[len(probes) // 2:len(probes) // 2 + 1])
        hyps = sorted(hyps, key=lambda h: h.screen_chi2)[:keep]
        log(f"  the {keep} best of a first look (one probe from H0, its linearised fit): "
            f"{', '.join(h.name for h in hyps)}")
    for h in hyps:
        _probe(ev, h0, h, bases, h.effect.probes(h0_cmp))
        if all(e.w is None for e in h.screened):
            why = ev.failures.get(f"screen {h.name}", "?")
            h.notes.append(f"every run of the screen failed: {why}")
            log(f"  screen {h.name}: every run failed ({why})")
            continue
        log(f"  screen {h.name}: chi2 {h0.fit.chi2:.4g} -> {h.screen_chi2:.4g}")


def _probe(ev: Evaluator, h0, h, bases: Sequence[Mapping[str, float]],
           probes: Sequence[Mapping[str, float]]) -> None:
    """``h`` at ``probes`` from ``bases`` and at the linearised joint fit of its best probe
    from H0's optimum (:func:`screen`); points ``h`` was already screened at are not run
    again. Updates ``h.screened``, ``h.screen_best`` and ``h.screen_chi2``."""
    base = h0.fit.values
    w0 = h0.fit.best.w
    J = h0.fit.jacobian
    neutral = neutral_values(h.effect)
    done = h.screened

    def run(points: list[dict]) -> list[Evaluation]:
        new = [p for p in points if all(p != e.values for e in done)]
        if new:  # one batch per hypothesis (its effect spec is part of every run)
            ws = ev.evaluate(h.spec, new, f"screen {h.name}")
            done.extend(Evaluation(v, w) for v, w in zip(new, ws, strict=True))
        return [next(e for e in done if e.values == p) for p in points]

    evaluated = run([{**b, **neutral, **probe} for b in bases for probe in probes])
    from_h0 = [(p, e) for p, e in zip(probes, evaluated[:len(probes)], strict=True)
               if e.w is not None]
    predicted = []
    for probe, e in sorted(from_h0, key=lambda pe: pe[1].chi2)[:1]:  # the best probe
        d = e.w - w0
        A = np.column_stack([J, d]) if J is not None and J.size else d[:, None]
        x, *_ = np.linalg.lstsq(A, -w0, rcond=None)
        c = float(np.clip(x[-1], 0.0, 2.0))
        z = h0.coords.code(base) + (x[:-1] if J is not None and J.size else 0.0)
        values = {**h0.coords.decode(np.clip(z, -1, 1)), **{
            k: clip_to(h.coords.axes[h.coords.names.index(k)],
                       neutral[k] + c * (v - neutral[k])) for k, v in probe.items()}}
        predicted.append({**neutral, **probe, **values})
    if predicted:
        run(predicted)
    best = min([Evaluation({**base, **neutral}, w0), *done], key=lambda e: e.chi2)
    h.screen_chi2, h.screen_best = best.chi2, best


def other_start(h0, h) -> Evaluation | None:
    """The best screened point of ``h`` whose base values are far (0.2 coded) from those of
    its calibrated point and of the point its calibration started from (the same start
    again would repeat the same path)."""
    base = h0.coords
    seen = [base.code(h.fit.values), base.code(h.fit.evaluations[0].values)]
    far = [e for e in h.screened if e.w is not None and
           all(np.max(np.abs(base.code(e.values) - z)) > 0.2 for z in seen)]
    return min(far, key=lambda e: e.chi2) if far else None


def clip_to(axis, value: float) -> float:
    return float(np.clip(value, axis.low, axis.high))


def neutral_values(effect) -> dict[str, float]:
    """Effect parameters at their nominal values overridden by the neutral ones."""
    return {**{p.name: p.nominal for p in effect.parameters()}, **effect.neutral}


