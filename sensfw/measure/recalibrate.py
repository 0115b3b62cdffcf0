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
    fit = two_searches(res, h0, budget // n_levels, opts, log)
    rough = widen_for_roughness(res, fit, log)
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
              "model_scatter_db": float(np.median(rough)) if len(rough) else 0.0,
              "trajectory": trajectory,
              "notes": [n for n in [discrepancy.noise_thd_note(
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
