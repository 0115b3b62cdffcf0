"""Parameters, design variables and the design space.

A *parameter* is what a model declares (name, unit, nominal, bounds). A *design variable* is
what a design moves: one parameter, or a group of parameters moved together (the paper,
Sect. 3.1, moves the static and dynamic friction coefficients as one variable, and the stiction
and friction velocities as another). A design variable is measured in the physical unit of its
lead (first) member; the other members follow through the coded value
``c = (x - mid) / half_range`` in [-1, 1], so at the variable's min all members sit at their
min, at the mid-point all at their mid-points (the "medium value" of Table 2).

Values are in the paper's units (N, mm, s); models convert internally (:data:`MM`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from .errors import ParameterError

#: metres per millimetre: parameters come in the paper's mm, models compute in SI
MM = 1e-3



def spaced(unit: str) -> str:
    """`` unit`` after a number, nothing for a dimensionless quantity (no trailing blank)."""
    return f" {unit}" if unit else ""

@dataclass(frozen=True)
class Parameter:
    """A model parameter with its unit and bounds (Table 1 style)."""

    name: str
    unit: str
    nominal: float
    min: float
    max: float
    description: str = ""
    group: str = ""  # component heading of Table 1 ("Slide bearing", "Bearing L1", ...)

    def __post_init__(self) -> None:
        for attr in ("nominal", "min", "max"):
            if not math.isfinite(getattr(self, attr)):
                raise ParameterError(f"parameter {self.name!r}: {attr} is not finite")
        if self.min > self.max:
            raise ParameterError(f"parameter {self.name!r}: min {self.min} > max {self.max}")
        if not self.min <= self.nominal <= self.max:
            raise ParameterError(
                f"parameter {self.name!r}: nominal {self.nominal} outside [{self.min}, {self.max}]"
            )

    def check(self, value: float, tol: float = 1e-9) -> float:
        """Return ``value`` as float, or raise naming the parameter if it is out of bounds
        (by more than ``tol`` of the bounds' magnitude: round-off passes, unchanged)."""
        value = float(value)
        span = max(abs(self.max), abs(self.min), 1e-300) * tol
        if not math.isfinite(value) or value < self.min - span or value > self.max + span:
            raise ParameterError(
                f"parameter {self.name!r} = {value:g}{spaced(self.unit)} is outside its "
                f"bounds [{self.min:g}, {self.max:g}]{spaced(self.unit)}"
            )
        return value

    def clip(self, value: float) -> float:
        """``value`` checked (:meth:`check`) and put on the bound it passes by round-off:
        what a calibration writes as a nominal value. (A coded -1 decoded through a group's
        members gives -0.9000000000000001 for a bound of -0.9, which a study file's nominal
        may not be. Runs keep the unclipped value: the stick-slip models' scores move
        visibly for a one-ulp change of a friction parameter, and run-store keys and every
        verdict measured so far rest on it.)"""
        return min(max(self.check(value), self.min), self.max)


class ParameterSet(Mapping[str, Parameter]):
    """Ordered, read-only collection of parameters, as a model declares them."""

    def __init__(self, parameters: Iterable[Parameter]):
        self._p: dict[str, Parameter] = {}
        for p in parameters:
            if p.name in self._p:
                raise ParameterError(f"duplicate parameter {p.name!r}")
            self._p[p.name] = p

    def __getitem__(self, name: str) -> Parameter:
        try:
            return self._p[name]
        except KeyError:
            import difflib

            close = difflib.get_close_matches(str(name), list(self._p), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise ParameterError(
                f"unknown parameter {name!r}{hint}; known: {', '.join(self._p)}"
            ) from None

    def __contains__(self, name: object) -> bool:
        return name in self._p

    def __iter__(self):
        return iter(self._p)

    def __len__(self) -> int:
        return len(self._p)

    def nominal(self) -> dict[str, float]:
        return {n: p.nominal for n, p in self._p.items()}

    def with_bounds(self, changes: Mapping[str, Mapping[str, float]]) -> ParameterSet:
        """A copy with some nominal/min/max replaced (``{"name": {"max": 1.0}}``)."""
        out = []
        for n, p in self._p.items():
            out.append(replace(p, **dict(changes[n])) if n in changes else p)
        unknown = set(changes) - set(self._p)
        if unknown:
            self[sorted(unknown)[0]]  # raises with the list of known names
        return ParameterSet(out)

    def complete(self, values: Mapping[str, float], check: bool = True) -> dict[str, float]:
        """Nominal values updated by ``values``, each checked against its bounds."""
        full = self.nominal()
        for name, v in values.items():
            full[name] = self[name].check(v) if check else float(v)
        return full

    def to_frame(self) -> pd.DataFrame:
        return pd.DataFrame(
            [
                dict(name=p.name, group=p.group, unit=p.unit, min=p.min, nominal=p.nominal,
                     max=p.max, description=p.description)
                for p in self._p.values()
            ]
        ).set_index("name")


@dataclass(frozen=True)
class DesignVariable:
    """What a design moves: one parameter or a group moved together.

    ``low``/``high``/``nominal`` are in the unit of the lead member (``members[0]``);
    ``bounds`` holds each member's own (min, nominal, max) for the stage.
    """

    name: str
    members: tuple[str, ...]
    unit: str
    low: float
    nominal: float
    high: float
    bounds: Mapping[str, tuple[float, float, float]] = field(default_factory=dict)

    @property
    def mid(self) -> float:
        return 0.5 * (self.low + self.high)

    def code(self, value: float | np.ndarray) -> float | np.ndarray:
        """Physical value of the lead -> coded value in [-1, 1]."""
        half = 0.5 * (self.high - self.low)
        return (np.asarray(value, dtype=float) - self.mid) / half if half > 0 else 0.0 * value

    def decode(self, coded: float | np.ndarray) -> float | np.ndarray:
        return self.mid + np.asarray(coded, dtype=float) * 0.5 * (self.high - self.low)

    def member_values(self, value: float) -> dict[str, float]:
        """Physical value of every member when the lead takes ``value``.

        The nominal of the lead maps to every member's nominal (so an OAT reference run is
        the true nominal even when nominal is not the mid-point); otherwise members follow
        the coded value linearly between their own bounds.
        """
        out = {}
        for m in self.members:
            lo, nom, hi = self.bounds[m]
            if math.isclose(value, self.nominal, rel_tol=1e-12, abs_tol=1e-300):
                out[m] = nom
            else:
                c = float(self.code(value))
                out[m] = 0.5 * (lo + hi) + c * 0.5 * (hi - lo)
        return out


def clashing_group_names(groups: Mapping[str, Sequence[str]], parameters) -> list[str]:
    """Group names that are parameters outside their own group: each would hide that
    parameter's own design variable (the study reports them at ``groups.NAME``)."""
    return [g for g, ms in groups.items() if g in parameters and g not in ms]


class DesignSpace:
    """The design variables of one stage plus the fixed values of every other parameter."""

    def __init__(self, variables: Sequence[DesignVariable], parameters: ParameterSet,
                 fixed: Mapping[str, float] | None = None):
        names = [v.name for v in variables]
        if len(set(names)) != len(names):
            raise ParameterError(f"duplicate design variable in {names}")
        seen: set[str] = set()
        for v in variables:
            for m in v.members:
                parameters[m]  # raises for unknown names
                if m in seen:
                    raise ParameterError(f"parameter {m!r} belongs to two design variables")
                seen.add(m)
        self.variables = tuple(variables)
        self.parameters = parameters
        self.fixed = parameters.complete(fixed or {})

    @classmethod
    def from_parameters(cls, parameters: ParameterSet, groups: Mapping[str, Sequence[str]]
                        | None = None, select: Sequence[str] | None = None,
                        bounds: Mapping[str, Mapping[str, float]] | None = None,
                        fixed: Mapping[str, float] | None = None) -> DesignSpace:
        """Build variables from parameters: grouped members become one variable.

        ``groups`` maps a variable name to its members; every parameter not in a group is a
        variable of its own. ``select`` keeps only the named variables (in that order).
        ``bounds`` overrides a member's min/nominal/max for this space (Table 2 narrows some).
        """
        params = parameters.with_bounds(bounds or {})
        groups = {k: tuple(v) for k, v in (groups or {}).items()}
        grouped = {m for ms in groups.values() for m in ms}
        clash = clashing_group_names(groups, params)
        if clash:
            raise ParameterError(f"group name(s) {clash} are parameters outside their groups: "
                                 "each would hide that parameter; name the groups otherwise")
        variables: dict[str, DesignVariable] = {}
        for name in params:
            if name in grouped:
                gname = next(g for g, ms in groups.items() if name in ms)
                if gname in variables:
                    continue
                members = groups[gname]
            else:
                gname, members = name, (name,)
            lead = params[members[0]]
            variables[gname] = DesignVariable(
                name=gname, members=members, unit=lead.unit, low=lead.min,
                nominal=lead.nominal, high=lead.max,
                bounds={m: (params[m].min, params[m].nominal, params[m].max) for m in members},
            )
        if select is not None:
            missing = [s for s in select if s not in variables]
            if missing:
                raise ParameterError(
                    f"unknown design variable(s) {missing}; known: {', '.join(variables)}"
                )
            chosen = [variables[s] for s in select]
        else:  # every variable that can vary: one pinned by min = max is a fixed parameter
            chosen = [v for v in variables.values()
                      if not all(lo == hi for lo, _, hi in v.bounds.values())]
        frozen = [v.name for v in chosen if all(lo == hi for lo, _, hi in v.bounds.values())]
        if frozen:
            raise ParameterError(
                f"design variable(s) {frozen} have min = max: they cannot vary (a design "
                "would code them to 0 and find no effect); widen their bounds or leave them "
                "out of the stage's variables")
        return cls(chosen, params, fixed)

    @property
    def names(self) -> list[str]:
        return [v.name for v in self.variables]

    def __len__(self) -> int:
        return len(self.variables)

    def __getitem__(self, name: str) -> DesignVariable:
        for v in self.variables:
            if v.name == name:
                return v
        raise ParameterError(f"unknown design variable {name!r}; known: {', '.join(self.names)}")

    def nominal_row(self) -> dict[str, float]:
        return {v.name: v.nominal for v in self.variables}

    def to_parameters(self, row: Mapping[str, float]) -> dict[str, float]:
        """Full parameter dict of one run (fixed values + members of every variable)."""
        full = dict(self.fixed)
        for v in self.variables:
            value = float(row[v.name]) if v.name in row else v.nominal
            full.update(v.member_values(value))
        for name, value in full.items():
            self.parameters[name].check(value)
        return full

    def code(self, frame: pd.DataFrame) -> pd.DataFrame:
        """Physical design table -> coded (-1..1) table."""
        missing = [n for n in self.names if n not in frame.columns]
        if missing:
            raise ParameterError(f"the design table has no column for design variable(s) "
                                 f"{missing} (it has {list(frame.columns)})")
        return pd.DataFrame({v.name: v.code(frame[v.name].to_numpy()) for v in self.variables},
                            index=frame.index)

    def decode(self, coded: pd.DataFrame | np.ndarray) -> pd.DataFrame:
        arr = np.asarray(coded, dtype=float)
        return pd.DataFrame({v.name: v.decode(arr[:, i]) for i, v in enumerate(self.variables)})

    def bounds_array(self) -> np.ndarray:
        return np.array([[v.low, v.high] for v in self.variables], dtype=float)
