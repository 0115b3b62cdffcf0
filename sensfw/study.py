"""Declarative study files (TOML) and their validation.

A study names a model, overrides parameter bounds (values with units, parsed with pint),
groups parameters into design variables, sets the excitation, solver and execution, and
lists stages (design + scorers + selection or surrogates). Every problem in a file is
reported at once with its dotted path (``parameters.clutch_drive_damping.max: ...``) as a
:class:`~sensfw.errors.StudyError`; the command line prints them and exits with status 2.

Example (``studies/quick.toml``)::

    [study]
    name = "quick"
    [model]
    name = "shaft_assembly"
    output = "crank_axial"
    [excitation]
    f0 = "50 Hz"
    f1 = "5 kHz"
    ...
    [[stages]]
    name = "screen"
    design = "oat"
    scorers = [{ name = "frf_scalar" }]
    select = { by = "frf_scalar", threshold = 0.1, max_variables = 3 }
"""

from __future__ import annotations

import functools
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from .errors import SensfwError, StudyError, UnknownPluginError
from .excitation import Excitation, make_excitation
from .models.base import IMPLICIT_METHODS, Model, SolverSettings
from .models.stepsize import CALIBRATED_METHODS
from .params import DesignSpace, Parameter, ParameterSet

Quantity = str | float | int


@functools.cache
def units():
    import pint

    return pint.UnitRegistry()


def to_unit(value: Quantity, unit: str) -> float:
    """``value`` ("7.05e5 N/mm", or a bare number meaning ``unit``) as a float in ``unit``."""
    if isinstance(value, bool):
        raise ValueError(f"expected a number or a quantity string, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value)
    import pint

    try:
        q = units().Quantity(value.strip())
        if isinstance(q, (int, float)):
            return float(q)
        return float(q.to(unit or "dimensionless").magnitude)
    except pint.DimensionalityError:
        raise ValueError(f"cannot convert {value!r} to {unit or 'a plain number'}") from None
    except (pint.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError,
            AttributeError, TypeError, AssertionError) as err:
        raise ValueError(f"cannot read {value!r} as a quantity in {unit or '1'}: {err}") \
            from None


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class StudyInfo(_Strict):
    name: str
    description: str = ""
    seed: int = 0


class ModelSection(_Strict):
    name: str = "shaft_assembly"
    options: dict[str, Any] = Field(default_factory=dict)
    output: str | None = None  # FRF/order output channel; default: the model's default_output


class GainSection(_Strict):
    """The shaker's gain (N/V) when measurements record the amplifier voltage."""

    nominal: Quantity
    min: Quantity
    max: Quantity


class ExcitationSection(_Strict):
    """The study's excitation; ``kind`` is what a study run uses, ``drive`` how the model is
    driven for a measurement: ``auto`` (the ideal excitation when the record is it, else the
    measured record), ``measured`` (always the record) or ``ideal`` (refuse other records)."""

    kind: Literal["log_chirp", "linear_sweep", "stepped_sine", "random"] = "log_chirp"
    f0: Quantity = "50 Hz"
    f1: Quantity = "5 kHz"
    duration: Quantity = "1 s"
    fs: Quantity = "20 kHz"
    amplitude: Quantity = "0.1 N"
    tail: Quantity = "0 s"
    steps: int = Field(default=20, ge=1)  # stepped_sine
    seed: int = 0  # random
    drive: Literal["auto", "measured", "ideal"] = "auto"
    gain: GainSection | None = None


class SolverSection(_Strict):
    # explicit Runge-Kutta methods, or Exudyn's implicit ones (stiff models: the bolted beam)
    method: Literal["RK44", "RK67", "ExplicitMidpoint", "ExplicitEuler", "DOPRI5",
                    "GeneralizedAlpha", "TrapezoidalIndex2"] = "RK44"
    step: Quantity = "1e-5 s"
    timeout: Quantity | None = None
    halvings: int = Field(default=1, ge=0, le=4)  # retries at half the step after divergence
    # smaller steps where the run's linearised eigenvalues need them (models/stepsize.py)
    auto_step: bool = True
    # numerical dissipation of GeneralizedAlpha (rho_inf; 1 = none)
    spectral_radius: float = Field(default=0.8, ge=0.0, le=1.0)


class ExecutionSection(_Strict):
    backend: Literal["serial", "processes", "dask"] = "processes"
    workers: int | None = Field(default=None, ge=1)
    scheduler: str | None = None


class ParameterOverride(_Strict):
    nominal: Quantity | None = None
    min: Quantity | None = None
    max: Quantity | None = None


class ScorerSpec(BaseModel):
    """A scorer and its options; ``label`` names the result (default: the scorer name)."""

    model_config = ConfigDict(extra="allow")
    name: str
    label: str | None = None
    channel: str | None = None

    def options(self) -> dict[str, Any]:
        return dict(self.model_extra or {})

    @property
    def key(self) -> str:
        return self.label or self.name


class SurrogateSpec(BaseModel):
    """A surrogate and its options; ``label`` names it in the results (default: its name)."""

    model_config = ConfigDict(extra="allow")
    name: str
    label: str | None = None

    def options(self) -> dict[str, Any]:
        return dict(self.model_extra or {})

    @property
    def key(self) -> str:
        return self.label or self.name


class SelectSpec(_Strict):
    by: str | None = None  # scorer label; default: the stage's first scorer
    threshold: float = Field(default=0.10, ge=0.0)
    max_variables: int | None = Field(default=None, ge=1)


class StageSpec(_Strict):
    name: str
    design: str
    design_options: dict[str, Any] = Field(default_factory=dict)
    analysis_options: dict[str, Any] = Field(default_factory=dict)
    variables: str | list[str] = "all"  # "all", a list, or "selected:<stage>"
    bounds: dict[str, ParameterOverride] = Field(default_factory=dict)
    scorers: list[ScorerSpec] = Field(min_length=1)
    select: SelectSpec | None = None
    surrogates: list[SurrogateSpec] = Field(default_factory=list)
    confirmation_runs: int = Field(default=0, ge=0)

    @field_validator("surrogates", mode="before")
    @classmethod
    def _surrogate_names(cls, v):
        return [{"name": x} if isinstance(x, str) else x for x in v] if isinstance(v, list) \
            else v

    @field_validator("variables")
    @classmethod
    def _variables(cls, v):
        if isinstance(v, str) and v != "all" and not v.startswith("selected:"):
            raise ValueError("must be 'all', 'selected:<stage name>' or a list of variables")
        return v


class StudyFile(_Strict):
    study: StudyInfo
    model: ModelSection = Field(default_factory=ModelSection)
    excitation: ExcitationSection = Field(default_factory=ExcitationSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    execution: ExecutionSection = Field(default_factory=ExecutionSection)
    parameters: dict[str, ParameterOverride] = Field(default_factory=dict)
    groups: dict[str, list[str]] | None = None  # None: the model's default grouping
    stages: list[StageSpec] = Field(min_length=1)


def _without(data: Any, locs: list[tuple]) -> Any:
    """A deep copy of ``data`` without the entries at ``locs``."""
    import copy

    out = copy.deepcopy(data)
    for loc in locs:
        node = out
        for part in loc[:-1]:
            node = node[part]
        node.pop(loc[-1], None)
    return out


def _path(loc: tuple) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


class Study:
    """A validated study: the file's content resolved against the model and the registries.

    Use :meth:`load` (file) or :meth:`from_dict`; both raise :class:`StudyError` listing
    every problem with its dotted path.
    """

    def __init__(self, spec: StudyFile, source: str | None = None):
        self.spec = spec
        self.source = source
        problems: list[tuple[str, str]] = []
        self.gain: Parameter | None = None
        self.model = self._resolve_model(problems)
        self.excitation = self._resolve_excitation(problems)
        self.parameters = self._resolve_parameters(problems)
        self.solver = self._resolve_solver(problems)
        self.groups = self._resolve_groups(problems)
        self.stage_bounds = {}
        self._check_stages(problems)
        if problems:
            raise StudyError(problems, source)

    # ---- construction ------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> Study:
        try:
            spec = StudyFile.model_validate(data)
        except ValidationError as err:
            problems = [(_path(e["loc"]), e["msg"]) for e in err.errors()]
            # unknown keys alone should not hide the other problems: drop them and check
            # the rest, so that everything is reported at once
            if all(e["type"] == "extra_forbidden" for e in err.errors()):
                cleaned = _without(data, [e["loc"] for e in err.errors()])
                try:
                    cls(StudyFile.model_validate(cleaned), source)
                except StudyError as more:
                    problems += more.problems
            raise StudyError(problems, source) from None
        return cls(spec, source)

    @classmethod
    def load(cls, path: str | Path) -> Study:
        path = Path(path)
        try:
            data = tomllib.loads(path.read_text())
        except FileNotFoundError:
            raise StudyError([("", "file not found")], str(path)) from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
            raise StudyError([("", f"not valid TOML: {err}")], str(path)) from None
        return cls.from_dict(data, str(path))

    # ---- resolution --------------------------------------------------------------------------
    def _resolve_model(self, problems) -> Model | None:
        from .plugins import models

        try:
            cls = models.get(self.spec.model.name)
        except UnknownPluginError as err:
            problems.append(("model.name", str(err)))
            return None
        try:
            model = cls(**self.spec.model.options)
        except TypeError as err:
            problems.append(("model.options", f"not accepted by {self.spec.model.name}: {err}"))
            return None
        except SensfwError as err:  # e.g. an unknown effect or attach point
            problems.append(("model.options", str(err)))
            return None
        out = self.spec.model.output or model.default_output
        if out not in model.sensors:
            problems.append(("model.output", f"unknown channel {out!r}; the model has "
                                             f"{', '.join(model.sensors)}"))
        self.output = out
        return model

    def _resolve_parameters(self, problems) -> ParameterSet | None:
        if self.model is None:
            return None
        declared = self.model.parameters()
        if self.gain is not None:
            declared = ParameterSet([*declared.values(), self.gain])
        changes, ok = self._overrides(self.spec.parameters, declared, "parameters", problems)
        if not ok:
            return None
        try:
            return declared.with_bounds(changes)
        except Exception as err:  # unreachable after the checks above, kept defensive
            problems.append(("parameters", str(err)))
            return None

    @staticmethod
    def _overrides(overrides: Mapping[str, ParameterOverride], declared: ParameterSet,
                   prefix: str, problems) -> tuple[dict, bool]:
        ok = True
        changes: dict[str, dict[str, float]] = {}
        for name, ov in overrides.items():
            if name not in declared:
                problems.append((f"{prefix}.{name}", f"unknown parameter; the model has "
                                                     f"{', '.join(declared)}"))
                ok = False
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
                    ok = False
            lo = vals.get("min", p.min)
            hi = vals.get("max", p.max)
            nom = vals.get("nominal", p.nominal)
            if lo > hi:
                problems.append((f"{prefix}.{name}.max",
                                 f"max {hi:g} {p.unit} is below min {lo:g} {p.unit}"))
                ok = False
            elif not lo <= nom <= hi:
                problems.append((f"{prefix}.{name}.nominal",
                                 f"nominal {nom:g} {p.unit} outside [{lo:g}, {hi:g}] {p.unit}"))
                ok = False
            changes[name] = vals
        return changes, ok

    def _resolve_excitation(self, problems) -> Excitation | None:
        e = self.spec.excitation
        vals = {}
        for name, unit in (("f0", "Hz"), ("f1", "Hz"), ("duration", "s"), ("fs", "Hz"),
                           ("tail", "s")):
            try:
                vals[name] = to_unit(getattr(e, name), unit)
            except ValueError as err:
                problems.append((f"excitation.{name}", str(err)))
        try:  # a force, or an amplifier voltage that drives through the gain
            vals["amplitude"] = to_unit(e.amplitude, "N")
        except ValueError:
            try:
                vals["amplitude"], vals["signal_unit"] = to_unit(e.amplitude, "V"), "V"
            except ValueError as err:
                problems.append(("excitation.amplitude", f"{err} (a force in N or a "
                                                         "voltage in V)"))
        if vals.get("signal_unit") == "V" and e.gain is None:
            problems.append(("excitation.gain", "a voltage excitation needs the shaker's "
                                                "gain: gain = { nominal, min, max } in N/V"))
        self.drive = e.drive
        if e.gain is not None:
            self._resolve_gain(e.gain, problems)
        if "amplitude" not in vals or len(vals) < 6:
            return None
        if e.kind == "stepped_sine":
            vals["steps"] = e.steps
        if e.kind == "random":
            vals["seed"] = e.seed
        try:
            return make_excitation({"kind": e.kind, **vals})
        except Exception as err:
            problems.append(("excitation", str(err)))
            return None

    def _resolve_gain(self, gain: GainSection, problems) -> None:
        """``excitation_gain`` (N/V) joins the parameters: calibrated like any other."""
        vals = {}
        for name in ("nominal", "min", "max"):
            try:
                vals[name] = to_unit(getattr(gain, name), "N/V")
            except ValueError as err:
                problems.append((f"excitation.gain.{name}", str(err)))
        if len(vals) == 3:
            try:
                self.gain = Parameter("excitation_gain", "N/V", vals["nominal"], vals["min"],
                                      vals["max"], "shaker force per amplifier volt",
                                      "Excitation")
            except SensfwError as err:
                problems.append(("excitation.gain", str(err)))

    def _resolve_solver(self, problems) -> SolverSettings | None:
        s = self.spec.solver
        step = timeout = None
        try:
            step = to_unit(s.step, "s")
        except ValueError as err:
            problems.append(("solver.step", str(err)))
        try:
            timeout = None if s.timeout is None else to_unit(s.timeout, "s")
        except ValueError as err:
            problems.append(("solver.timeout", str(err)))
        if step is None:
            return None
        if not 0 < step < 1e-2:
            problems.append(("solver.step", f"step {step:g} s must be in (0, 0.01) s"))
            return None
        if self.excitation is not None and step > 1 / self.excitation.fs:
            problems.append(("solver.step", f"step {step:g} s exceeds the output sample period "
                                            f"{1 / self.excitation.fs:g} s"))
        if s.auto_step and s.method in IMPLICIT_METHODS:
            problems.append(("solver.auto_step", f"{s.method} is implicit (unconditionally "
                             "stable): its step is chosen for accuracy, not from the "
                             "eigenvalues; set auto_step = false and the step"))
        elif s.auto_step and s.method not in CALIBRATED_METHODS:
            problems.append(("solver.auto_step", f"the automatic step is calibrated for "
                             f"{', '.join(CALIBRATED_METHODS)}, not {s.method} (whose stability "
                             "region is smaller): set auto_step = false and a step that "
                             f"suits {s.method}, or use RK44"))
        return SolverSettings(method=s.method, step=step, timeout=timeout,
                              halvings=s.halvings, auto_step=s.auto_step,
                              spectral_radius=s.spectral_radius)

    def _resolve_groups(self, problems) -> dict[str, tuple[str, ...]]:
        if self.model is None:
            return {}
        groups = self.model.groups() if self.spec.groups is None else \
            {k: tuple(v) for k, v in self.spec.groups.items()}
        seen: dict[str, str] = {}
        for g, members in groups.items():
            if not members:
                problems.append((f"groups.{g}", "a group needs at least one parameter"))
            for m in members:
                if self.parameters is not None and m not in self.parameters:
                    problems.append((f"groups.{g}", f"unknown parameter {m!r}"))
                if m in seen:
                    problems.append((f"groups.{g}", f"parameter {m!r} is already in group "
                                                    f"{seen[m]!r}"))
                seen[m] = g
        return groups

    def variable_names(self) -> list[str]:
        """All design variables of the study (groups first-member order of the model)."""
        if self.parameters is None:
            return []
        return DesignSpace.from_parameters(self.parameters, self.groups).names

    def _check_stages(self, problems) -> None:
        from .plugins import designs, scorers, surrogates

        names = [s.name for s in self.spec.stages]
        all_vars = set(self.variable_names())
        for i, st in enumerate(self.spec.stages):
            where = f"stages[{i}]"
            if names.count(st.name) > 1:
                problems.append((f"{where}.name", f"duplicate stage name {st.name!r}"))
            try:
                designs.get(st.design)
            except UnknownPluginError as err:
                problems.append((f"{where}.design", str(err)))
            labels = []
            for j, sc in enumerate(st.scorers):
                try:
                    scorers.get(sc.name)
                except UnknownPluginError as err:
                    problems.append((f"{where}.scorers[{j}].name", str(err)))
                if sc.channel is not None and self.model is not None and \
                        sc.channel not in (*self.model.sensors, "force"):
                    problems.append((f"{where}.scorers[{j}].channel",
                                     f"unknown channel {sc.channel!r}; the model has "
                                     f"{', '.join(self.model.sensors)}"))
                if sc.key in labels:
                    problems.append((f"{where}.scorers[{j}].label",
                                     f"duplicate scorer label {sc.key!r}"))
                labels.append(sc.key)
            seen_sur = []
            for j, sur in enumerate(st.surrogates):
                try:
                    surrogates.get(sur.name)
                except UnknownPluginError as err:
                    problems.append((f"{where}.surrogates[{j}]", str(err)))
                if sur.key in seen_sur:
                    problems.append((f"{where}.surrogates[{j}].label",
                                     f"duplicate surrogate label {sur.key!r}"))
                seen_sur.append(sur.key)
            if st.select is not None and st.select.by is not None and st.select.by not in labels:
                problems.append((f"{where}.select.by", f"no scorer labelled {st.select.by!r} "
                                                       f"in this stage ({', '.join(labels)})"))
            if isinstance(st.variables, str) and st.variables.startswith("selected:"):
                ref = st.variables.split(":", 1)[1]
                if ref not in names[:i]:
                    problems.append((f"{where}.variables",
                                     f"no earlier stage named {ref!r}"))
                elif self.spec.stages[names.index(ref)].select is None:
                    problems.append((f"{where}.variables",
                                     f"stage {ref!r} has no [select] to take variables from"))
            elif isinstance(st.variables, list):
                for v in st.variables:
                    if all_vars and v not in all_vars:
                        problems.append((f"{where}.variables",
                                         f"unknown design variable {v!r}; known: "
                                         f"{', '.join(sorted(all_vars))}"))
            if self.parameters is not None:
                changes, _ = self._overrides(st.bounds, self.parameters, f"{where}.bounds",
                                             problems)
                self.stage_bounds[st.name] = changes

    # ---- use ---------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.spec.study.name

    @property
    def stages(self) -> list[StageSpec]:
        return self.spec.stages

    def space(self, stage: StageSpec, variables: list[str] | None) -> DesignSpace:
        """Design space of ``stage`` (``variables=None``: all of the study's variables)."""
        return DesignSpace.from_parameters(self.parameters, self.groups, select=variables,
                                           bounds=self.stage_bounds.get(stage.name, {}))

    def model_ref(self) -> dict[str, Any]:
        return {"name": self.spec.model.name, "options": dict(self.spec.model.options)}
