"""The coded box of a calibration: every calibrated quantity mapped to ``[-1, 1]``.

A range of a factor 10 or more is coded logarithmically (a contact stiffness, a transition
velocity: the response changes evenly per decade); a range that starts at zero and reaches
a hundred times its nominal value or more (a cubic stiffness 0..1e12 N/mm^3 with a nominal
1e8) is coded by ``log10(1 + x / x0)`` with ``x0`` four decades below the top, so that the
decades near zero are not squeezed into the first 0.01 % of the axis; every other range is
coded linearly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ...params import DesignSpace

#: decades of a zero-based axis resolved by the ``log10(1 + x / x0)`` coding
ZERO_LOG_DECADES = 4.0


@dataclass(frozen=True)
class Axis:
    """One calibrated quantity: a design variable (its lead member's unit) or an effect
    parameter, with its bounds, its nominal value and its coding (``"linear"``, ``"log"``
    or ``"log1p"``, see the module docstring)."""

    name: str
    low: float
    high: float
    nominal: float
    unit: str = ""
    scale: str = "linear"

    @classmethod
    def of(cls, name: str, low: float, high: float, nominal: float, unit: str = "") -> Axis:
        low, high, nominal = float(low), float(high), float(nominal)
        if low > 0 and high >= 10 * low:
            scale = "log"
        elif low == 0 and nominal > 0 and high >= 100 * nominal:
            scale = "log1p"
        else:
            scale = "linear"
        return cls(name, low, high, nominal, unit, scale)

    @property
    def log(self) -> bool:
        return self.scale == "log"

    @property
    def _x0(self) -> float:
        return self.high * 10.0 ** -ZERO_LOG_DECADES

    def _t(self, x):
        x = np.asarray(x, float)
        if self.scale == "log":
            return np.log10(x)
        if self.scale == "log1p":
            return np.log10(1.0 + x / self._x0)
        return x

    def _t_inv(self, t):
        if self.scale == "log":
            return 10.0**t
        if self.scale == "log1p":
            return (10.0**t - 1.0) * self._x0
        return t

    def code(self, x: float) -> float:
        a, b = self._t(self.low), self._t(self.high)
        return float(2 * (self._t(x) - a) / (b - a) - 1) if b > a else 0.0

    def decode(self, z: float) -> float:
        a, b = self._t(self.low), self._t(self.high)
        t = a + (float(np.clip(z, -1, 1)) + 1) / 2 * (b - a)
        return float(np.clip(self._t_inv(t), self.low, self.high))


@dataclass
class Coordinates:
    """The coded space of a calibration: its axes in order."""

    axes: list[Axis]

    @classmethod
    def of(cls, space: DesignSpace | None = None, params: Sequence = ()) -> Coordinates:
        """Axes of a design space's variables and of extra parameters (effect
        :class:`~sensfw.params.Parameter` objects)."""
        axes = [] if space is None else [Axis.of(v.name, v.low, v.high, v.nominal, v.unit)
                                         for v in space.variables]
        axes += [Axis.of(p.name, p.min, p.max, p.nominal, p.unit) for p in params]
        return cls(axes)

    def __add__(self, other: Coordinates) -> Coordinates:
        return Coordinates(self.axes + [a for a in other.axes if a.name not in self.names])

    @property
    def names(self) -> list[str]:
        return [a.name for a in self.axes]

    def __len__(self) -> int:
        return len(self.axes)

    def code(self, values: Mapping[str, float]) -> np.ndarray:
        return np.array([a.code(values[a.name]) for a in self.axes])

    def decode(self, z: Sequence[float]) -> dict[str, float]:
        return {a.name: a.decode(v) for a, v in zip(self.axes, z, strict=True)}
