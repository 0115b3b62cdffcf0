"""Calibrate a study's base variables alone (hypothesis "parameters" of diagnosis, the
``sensfw calibrate`` command): the global calibration of :mod:`sensfw.measure.calibration`
in two searches (:func:`~sensfw.measure.diagnose.two_searches`), the calibrated values
with intervals and flags, the error per level before and after, and the calibrated study
file."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..runs import Runner
from ..study import Study
from ..study.edit import set_calibration, set_calibration_result, set_nominals
from . import discrepancy
from .augment import _source_text
from .calibration import Coordinates
from .diagnose import LOCAL_ONLY, two_searches, workers_of
from .hypotheses import Hypothesis, calibration_residuals
from .io import Measurement
from .prediction import fitted_records
from .scatter import widen_for_roughness


def default_budget(n_levels: int) -> int:
    """Simulations of a calibration when none is given: 60 points, each at every level."""
    return 60 * n_levels


def least_points(k: int) -> int:
    """Points below which :func:`~sensfw.measure.diagnose.two_searches` cannot search
    globally over ``k`` variables: each search needs a design of ``2 k + 1`` points (the
    first) or a start, and a local least-squares search of at least ``k + 2`` (DFO-LS's
    interpolation set and one step)."""
    return 2 * (2 * k + 1) + 2 * (k + 2)


def small_budget_note(budget: int, points: int, k: int, n_levels: int,
                      global_phase: bool = True) -> str | None:
    """A line saying that ``points`` (``budget`` simulations at ``n_levels`` levels) are
    fewer than a global calibration of ``k`` variables needs (:func:`least_points`): the
    result is then a short local search, and its intervals describe the point it stopped
    at, not the box. None where the budget suffices or no global search was asked for."""
    need = least_points(k)
    if not global_phase or k == 0 or points >= need:
        return None
    return (f"a budget of {budget} simulations is {points} points at {n_levels} level(s), "
            f"fewer than a global search over {k} variables needs (about {need}, "
            f"{need * n_levels} simulations): the result is a short local search, and its "
            f"intervals are those of the point it stopped at (default budget "
            f"{default_budget(n_levels)}).")


def scatter_note(unwidened: np.ndarray | None, widened: np.ndarray | None,
                 rough_db: np.ndarray, k: int) -> str | None:
    """A line saying that the calibrated point passes the noise's test only once the
    model's own scatter there (:func:`~sensfw.measure.scatter.roughness`, ``rough_db`` per
    entry) is counted: a rough spot of the response widens its own errors, so a search that
    stopped there can look as good as the optimum (``bench/RECOVERY.md``; a probe at 13
    points per level: chi2 966 for 121 entries at the stopping point, 69 at the true values,
    96 after widening). None where the point fits without it, or fails with it."""
    if unwidened is None or widened is None:
        return None
    if discrepancy.fits(unwidened, k) or not discrepancy.fits(widened, k):
        return None
    return (f"the calibrated point fits the noise only with the model's own scatter there "
            f"counted (median {float(np.median(rough_db)):.2f} dB, largest "
            f"{float(np.max(rough_db, initial=0.0)):.2f} dB): without it chi2 "
            f"{float(unwidened @ unwidened):.4g} for {len(unwidened)} entries. A rough spot "
            "can hide a better optimum elsewhere; a larger budget searches more of the box.")


def recalibrate(study: Study, measurements: Sequence[Measurement], runner: Runner,
                budget: int | None = None, local: str = "dfols", global_phase: bool = True,
                study_text: str | None = None, log=lambda s: None) -> dict:
    """Calibrate the study's base variables alone (module docstring); ``budget`` counts
    simulations (one per point and level; default 60 points). ``global_phase=False``
    leaves out the design and the surrogate search: the local least squares from the
    study's nominal values (a study a calibration already wrote, with a variable added)."""
    names, source, space, res = calibration_residuals(study, measurements, runner, log)
    n_levels = res.n_levels
    budget = default_budget(n_levels) if budget is None else int(budget)
    base = Coordinates.of(space)
    nominal, nominal_cmp = res.nominal()
    log(f"calibrating {', '.join(names)} ({source}), {budget} simulations")
    h0 = Hypothesis(None, "", base)
    opts = {"q": workers_of(runner), "local": local, **({} if global_phase else LOCAL_ONLY)}
    points = budget // n_levels
    short = small_budget_note(budget, points, len(base), n_levels, global_phase)
    if short:
        log(f"notice: {short}")
    fit = two_searches(res, h0, points, opts, log)
    unwidened = fit.best.w.copy() if fit.best.w is not None else None
    rough = widen_for_roughness(res, fit, log)
    masked = scatter_note(unwidened, fit.best.w, rough, len(base))
    (cal_cmp,) = res.comparisons(None, [fit.values], "calibrated")
    trajectory = [{"step": label, "error": res.rms_db(c), "error_per_level":
                   res.rms_db_per_level(c), "levels": [m.level for m in measurements],
                   "kinds": res.kinds,
                   "params": dict(values)}
                  for label, c, values in (("nominal model", nominal_cmp, nominal),
                                           ("calibrated", cal_cmp, fit.values))]
    result = {"variables": names, "variables_from": source, "channels": res.channels,
              "params": fit.values, "base_parameters": space.to_parameters(fit.values),
              "calibration": fit.summary(), "trades": fit.trades(),
              "uncertainty": fit.uncertainty(
                  fitted_records(res.records(), res.output_comparisons(cal_cmp))),
              "surrogate": fit.info.get("surrogate"), "chi2": fit.chi2,
              "n_entries": res.entries.size(),
              "fits_noise": discrepancy.fits(fit.best.w, len(base)),
              "fits_noise_without_scatter": (None if unwidened is None else
                                             discrepancy.fits(unwidened, len(base))),
              "model_scatter_db": float(np.median(rough)) if len(rough) else 0.0,
              "trajectory": trajectory,
              "notes": [n for n in [short, masked, discrepancy.noise_thd_note(
                  cal_cmp, res.entries, fit.best.w, res.channels)] if n],
              "n_simulations": res.n_simulations, "budget": budget,
              "records": res.records(), "kind_weights": res.kind_weights,
              "comparison": {"nominal model": [c.to_dict() for c in
                                               res.output_comparisons(nominal_cmp)],
                             "calibrated": [c.to_dict() for c in
                                            res.output_comparisons(cal_cmp)]},
              "_comparisons": {"nominal model": res.output_comparisons(nominal_cmp),
                               "calibrated": res.output_comparisons(cal_cmp)}}
    text = study_text if study_text is not None else _source_text(study)
    if text is not None:
        values = {k: study.parameters[k].clip(v)
                  for k, v in result["base_parameters"].items()
                  if v != study.parameters[k].nominal}
        text = set_nominals(text, values, {k: (study.parameters[k].min,
                                               study.parameters[k].max) for k in values})
        text = set_calibration(text, names)
        if result["uncertainty"] is not None:
            text = set_calibration_result(text, result["uncertainty"])
        result["study_text"] = text
    return result
