"""Declared options: one contract for every plugin kind (designs, scorers, surrogates, models,
effects).

A plugin declares its options in ``Options``, a :class:`PluginOptions` (pydantic) model: one
field per option with its type, its range (``Field(ge=...)``, ``Literal[...]``, the strict
types below) and, in ``description``, what it accepts, which the messages quote
(``levels must be an integer >= 2 or a list of them, got 1``). A constraint between options
is a ``model_validator`` that raises :class:`~sensfw.errors.OptionError` naming the option.
:func:`option_problems` checks options against the declaration and reports every problem at
once; :func:`build` also makes the plugin, whose constructor may find more (a model resolves
its effects); :func:`make` is that for a registered name, raising the problems. Every command
checks a study's plugins through :func:`build` before its first simulation
(:mod:`sensfw.study.checks`).

A plugin without ``Options`` (a third-party one) has untyped options: the keys of its
``defaults`` dict (designs, scorers: constructors that take ``**options``) or its
constructor's keyword arguments (surrogates, models, effects); unknown keys are still
reported, and whatever its constructor raises is a problem of its options.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Mapping
from typing import Annotated, Any

import numpy as np
from pydantic import AfterValidator, BaseModel, ConfigDict, Strict, ValidationError, create_model
from pydantic_core import PydanticUndefined

from .errors import OptionError

#: an integer, not a float or a bool that equals one
Int = Annotated[int, Strict()]
#: a number (an integer is accepted), not a string or a bool
Float = Annotated[float, Strict()]
Bool = Annotated[bool, Strict()]
Str = Annotated[str, Strict()]

#: ``(option path or None for the options together, message)``
Problem = tuple[str | None, str]


def _pairs(value):
    if value is None:
        return value
    b = np.asarray(value, dtype=float)
    if b.ndim != 2 or b.shape[1] != 2 or not np.all(np.isfinite(b)):
        raise ValueError("not a list of (low, high) pairs")
    return value


#: bounds per variable: ``[(low, high), ...]`` (a list, tuple or array), or None
Pairs = Annotated[Any, AfterValidator(_pairs)]


def choices(values) -> str:
    """``'a', 'b' or 'c'``: the words of a description listing allowed values."""
    words = [repr(v) for v in values]
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} or {words[-1]}"


class PluginOptions(BaseModel):
    """Base of a plugin's declared options (unknown keys are reported by
    :func:`option_problems`, so the model itself accepts any)."""

    model_config = ConfigDict(arbitrary_types_allowed=True, validate_default=False)


def _signature_defaults(cls) -> dict[str, Any]:
    out = {}
    for p in inspect.signature(cls).parameters.values():
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD) or p.name == "self":
            continue
        out[p.name] = PydanticUndefined if p.default is p.empty else p.default
    return out


def _takes_keywords(cls) -> bool:
    return any(p.kind == p.VAR_KEYWORD for p in inspect.signature(cls).parameters.values())


@functools.cache
def options_model(cls) -> type[PluginOptions]:
    """The declared options of plugin class ``cls``: its ``Options``, or for a plugin
    without one its ``defaults`` (constructors taking ``**options``) or its constructor's
    keyword arguments, untyped."""
    declared = getattr(cls, "Options", None)
    if isinstance(declared, type) and issubclass(declared, BaseModel):
        if "Options" in vars(cls) or _takes_keywords(cls):
            return declared
        # inherited (an effect without its own: Effect.Options, attach only): the
        # constructor's other keyword arguments are options too, untyped
        extra = {k: v for k, v in _signature_defaults(cls).items()
                 if k not in declared.model_fields}
        if not extra:
            return declared
        return create_model(f"{cls.__name__}Options", __base__=declared,
                            **{k: (Any, v) for k, v in extra.items()})
    fields = dict(getattr(cls, "defaults", None) or {}) if _takes_keywords(cls) else \
        _signature_defaults(cls)
    return create_model(f"{cls.__name__}Options", __base__=PluginOptions,
                        **{k: (Any, v) for k, v in fields.items()})


def option_defaults(cls) -> dict[str, Any]:
    """Every declared option of ``cls`` that has a default, with it (an option the
    declaration leaves without one takes the constructor's default)."""
    signature = {} if _takes_keywords(cls) else _signature_defaults(cls)
    out = {}
    for name, field in options_model(cls).model_fields.items():
        default = field.get_default(call_default_factory=True)
        if default is PydanticUndefined:
            default = signature.get(name, PydanticUndefined)
        if default is not PydanticUndefined:
            out[name] = default
    return out


def _message(name: str, given: Any, errors: list[dict], field) -> Problem:
    """One problem of option ``name`` (value ``given``) from pydantic's errors about it: the
    message of a constraint that words its own (an OptionError), else what the option must
    be (its description) and what it got, else pydantic's message at the innermost place."""
    for e in errors:
        err = (e.get("ctx") or {}).get("error")
        if isinstance(err, OptionError):
            return err.option or name, str(err)
    description = getattr(field, "description", None)
    if description and any(e["input"] is given for e in errors):
        return name, f"{name} must be {description}, got {given!r}"
    e = errors[0]
    where = ".".join(str(p) for p in e["loc"][1:])
    return name, f"{name}: {where + ': ' if where else ''}{e['msg']}, got {e['input']!r}"


def option_problems(cls, options: Mapping[str, Any]) -> list[Problem]:
    """Every problem of ``options`` for plugin class ``cls``, as (option, message): unknown
    options (listing the known ones), then each option against its declared type and range
    (all reported), then the constraints between options (:func:`options_model`)."""
    model = options_model(cls)
    known = list(model.model_fields)
    listed = ", ".join(sorted(known)) or "(none)"
    problems: list[Problem] = [(k, f"unknown option; known: {listed}")
                               for k in options if k not in known]
    values = {**option_defaults(cls), **{k: v for k, v in options.items() if k in known}}
    try:
        model.model_validate(values)
    except ValidationError as err:
        by_option: dict[str | None, list[dict]] = {}
        for e in err.errors():
            by_option.setdefault(str(e["loc"][0]) if e["loc"] else None, []).append(e)
        for name, errors in by_option.items():
            if name is None:  # a constraint between options
                cause = (errors[0].get("ctx") or {}).get("error")
                problems.append((getattr(cause, "option", None), str(cause or errors[0]["msg"])))
            else:
                problems.append(_message(name, values.get(name), errors,
                                         model.model_fields.get(name)))
    return problems


def build(cls, options: Mapping[str, Any]) -> tuple[Any, list[Problem]]:
    """``(plugin or None, problems)``: ``cls`` built with ``options``, and every problem:
    those of :func:`option_problems`, then what the constructor finds (a model resolving its
    effects raises an :class:`~sensfw.errors.OptionError` naming each at its path), which it
    is asked with the bad options left out, so that both are reported at once. Anything else
    a constructor raises is a problem of the options too (a third-party plugin may not raise
    OptionError)."""
    problems = option_problems(cls, options)
    if any(opt is None for opt, _ in problems):  # the options together: nothing to add
        return None, problems
    bad = {opt.split(".")[0].split("[")[0] for opt, _ in problems}
    try:
        plugin = cls(**{k: v for k, v in options.items() if k not in bad})
    except OptionError as err:
        return None, problems + [p for p in err.problems if p[0] is None or
                                 p[0].split(".")[0].split("[")[0] not in bad]
    except Exception as err:  # a third-party constructor may raise anything on its options
        if problems:
            return None, problems
        return None, [(None, f"invalid options ({type(err).__name__}: {err})")]
    return (None, problems) if problems else (plugin, [])


def describe(problems: list[Problem]) -> str:
    """The problems in one line: ``option: message; ...``."""
    return "; ".join(msg if opt is None or msg.startswith(f"{opt} ") else f"{opt}: {msg}"
                     for opt, msg in problems)


def checked(cls, options: Mapping[str, Any], error: type[OptionError], what: str
            ) -> dict[str, Any]:
    """``options`` with the declared defaults of the rest, for a plugin that checks its
    options when it is built (designs, scorers); ``error`` (``what: ...``) names every
    problem of :func:`option_problems`."""
    problems = option_problems(cls, options)
    if problems:
        raise error(f"{what}: {describe(problems)}", option=problems[0][0], problems=problems)
    return {**option_defaults(cls), **options}


def make(registry, name: str, options: Mapping[str, Any], error: type[OptionError] = OptionError):
    """The plugin registered as ``name`` in ``registry``, built with ``options``; ``error``
    (naming the plugin, the first bad option and carrying every problem) if any is bad."""
    cls = registry.get(name)
    plugin, problems = build(cls, options)
    if problems:
        raise error(f"{registry.kind} {name!r}: {describe(problems)}", option=problems[0][0],
                    problems=problems)
    return plugin
