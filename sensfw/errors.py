"""Exceptions raised by sensfw.

Every error that a user can cause (a study file, a measurement file, a parameter value, a
plugin name) derives from :class:`SensfwError`, so the command line can print it without a
traceback and exit with status 2.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping


class SensfwError(Exception):
    """Base class of all sensfw errors."""


class StudyError(SensfwError):
    """A study file is invalid.

    Carries one or more ``(dotted_path, message)`` pairs, for example
    ``("parameters.clutch_damping.max", "must be >= min (1 N*s/mm)")``.
    """

    def __init__(self, problems: Iterable[tuple[str, str]], source: str | None = None):
        self.problems = [(str(p), str(m)) for p, m in problems]
        self.source = source
        head = f"invalid study file {source}" if source else "invalid study"
        lines = [f"{head} ({len(self.problems)} problem(s)):"]
        lines += [f"  {path}: {msg}" if path else f"  {msg}" for path, msg in self.problems]
        super().__init__("\n".join(lines))


class UnknownPluginError(SensfwError, KeyError):
    """A plugin name is not registered; the message lists the available names."""

    def __init__(self, kind: str, name: str, available: Iterable[str],
                 reason: str | None = None):
        self.kind, self.name, self.available = kind, name, sorted(available)
        why = f" ({reason})" if reason else ""
        super().__init__(
            f"unknown {kind} {name!r}{why}; available: "
            f"{', '.join(self.available) or '(none)'}"
        )

    def __str__(self) -> str:  # KeyError would quote the message
        return self.args[0]


class OptionError(SensfwError, ValueError):
    """A plugin (design, scorer, surrogate, model, effect) got a bad option; ``option`` names
    it (a dotted path inside the plugin's options, e.g. ``effects[1].attach``; None: the
    options together), so a study can report it at its dotted path. ``problems`` holds every
    ``(option, message)`` when there are several (:mod:`sensfw.options`)."""

    def __init__(self, message: str, option: str | None = None,
                 problems: Iterable[tuple[str | None, str]] | None = None):
        super().__init__(message)
        self.option = option
        self.problems = list(problems) if problems is not None else [(option, message)]


class ParameterError(SensfwError, ValueError):
    """A parameter value is unknown, not finite or outside its bounds."""


class SimulationError(SensfwError, RuntimeError):
    """A simulation failed or diverged; the message names the parameter values."""

    def __init__(self, model: str, reason: str, parameters: Mapping[str, float] | None = None):
        self.model, self.reason = model, reason
        self.parameters = dict(parameters or {})
        values = ", ".join(f"{k}={v:.6g}" for k, v in self.parameters.items())
        where = f" [{values}]" if values else ""
        super().__init__(f"{model} simulation failed: {reason}{where}")


class DivergenceError(SimulationError):
    """The time integration blew up (non-finite or absurd signals): a numerical failure that
    a smaller step may cure (see :func:`sensfw.runs.spec.execute`). ``step`` is the step
    (s) that diverged, where the model knows it."""

    def __init__(self, model: str, reason: str, parameters: Mapping[str, float] | None = None,
                 step: float | None = None):
        super().__init__(model, reason, parameters)
        self.step = step


class SignalError(SensfwError, ValueError):
    """A signal is unusable for the requested analysis (too short, wrong rate, NaN...)."""


class MeasurementError(SensfwError, ValueError):
    """A measurement file is unusable; the message names the file and the channel."""

    def __init__(self, file: str, message: str, channel: str | None = None):
        self.file, self.channel = file, channel
        where = f"{file}" + (f", channel {channel!r}" if channel else "")
        super().__init__(f"{where}: {message}")


class AnalysisError(SensfwError, ValueError):
    """What is left of a design cannot support the requested analysis or fit."""
