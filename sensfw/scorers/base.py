"""The scorer contract: signals (and a reference where it compares) -> named numbers."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

from ..errors import OptionError, SensfwError
from ..models.base import Signals
from ..options import checked


class ScorerError(OptionError):
    """A scorer was given a bad option (``option`` names it, where known) or cannot score the
    signals it got."""


class Scorer(ABC):
    """Base class of outcome scorers (plugin group ``sensfw.scorers``).

    Subclasses set ``name``, ``outputs`` (names of the numbers :meth:`score` returns),
    ``needs_reference`` and ``Options`` (:mod:`sensfw.options`: every option with its type,
    range and default; a scorer without ``Options`` may list untyped options with their
    defaults in ``defaults``); options are checked at construction, so a study file with a
    wrong option fails before any run. ``channel`` (the signal scored) is not an option of
    the scorer but of its use in a study.
    """

    name: ClassVar[str] = "scorer"
    outputs: ClassVar[tuple[str, ...]] = ("value",)
    needs_reference: ClassVar[bool] = False
    defaults: ClassVar[dict[str, Any]] = {}

    def __init__(self, channel: str | None = None, **options: Any):
        self.options = checked(type(self), options, ScorerError, f"scorer {self.name!r}")
        self.channel = channel
        self.given = frozenset(options)  # the options set explicitly (not defaults)

    def check_excitation(self, excitation) -> None:  # noqa: B027  (optional hook)
        """Check the options against the study's excitation (a
        :class:`~sensfw.excitation.Chirp`) before anything runs; raise :class:`ScorerError`
        with ``option=`` naming the option."""

    def channel_name(self, signals: Signals) -> str:
        """The scored channel: ``channel``, or the signals' first sensor channel."""
        name = self.channel or next(iter(signals.channels), None)
        if name is None:
            raise ScorerError(f"scorer {self.name!r}: the signals hold no sensor channel "
                              "(only the force); name one with channel='force'")
        return name

    def signal(self, signals: Signals):
        name = self.channel_name(signals)
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
