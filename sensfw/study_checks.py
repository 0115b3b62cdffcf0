"""Checks of a study's stages before anything runs: every design, scorer and surrogate the
study names is built with its options, and every problem is reported at once at its dotted
path (``stages[1].design_options.levelz: unknown option; known: levels``).

Options are checked one by one (a plugin built with that option alone), so two bad options
give two problems; a problem that only the options together have (``trajectories`` and
``optimal_trajectories`` of Morris) is reported at the options' path. Scorers are also
checked against the study's excitation (an FRF band above Nyquist or outside the sweep),
designs against the stage's design space where its variables are known before the run.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .errors import SensfwError, UnknownPluginError

if TYPE_CHECKING:  # pragma: no cover
    from .study import StageSpec, Study

Problems = list[tuple[str, str]]


def _message(err: Exception) -> str:
    return str(err) if isinstance(err, SensfwError) else f"invalid value ({err})"


def option_problems(build: Callable[..., Any], options: dict[str, Any],
                    known: list[str]) -> list[tuple[str | None, str]]:
    """(option or None, message) for every problem of ``options``: unknown keys (listing
    ``known``), then each option alone through ``build(**{key: value})``, then all together.
    Returns the built plugin's problems only; ``build`` must raise on a bad option."""
    out: list[tuple[str | None, str]] = [
        (k, f"unknown option; known: {', '.join(known) or '(none)'}")
        for k in options if k not in known]
    given = {k: v for k, v in options.items() if k in known}
    # any exception of a plugin's constructor is a problem of the options it was given
    # (third-party plugins may not raise OptionError on a value of the wrong type)
    for key, value in given.items():
        try:
            build(**{key: value})
        except Exception as err:
            out.append((key, _message(err)))
    if not out:
        try:
            build(**given)
        except Exception as err:
            out.append((getattr(err, "option", None), _message(err)))
    return out


def _at(where: str, problems: list[tuple[str | None, str]]) -> Problems:
    return [(f"{where}.{opt}" if opt else where, msg) for opt, msg in problems]


def _design(study: Study, st: StageSpec, where: str, all_vars: set, problems: Problems):
    from .plugins import designs

    try:
        cls = designs.get(st.design)
    except UnknownPluginError as err:
        problems.append((f"{where}.design", str(err)))
        return
    found = option_problems(cls, st.design_options, sorted(cls.defaults))
    problems += _at(f"{where}.design_options", found)
    if found or study.parameters is None:
        return
    # the space is known before the run unless the variables come from an earlier stage
    if isinstance(st.variables, list) and not set(st.variables) <= all_vars:
        return
    if isinstance(st.variables, str) and st.variables.startswith("selected:"):
        return
    try:
        names = study.variable_names() if st.variables == "all" else list(st.variables)
        cls(**st.design_options).n_runs(study.space(st, names))
    except SensfwError as err:
        problems.append((f"{where}.design", str(err)))
    except Exception:  # a bad bound override is reported at its own path
        pass


def _scorers(study: Study, st: StageSpec, where: str, problems: Problems) -> list[str]:
    from .plugins import scorers

    labels = []
    for j, sc in enumerate(st.scorers):
        at = f"{where}.scorers[{j}]"
        try:
            cls = scorers.get(sc.name)
        except UnknownPluginError as err:
            problems.append((f"{at}.name", str(err)))
            cls = None
        if cls is not None:
            found = option_problems(cls, sc.options(), sorted(cls.defaults))
            problems += _at(at, found)
            if not found and study.excitation is not None:
                try:
                    cls(**sc.options()).check_excitation(study.excitation)
                except Exception as err:
                    opt = getattr(err, "option", None)
                    problems.append((f"{at}.{opt}" if opt else at, _message(err)))
        if sc.channel is not None and study.model is not None and \
                sc.channel not in (*study.model.sensors, "force"):
            problems.append((f"{at}.channel", f"unknown channel {sc.channel!r}; the model "
                                              f"has {', '.join(study.model.sensors)}"))
        if sc.key in labels:
            problems.append((f"{at}.label", f"duplicate scorer label {sc.key!r}"))
        labels.append(sc.key)
    return labels


def _surrogates(st: StageSpec, where: str, problems: Problems) -> None:
    from .plugins import surrogates
    from .surrogates.base import option_problems as surrogate_problems

    seen = []
    for j, sur in enumerate(st.surrogates):
        at = f"{where}.surrogates[{j}]"
        try:
            cls = surrogates.get(sur.name)
        except UnknownPluginError as err:
            problems.append((at, str(err)))
        else:
            problems += _at(at, surrogate_problems(cls, sur.options()))
        if sur.key in seen:
            problems.append((f"{at}.label", f"duplicate surrogate label {sur.key!r}"))
        seen.append(sur.key)


def check_stages(study: Study, problems: Problems) -> None:
    """Append every problem of ``study``'s stages to ``problems``; record each stage's bound
    overrides in ``study.stage_bounds``."""
    names = [s.name for s in study.spec.stages]
    all_vars = set(study.variable_names())
    for i, st in enumerate(study.spec.stages):
        where = f"stages[{i}]"
        if names.count(st.name) > 1:
            problems.append((f"{where}.name", f"duplicate stage name {st.name!r}"))
        if study.parameters is not None:
            changes, _ = study._overrides(st.bounds, study.parameters, f"{where}.bounds",
                                          problems)
            study.stage_bounds[st.name] = changes
        labels = _scorers(study, st, where, problems)
        _surrogates(st, where, problems)
        if st.select is not None and st.select.by is not None and st.select.by not in labels:
            problems.append((f"{where}.select.by", f"no scorer labelled {st.select.by!r} "
                                                   f"in this stage ({', '.join(labels)})"))
        if isinstance(st.variables, str) and st.variables.startswith("selected:"):
            ref = st.variables.split(":", 1)[1]
            if ref not in names[:i]:
                problems.append((f"{where}.variables", f"no earlier stage named {ref!r}"))
            elif study.spec.stages[names.index(ref)].select is None:
                problems.append((f"{where}.variables",
                                 f"stage {ref!r} has no [select] to take variables from"))
        elif isinstance(st.variables, list):
            for v in st.variables:
                if all_vars and v not in all_vars:
                    problems.append((f"{where}.variables",
                                     f"unknown design variable {v!r}; known: "
                                     f"{', '.join(sorted(all_vars))}"))
        _design(study, st, where, all_vars, problems)
