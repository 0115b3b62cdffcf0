"""Checks of a study file before anything runs, as pure functions of the parsed file (and of
what the study resolved from it: the model's parameters and sensors, the excitation).

Every problem is returned at its dotted path
(``stages[1].design_options.levelz: unknown option; known: levels``), all at once. Every
design, scorer and surrogate the study names is built with its options through the one
check of every plugin kind (:func:`plugin_problems`, :mod:`sensfw.options`); scorers are
also checked against the study's excitation (an FRF band above Nyquist or outside the
sweep), designs against the stage's design space where its variables are known before the
run.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from ..errors import OptionError, SensfwError, UnknownPluginError
from ..options import Problem, build
from ..params import DesignSpace, ParameterSet, spaced
from .schema import ParameterOverride, StageSpec
from .units import to_unit

Problems = list[tuple[str, str]]
#: a parameter's bound overrides: ``{name: {"min": ..., "nominal": ..., "max": ...}}``
Bounds = dict[str, dict[str, float]]


def bound_overrides(overrides: Mapping[str, ParameterOverride], declared: ParameterSet,
                    prefix: str, accepted: ParameterSet | None = None,
                    model: str = "") -> tuple[Bounds, Problems]:
    """The overrides of ``declared`` parameters in their units, and every problem at
    ``prefix.<parameter>[.field]`` (an unknown parameter, a value that does not convert, a
    min above the max, a nominal outside the bounds, a value outside the range the
    ``model`` accepts, its ``accepted`` parameters' bounds)."""
    problems: Problems = []
    changes: Bounds = {}
    for name, ov in overrides.items():
        if name not in declared:
            problems.append((f"{prefix}.{name}", f"unknown parameter; the model has "
                                                 f"{', '.join(declared)}"))
            continue
        p = declared[name]
        vals = {}
        for field_name in ("nominal", "min", "max"):
            raw = getattr(ov, field_name)
            if raw is None:
                continue
            try:
                vals[field_name] = to_unit(raw, p.unit)
            except ValueError as err:
                problems.append((f"{prefix}.{name}.{field_name}", str(err)))
                continue
            if not math.isfinite(vals[field_name]):
                problems.append((f"{prefix}.{name}.{field_name}",
                                 f"{raw!r} is not a finite number"))
                del vals[field_name]
        lo = vals.get("min", p.min)
        hi = vals.get("max", p.max)
        nom = vals.get("nominal", p.nominal)
        if lo > hi:
            problems.append((f"{prefix}.{name}.max",
                             f"max {hi:g}{spaced(p.unit)} is below min {lo:g}{spaced(p.unit)}"))
        elif not lo <= nom <= hi:
            problems.append((f"{prefix}.{name}.nominal",
                             f"nominal {nom:g}{spaced(p.unit)} outside "
                             f"[{lo:g}, {hi:g}]{spaced(p.unit)}"))
        if accepted is not None and name in accepted:  # the model refuses values outside
            a = accepted[name]
            told = {path for path, _ in problems}
            problems += [(f"{prefix}.{name}.{field_name}",
                          f"{v:g}{spaced(a.unit)} is outside the range the model {model} "
                          f"accepts, [{a.min:g}, {a.max:g}]{spaced(a.unit)}")
                         for field_name, v in vals.items() if not a.min <= v <= a.max
                         and f"{prefix}.{name}.{field_name}" not in told]
        changes[name] = vals
    return changes, problems


def _at(where: str, problems: list[Problem]) -> Problems:
    """Problems of a plugin's options at their dotted paths under ``where``."""
    return [(f"{where}.{opt}" if opt else where, msg) for opt, msg in problems]


def plugin_problems(registry, name: str, options: Mapping[str, Any], where: str,
                    name_at: str | None = None) -> tuple[Any, Problems]:
    """``(plugin or None, problems)``: the plugin registered as ``name`` built with
    ``options`` (:func:`sensfw.options.build`, the one check of every plugin kind), every
    problem at its path under ``where`` (an unknown name at ``name_at``, default
    ``where``)."""
    try:
        cls = registry.get(name)
    except UnknownPluginError as err:
        return None, [(name_at or where, str(err))]
    plugin, found = build(cls, options)
    return plugin, _at(where, found)


def _selected_design(design, st: StageSpec, where: str, space, variables: Sequence[str],
                     stages: Sequence[StageSpec]) -> Problems:
    """A stage on an earlier stage's selection: its design at every count of variables the
    selection can give (1 to the earlier stage's ``max_variables`` or its variable count);
    a problem only where no count fits (``box_behnken``, 3 variables at least, after a
    selection of at most 2), so a study is not refused for a selection it may not make.
    Not checked after a grouped screen (its selection counts members, not groups)."""
    ref = st.variables.split(":", 1)[1]
    src = next((s for s in stages if s.name == ref), None)
    if src is None or src.select is None or src.groups or not variables:
        return []
    most = len(variables) if src.variables == "all" else len(src.variables)
    most = min(src.select.max_variables or most, most, len(variables))
    last = None
    for k in range(1, most + 1):
        try:
            design.n_runs(space(list(variables[:k])))
            return []
        except SensfwError as err:
            last = err
    if last is None:
        return []
    return [(f"{where}.design", f"{last} (this stage takes the at most {most} variable(s) "
                                f"that stage {ref!r} selects)")]


def _design(st: StageSpec, where: str, space: Callable[[list[str]], DesignSpace] | None,
            variables: Sequence[str], stages: Sequence[StageSpec] | None = None) -> Problems:
    """The stage's design and its options; its run count where the space is known (the
    stage's variables are not taken from an earlier stage)."""
    from ..plugins import designs

    design, found = plugin_problems(designs, st.design, st.design_options,
                                    f"{where}.design_options", name_at=f"{where}.design")
    if found or space is None:
        return found
    if isinstance(st.variables, str) and st.variables.startswith("selected:"):
        return _selected_design(design, st, where, space, variables, stages or [])
    names = list(variables) if st.variables == "all" else list(st.variables)
    if not set(names) <= set(variables):
        return []  # unknown variables are reported at stages[i].variables
    try:
        design.n_runs(space(names))
    except OptionError as err:  # an option that does not fit the stage's variables
        return [(f"{where}.design_options.{opt}" if opt else f"{where}.design", msg)
                for opt, msg in err.problems]
    except SensfwError as err:
        return [(f"{where}.design", str(err))]
    return []


def _scorers(st: StageSpec, where: str, excitation, sensors: Sequence[str] | None
             ) -> tuple[Problems, list[str]]:
    from ..plugins import scorers

    problems: Problems = []
    labels = []
    for j, sc in enumerate(st.scorers):
        at = f"{where}.scorers[{j}]"
        scorer, found = plugin_problems(scorers, sc.name, sc.options(), at, name_at=f"{at}.name")
        problems += found
        if scorer is not None and excitation is not None:
            try:
                scorer.check_excitation(excitation)
            except SensfwError as err:
                opt = getattr(err, "option", None)
                problems.append((f"{at}.{opt}" if opt else at, str(err)))
        if sc.channel is not None and sensors is not None and \
                sc.channel not in (*sensors, "force"):
            problems.append((f"{at}.channel", f"unknown channel {sc.channel!r}; the model "
                                              f"has {', '.join(sensors)}"))
        if sc.key in labels:
            problems.append((f"{at}.label", f"duplicate scorer label {sc.key!r}"))
        labels.append(sc.key)
    return problems, labels


def _surrogates(st: StageSpec, where: str) -> Problems:
    from ..plugins import surrogates

    problems: Problems = []
    seen = []
    for j, sur in enumerate(st.surrogates):
        at = f"{where}.surrogates[{j}]"
        problems += plugin_problems(surrogates, sur.name, sur.options(), at)[1]
        if sur.key in seen:
            problems.append((f"{at}.label", f"duplicate surrogate label {sur.key!r}"))
        seen.append(sur.key)
    return problems


def _variables(st: StageSpec, i: int, stages: Sequence[StageSpec],
               variables: Sequence[str]) -> Problems:
    where = f"stages[{i}].variables"
    names = [s.name for s in stages]
    if isinstance(st.variables, str) and st.variables.startswith("selected:"):
        ref = st.variables.split(":", 1)[1]
        if ref not in names[:i]:
            return [(where, f"no earlier stage named {ref!r}")]
        if stages[names.index(ref)].select is None:
            return [(where, f"stage {ref!r} has no [select] to take variables from")]
    elif isinstance(st.variables, list) and variables:
        return [(where, f"unknown design variable {v!r}; known: "
                        f"{', '.join(sorted(variables))}")
                for v in st.variables if v not in variables]
    return []


def check_stages(stages: Sequence[StageSpec], *, parameters: ParameterSet | None,
                 groups: Mapping[str, Sequence[str]], excitation=None,
                 sensors: Sequence[str] | None = None, accepted: ParameterSet | None = None,
                 model: str = "") -> tuple[Problems, dict[str, Bounds]]:
    """Every problem of the study's ``stages`` and each stage's bound overrides (by stage
    name), given what the study resolved: its ``parameters`` (None when they did not
    resolve), its ``groups`` of parameters into design variables, its ``excitation``, the
    model's ``sensors`` (None: no model) and the parameters' ranges the ``model`` accepts
    (``accepted``)."""
    problems: Problems = []
    stage_bounds: dict[str, Bounds] = {}
    names = [s.name for s in stages]
    variables = [] if parameters is None else \
        DesignSpace.from_parameters(parameters, groups).names
    for i, st in enumerate(stages):
        where = f"stages[{i}]"
        if names.count(st.name) > 1:
            problems.append((f"{where}.name", f"duplicate stage name {st.name!r}"))
        space = None
        if parameters is not None:
            bounds, found = bound_overrides(st.bounds, parameters, f"{where}.bounds",
                                            accepted, model)
            stage_bounds[st.name] = bounds
            problems += found
            if not found:  # the stage's space is known (its variables permitting)
                def space(select, bounds=bounds):
                    return DesignSpace.from_parameters(parameters, groups, select=select,
                                                       bounds=bounds)
        found, labels = _scorers(st, where, excitation, sensors)
        problems += found
        problems += _surrogates(st, where)
        if (st.select is not None and st.select.by is not None and st.select.by not in labels
                and st.select.by.split(".", 1)[0] not in labels):  # "label.key": one value
            problems.append((f"{where}.select.by", f"no scorer labelled {st.select.by!r} "
                                                   f"in this stage ({', '.join(labels)})"))
        problems += _variables(st, i, stages, variables)
        problems += _design(st, where, space, variables, stages)
    return problems, stage_bounds
