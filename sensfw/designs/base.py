"""The design contract: a design generates the run table of a design space and analyses the
responses of its runs (pairs with the same name, as SALib's sample/analyze modules)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import pandas as pd

from ..errors import AnalysisError, OptionError
from ..options import checked
from ..params import DesignSpace


class DesignError(OptionError):
    """A design was given a bad option (``option`` names it, where known) or cannot be built
    for the space."""


@dataclass
class ScreeningResult:
    """What a design's analysis says about its variables.

    ``importance`` (variable -> non-negative number, higher = more important) drives ranking
    and selection; ``table`` holds the design-specific details; ``notes`` what was missing.
    """

    importance: pd.Series
    table: pd.DataFrame
    notes: list[str] = field(default_factory=list)

    @property
    def ranking(self) -> list[str]:
        return list(self.importance.sort_values(ascending=False, kind="stable").index)

    def select(self, threshold: float | None = None,
               max_variables: int | None = None) -> list[str]:
        """Variables with importance above ``threshold`` (most important first), at most
        ``max_variables``."""
        out = [v for v in self.ranking
               if threshold is None or self.importance[v] > threshold]
        return out[:max_variables] if max_variables else out


class Design(ABC):
    """Base class of design plugins (group ``sensfw.designs``).

    Subclasses set ``name`` and ``Options`` (:mod:`sensfw.options`: every option with its
    type, range and default); options are checked at construction, so a study fails before
    anything runs, and ``self.options`` holds them with the defaults of the others. A design
    without ``Options`` may list untyped options with their defaults in ``defaults``.
    """

    name: ClassVar[str] = "design"
    defaults: ClassVar[dict[str, Any]] = {}

    def __init__(self, **options: Any):
        self.options = checked(type(self), options, DesignError, f"design {self.name!r}")

    @abstractmethod
    def n_runs(self, space: DesignSpace) -> int:
        """Number of runs, known before anything runs."""

    @abstractmethod
    def generate(self, space: DesignSpace, seed: int | None = None) -> pd.DataFrame:
        """Physical values of the design variables, one row per run (columns =
        ``space.names``, index = run labels); deterministic for a seed."""

    @abstractmethod
    def analyze(self, space: DesignSpace, table: pd.DataFrame, y) -> ScreeningResult:
        """Importance of every variable from the responses ``y`` (NaN = failed run)."""


def check_groups(design: str, groups: dict[str, list[str]], names: list[str]
                 ) -> dict[str, str]:
    """Variable -> its group, every one of ``names`` in exactly one of ``groups`` (a
    design's ``groups`` option); otherwise a :class:`DesignError` at ``groups``."""
    member = [v for vs in groups.values() for v in vs]
    problems = (("unknown variables", sorted(set(member) - set(names))),
                ("variables without a group", [v for v in names if v not in member]),
                ("variables in two groups", sorted({v for v in member
                                                    if member.count(v) > 1})),
                ("empty groups", [g for g, vs in groups.items() if not vs]))
    for what, bad in problems:
        if bad:
            raise DesignError(f"design {design!r}: {what} in groups: {bad}", option="groups")
    return {v: g for g, vs in groups.items() for v in vs}


def responses(table: pd.DataFrame, y, design: str) -> np.ndarray:
    """``y`` as a float vector, one per run of ``table`` (NaN: a failed run); an
    :class:`AnalysisError` where it is not numeric, has another length, or has no finite
    value."""
    try:
        y = np.asarray(y, dtype=float).ravel()
    except (TypeError, ValueError) as err:
        raise AnalysisError(f"{design}: the responses must be numbers ({err})") from None
    if len(y) != len(table):
        raise AnalysisError(f"{design}: {len(y)} responses for {len(table)} runs")
    if not len(y):
        raise AnalysisError(f"{design}: no runs to analyse")
    if not np.isfinite(y).any():
        raise AnalysisError(f"{design}: none of the {len(y)} runs has a score (every run "
                            "failed or scored NaN): there is nothing to analyse")
    return y


#: an effect at most this fraction of the responses' own scale (their largest magnitude)
#: is round-off, not an effect: ``1 + 1e-16 - 1`` normalised to the largest effect made a
#: variable that does nothing 100 % important
ROUND_OFF = 1e-9


def relative(effects: pd.Series, y: np.ndarray, notes: list[str] | None = None,
             by: str = "max") -> pd.Series:
    """``effects`` (non-negative) over their largest (``by="max"``) or their sum
    (``"sum"``); all zero, with a line in ``notes``, where the largest is round-off of the
    responses ``y`` (:data:`ROUND_OFF`)."""
    effects = effects.fillna(0.0)
    top = float(effects.max()) if len(effects) else 0.0
    finite = np.asarray(y, float)[np.isfinite(np.asarray(y, float))]
    scale = float(np.max(np.abs(finite))) if finite.size else 0.0
    if top <= ROUND_OFF * scale or top <= 0:
        if notes is not None and len(effects):
            notes.append(f"no variable changes the response beyond round-off (largest effect "
                         f"{top:.3g}, responses up to {scale:.3g}): every importance is 0")
        return effects * 0.0
    return effects / (top if by == "max" else float(effects.sum()))
