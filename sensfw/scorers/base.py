"""The scorer contract: signals (and a reference where it compares) -> named numbers."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

from ..errors import OptionError, SensfwError
from ..models.base import Signals


class ScorerError(OptionError):
    """A scorer was given a bad option (``option`` names it, where known) or cannot score the
    signals it got."""


class Scorer(ABC):
    """Base class of outcome scorers (plugin group ``sensfw.scorers``).

    Subclasses set ``name``, ``outputs`` (names of the numbers :meth:`score` returns),
    ``needs_reference`` and ``defaults`` (every accepted option with its default); options
    are validated at construction, so a study file with a wrong option fails before any run.
    """

    name: ClassVar[str] = "scorer"
    outputs: ClassVar[tuple[str, ...]] = ("value",)
    needs_reference: ClassVar[bool] = False
    defaults: ClassVar[dict[str, Any]] = {}

    def __init__(self, channel: str | None = None, **options: Any):
        unknown = set(options) - set(self.defaults)
        if unknown:
            raise ScorerError(f"scorer {self.name!r}: unknown option(s) "
                              f"{', '.join(sorted(unknown))}; accepted: "
                              f"{', '.join(sorted(self.defaults)) or '(none)'}",
                              option=sorted(unknown)[0])
        self.channel = channel
        self.given = frozenset(options)  # the options set explicitly (not defaults)
        self.options = {**self.defaults, **options}
        self.validate()

    def validate(self) -> None:  # noqa: B027  (optional hook)
        """Check ``self.options``; raise :class:`ScorerError` naming the option."""

    def check_excitation(self, excitation) -> None:  # noqa: B027  (optional hook)
        """Check the options against the study's excitation (a
        :class:`~sensfw.excitation.Chirp`) before anything runs; raise :class:`ScorerError`
        with ``option=`` naming the option."""

    def signal(self, signals: Signals):
        name = self.channel or next(iter(signals.channels))
        try:
            return signals.channel(name)
        except SensfwError as err:
            raise ScorerError(f"scorer {self.name!r}: {err}") from None

    @abstractmethod
    def score(self, signals: Signals, reference: Signals | None = None) -> dict[str, float]:
        """Named numbers (keys = ``outputs``)."""

    def __repr__(self) -> str:
        opts = ", ".join(f"{k}={v!r}" for k, v in self.options.items())
        return f"{type(self).__name__}(channel={self.channel!r}, {opts})"
