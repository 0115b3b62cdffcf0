"""Add the missing effect at its place and calibrate it jointly with the base parameters: the
augmented model, the augmented study file, and the error trajectory per level, nominal
model -> base parameters recalibrated -> effect added (its nominal values) -> jointly
calibrated. Both calibrations are the global ones of :mod:`sensfw.measure.calibration`, one
search each (two, as ``sensfw calibrate`` runs them, did worse here:
``bench/augment_search.py``); ``budget`` counts simulations (one per point and level), as
for diagnosis."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from ..errors import SensfwError
from ..evaluate import model_with_effects
from ..options import build, describe
from ..plugins import effects as effect_registry
from ..runs import Runner
from ..study import Study
from ..study.edit import add_effect, set_calibration, set_calibration_result
from .calibration import Coordinates
from .diagnose import LOCAL_ONLY, _around, calibrate_hypothesis, two_searches, workers_of
from .hypotheses import Hypothesis, calibration_residuals, neutral_values
from .io import Measurement
from .prediction import fitted_records
from .scatter import widen_for_roughness


def default_budget(n_levels: int) -> int:
    """Simulations of an augmentation when none is given: 100 + 60 per level."""
    return 100 + 60 * n_levels


def augment(study: Study, measurements: Sequence[Measurement], runner: Runner, effect: str,
            attach: str | None = None, start: Mapping[str, float] | None = None,
            base_start: Mapping[str, float] | None = None, budget: int | None = None,
            local: str = "dfols", study_text: str | None = None,
            options: Mapping[str, object] | None = None,
            searches: tuple[int, int] = (1, 1), log=lambda s: None) -> dict:
    """Calibrate ``effect`` at ``attach`` (default: its preferred place) jointly with the
    study's calibration variables. ``start`` (e.g. the values :func:`diagnose` found: base
    variables and effect parameters) and ``base_start`` (diagnose's "parameters only"
    values) are simulated first and seed the calibrations. ``study_text`` (default: the
    study's file) is the text the augmented study is written from (comments and layout
    kept); the result's ``"study_text"`` is the augmented study. ``options`` are the
    effect's own options (``{"elements": 6}`` for ``micro_slip``), checked against its
    declaration and written into the augmented study's effect entry. ``searches``: how
    many searches (1 or 2, :func:`two_searches`) the base variables' calibration and the
    joint one get where they are global (no ``base_start``, no ``start``). One each: over
    the 34 effect cases of ``bench/augment_search.py`` (the true effect at its place, the
    default budget) the joint calibration reached the noise in 29 with one search each,
    26 with two for the base variables, 24 with two for both (``bench/RECOVERY.md``, stop 43)."""
    if len(searches) != 2 or not set(searches) <= {1, 2}:
        raise SensfwError(f"augment: searches must be two of 1 or 2, not {searches!r}")
    if "attach" in (options or {}):  # it silently overrode the place of NAME@PLACE
        raise SensfwError(f"effect {effect}: its place is not an option; give it as "
                          f"{effect}@PLACE")
    eff, problems = build(effect_registry.get(effect), {"attach": attach, **(options or {})})
    if problems:
        raise SensfwError(f"effect {effect}: {describe(problems)}")
    model_with_effects(study, [eff])  # resolves (and checks) where it attaches
    names, source, space, res = calibration_residuals(study, measurements, runner, log)
    n_levels = res.n_levels
    budget = default_budget(n_levels) if budget is None else int(budget)
    q = workers_of(runner)
    base = Coordinates.of(space)
    nominal, _ = res.nominal()

    def search(n, h, points, opts):
        if n == 2:
            return two_searches(res, h, points, opts, log)
        return calibrate_hypothesis(res, h, points, log=log, **opts)

    log(f"recalibrating the base variables {', '.join(names)} ({source})")
    h0 = Hypothesis(None, "", base)
    if base_start is not None:
        given = {k: float(base_start[k]) for k in names if k in base_start}
        if given:
            res.evaluate(None, [{**nominal, **given}], "base start")
    # from a diagnosis's values: refine only (its global search found them)
    h0_points = int(0.35 * budget) // n_levels
    if h0_points < 2 * (len(base) + 1):
        log(f"notice: a budget of {budget} leaves the base variables {h0_points} points at "
            f"{n_levels} level(s), fewer than a design and a local search need (about "
            f"{2 * (len(base) + 1)}; default budget {default_budget(n_levels)})")
    h0.fit = search(searches[0], h0, h0_points,
                    {"q": q, "local": local, **(LOCAL_ONLY if base_start is not None else {})})
    widen_for_roughness(res, h0.fit, log)
    h = Hypothesis(eff, eff.attach, base + Coordinates.of(None, eff.parameters()))
    added = {**h0.fit.values, **{p.name: p.nominal for p in eff.parameters()}}
    if start is not None:
        want = set(h.coords.names)
        missing = sorted(want - set(start))
        if missing:
            raise SensfwError(f"start values for {effect} lack {missing}")
        first = {k: float(start[k]) for k in want}
        (w,) = res.evaluate(h.effects, [first], f"{effect} start")
        if w is None:
            raise SensfwError(f"the model with {h.name} failed at the start values: "
                              f"{res.failures.get(f'{effect} start', '?')}")
    else:
        (h0_cmp,) = res.comparisons(None, [h0.fit.values], "base recalibrated")
        probes = eff.probes(res.output_comparisons(h0_cmp))
        ws = res.evaluate(h.effects, [{**h0.fit.values, **neutral_values(eff), **p}
                                      for p in probes], f"probes {h.name}")
        if all(w is None for w in ws):
            raise SensfwError(f"the model with {h.name} failed at every probe: "
                              f"{res.failures.get(f'probes {h.name}', '?')}")
    left = (budget - res.n_simulations) // n_levels
    points = max(left, 2 * h.k + 4)
    if points > left:
        h.notes.append(f"the budget of {budget} simulations left {max(left, 0)} points for "
                       f"the joint calibration of {h.k} parameters; it ran the least a "
                       f"search needs, {points} ({points * n_levels} simulations)")
        log(f"notice: {h.notes[-1]}")
    log(f"calibrating {h.name} jointly with {', '.join(names)} ({points} points)")
    design = LOCAL_ONLY if start is not None else {"design_box": _around(h0, h),
                                                     "n_design": len(h.own) + 1}
    h.fit = search(searches[1], h, points, {"q": q, "local": local, **design})
    steps = [("nominal model", None, nominal), ("base recalibrated", None, h0.fit.values),
             ("effect added", h.effects, added), ("jointly calibrated", h.effects,
                                                  h.fit.values)]
    comps, trajectory = {}, []
    for label, effects, values in steps:
        (c,) = res.comparisons(effects, [values], label)
        comps[label] = res.output_comparisons(c)
        trajectory.append({"step": label, "error": res.rms_db(c),
                           "error_per_level": res.rms_db_per_level(c),
                           "levels": [m.level for m in measurements],
                           "kinds": res.kinds,
                           "params": dict(values)})
    own = set(h.own)
    result = {"effect": effect, "attach": eff.attach, "variables": names,
              "options": {k: v for k, v in eff.spec().items() if k not in ("name", "attach")},
              "channels": res.channels, "variables_from": source,
              "params": {k: v for k, v in h.fit.values.items() if k in own},
              "base": {k: v for k, v in h.fit.values.items() if k not in own},
              "base_parameters": space.to_parameters(
                  {k: v for k, v in h.fit.values.items() if k in names}),
              "calibration": h.fit.summary(), "trades": h.fit.trades(),
              "uncertainty": h.fit.uncertainty(
                  fitted_records(res.records(), comps["jointly calibrated"])),
              "surrogate": h.fit.info.get("surrogate"), "chi2": h.fit.chi2,
              "notes": h.notes, "trajectory": trajectory,
              "n_simulations": res.n_simulations, "budget": budget,
              "records": res.records(), "kind_weights": res.kind_weights,
              "comparison": {k: [x.to_dict() for x in v] if v else None
                             for k, v in comps.items()},
              "_comparisons": comps}
    text = study_text if study_text is not None else _source_text(study)
    if text is not None:
        result["study_text"] = augmented_study(text, study, result, measurements)
    return result


def _source_text(study: Study) -> str | None:
    path = Path(study.source) if study.source else None
    return path.read_text(encoding="utf-8") if path is not None and path.is_file() else None


def augmented_study(text: str, study: Study, result: Mapping, measurements) -> str:
    """The study file ``text`` with the effect of ``result`` (:func:`augment`) at its place,
    the calibrated parameters as ``[parameters.NAME]`` tables (bounds kept) and
    ``[calibration]`` = the base variables and the effect's parameters, so that a next
    round (diagnose or augment of this study) recalibrates the whole augmented model."""
    name = result["effect"]
    declared = {p.name: p for p in effect_registry.get(name)().parameters()}
    calibrated = {k: {"min": declared[k].min, "nominal": declared[k].clip(v),
                      "max": declared[k].max} for k, v in result["params"].items()}
    for k, v in result.get("base_parameters", {}).items():
        p = study.parameters[k]
        if v != p.nominal:
            calibrated[k] = {"min": p.min, "nominal": p.clip(v), "max": p.max}
    jointly = f" jointly with {', '.join(result['variables'])}" if result.get("variables") \
        else ""
    note = (f"[augmented with {name}@{result['attach']}, calibrated{jointly} against "
            f"{', '.join(m.file for m in measurements)}]")
    text = add_effect(text, name, result["attach"], calibrated, note,
                      options=result.get("options") or None)
    if result.get("variables"):
        text = set_calibration(text, [*result["variables"],
                                      *(k for k in result["params"]
                                        if k not in result["variables"])])
    if result.get("uncertainty") is not None:
        text = set_calibration_result(text, result["uncertainty"])
    return text


def diagnosed_start(path, name: str, attach: str | None = None
                    ) -> tuple[dict, str, dict | None]:
    """The calibrated values (base variables and effect parameters) and the place of effect
    ``name`` (at ``attach``, if given) in a ``diagnose.json``, and the base values of its
    "parameters only" hypothesis: where :func:`augment` starts."""
    import json

    path = Path(path)
    if not path.is_file():
        raise SensfwError(f"--start-from {path}: no such file; give the diagnose.json a "
                          "`sensfw diagnose ... --out DIR` wrote (DIR/diagnose.json)")
    try:
        data = json.loads(path.read_text())
        ranking = data.get("ranking", [])
        h0 = (data.get("parameters_only") or {}).get("params")
        rows = [r for r in ranking
                if r.get("effect") == name and (not attach or r.get("place") == attach)]
    except (OSError, ValueError, AttributeError) as err:
        raise SensfwError(f"{path}: not a readable diagnose.json ({err})") from None
    if not rows:
        raise SensfwError(f"{path}: no ranking entry for effect {name!r}"
                          + (f" at {attach!r}" if attach else ""))
    if not isinstance(rows[0].get("params"), dict) or not rows[0].get("place"):
        raise SensfwError(f"{path}: the entry for {name!r} lacks 'params' or 'place'")
    return rows[0]["params"], rows[0]["place"], h0 if isinstance(h0, dict) else None
