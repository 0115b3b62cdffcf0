"""Add the missing effect at its place and calibrate it jointly with the base parameters: the
augmented model and the error trajectory per level, nominal model -> base parameters
recalibrated -> effect added (its nominal values) -> jointly calibrated."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from ..errors import SensfwError
from ..plugins import effects as effect_registry
from ..runs import Runner
from ..study import Study
from . import discrepancy
from .calibrate import Coordinates, Evaluation, calibrate
from .diagnose import (
    Hypothesis,
    Log,
    _calibrate_candidate,
    calibration_variables,
    widen_for_roughness,
)
from .evaluate import Evaluator
from .io import Measurement
from .screening import neutral_values, screen
from .synthetic import model_with_effects


def augment(study: Study, measurements: Sequence[Measurement], runner: Runner, effect: str,
            attach: str | None = None, start: Mapping[str, float] | None = None,
            base_start: Mapping[str, float] | None = None, budget: int = 200,
            log: Log = lambda s: None) -> dict:
    """Calibrate ``effect`` at ``attach`` (default: its preferred place) jointly with the
    study's calibration variables. ``start`` (e.g. the values :func:`diagnose` found: base
    variables and effect parameters) replaces the screening of the effect's probes;
    ``base_start`` (e.g. diagnose's "parameters only" values) is where the base variables'
    own recalibration starts when it is better than their nominal values."""
    eff = effect_registry.get(effect)(attach=attach)
    model_with_effects(study, [eff])  # resolves (and checks) where it attaches
    names, source = calibration_variables(study, runner, log)
    space = study.calibration_space(names)
    ev = Evaluator(study, measurements, runner, space)
    base = Coordinates.of(space)
    nominal = space.nominal_row()
    (nominal_cmp,) = ev.comparisons([ev.variant(None, nominal)], "nominal model")
    if nominal_cmp is None:
        raise SensfwError("the study's model failed at the measured level(s)")
    log(f"recalibrating the base variables {', '.join(names)} ({source})")
    h0 = Hypothesis(None, "", base)
    first = Evaluation(nominal, ev.weighted(nominal_cmp))
    if base_start is not None:
        given = {k: float(base_start[k]) for k in names if k in base_start}
        if given:
            point = {**nominal, **given}
            (w,) = ev.evaluate(None, [point], "base start")
            first = min(first, Evaluation(point, w), key=lambda e: e.chi2)
    h0.fit = calibrate(lambda pts: ev.evaluate(None, pts, "base calibration"), base, first,
                       budget=budget // 3, log=log)
    widen_for_roughness(ev, h0.fit, log)
    h = Hypothesis(eff, eff.attach, Coordinates(base.axes + Coordinates.of(
        None, eff.parameters()).axes))
    added = {**h0.fit.values, **{p.name: p.nominal for p in eff.parameters()}}
    if start is not None:
        want = set(h.coords.names)
        missing = sorted(want - set(start))
        if missing:
            raise SensfwError(f"start values for {effect} lack {missing}")
        first = {k: float(start[k]) for k in want}
        (w,) = ev.evaluate(h.spec, [first], f"{effect} start")
        if w is None:
            raise SensfwError(f"the model with {h.name} failed at the start values: "
                              f"{ev.failures.get(f'{effect} start', '?')}")
        h.screen_best = min([Evaluation(first, w),
                             Evaluation({**h0.fit.values, **neutral_values(eff)}, h0.fit.best.w)],
                            key=lambda e: e.chi2)
    else:
        (h0_cmp,) = ev.comparisons([ev.variant(None, h0.fit.values)], "base recalibrated")
        screen(ev, h0, [h], ev.output_comparisons(h0_cmp), log)
        if all(e.w is None for e in h.screened):
            raise SensfwError(f"the model with {h.name} failed at every probe: "
                              f"{ev.failures.get(f'screen {h.name}', '?')}")
    log(f"calibrating {h.name} jointly with {', '.join(names)}")
    _calibrate_candidate(ev, h0, h, budget // 2, log)
    steps = [("nominal model", None, nominal), ("base recalibrated", None, h0.fit.values),
             ("effect added", h.spec, added), ("jointly calibrated", h.spec, h.fit.values)]
    comps = {}
    trajectory = []
    for label, spec, values in steps:
        (c,) = ev.comparisons([ev.variant(spec, values)], label)
        comps[label] = ev.output_comparisons(c)
        trajectory.append({"step": label, "error": ev.rms_db(c),
                           "error_per_level": ev.rms_db_per_level(c),
                           "levels": [m.level for m in measurements],
                           "params": dict(values)})
    own = {p.name for p in eff.parameters()}
    summary = h.fit.summary()
    return {"effect": effect, "attach": eff.attach, "variables": names, "channels": ev.channels,
            "variables_from": source,
            "params": {k: v for k, v in h.fit.values.items() if k in own},
            "base": {k: v for k, v in h.fit.values.items() if k not in own},
            "base_parameters": space.to_parameters(
                {k: v for k, v in h.fit.values.items() if k in names}),
            "calibration": summary, "notes": h.notes, "trajectory": trajectory,
            "n_simulations": ev.n_simulations,
            "comparison": {k: [x.to_dict() for x in v] if v else None
                           for k, v in comps.items()},
            "_comparisons": comps}


def recalibrate(study: Study, measurements: Sequence[Measurement], runner: Runner,
                budget: int = 120, log: Log = lambda s: None) -> dict:
    """Calibrate the study's base variables alone (hypothesis "parameters" of diagnosis):
    the calibrated values with intervals and flags, and the error per level before and
    after."""
    names, source = calibration_variables(study, runner, log)
    space = study.calibration_space(names)
    ev = Evaluator(study, measurements, runner, space)
    base = Coordinates.of(space)
    nominal = space.nominal_row()
    (nominal_cmp,) = ev.comparisons([ev.variant(None, nominal)], "nominal model")
    if nominal_cmp is None:
        raise SensfwError("the study's model failed at the measured level(s)")
    log(f"calibrating {', '.join(names)} ({source})")
    fit = calibrate(lambda pts: ev.evaluate(None, pts, "calibration"), base,
                    Evaluation(nominal, ev.weighted(nominal_cmp)), budget=budget, log=log)
    scatter = widen_for_roughness(ev, fit, log)
    (cal_cmp,) = ev.comparisons([ev.variant(None, fit.values)], "calibrated")
    trajectory = [{"step": label, "error": ev.rms_db(c), "error_per_level":
                   ev.rms_db_per_level(c), "levels": [m.level for m in measurements],
                   "params": dict(values)}
                  for label, c, values in (("nominal model", nominal_cmp, nominal),
                                           ("calibrated", cal_cmp, fit.values))]
    return {"variables": names, "variables_from": source, "channels": ev.channels,
            "params": fit.values, "base_parameters": space.to_parameters(fit.values),
            "calibration": fit.summary(), "chi2": fit.chi2, "n_entries": ev.entries.size(),
            "fits_noise": discrepancy.fits(fit.best.w, len(base)),
            "model_scatter_db": scatter,
            "trajectory": trajectory, "n_simulations": ev.n_simulations,
            "comparison": {"nominal model": [c.to_dict() for c in
                                             ev.output_comparisons(nominal_cmp)],
                           "calibrated": [c.to_dict() for c in
                                          ev.output_comparisons(cal_cmp)]},
            "_comparisons": {"nominal model": ev.output_comparisons(nominal_cmp),
                             "calibrated": ev.output_comparisons(cal_cmp)}}
