"""The :class:`Study`: a study file's content resolved against the model and the
registries (model, parameters with their bound overrides, groups, excitation, solver), with
every problem of the file reported at once (:mod:`sensfw.study`)."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, get_args, get_origin

from pydantic import BaseModel, ValidationError

from ..errors import SensfwError, StudyError
from ..excitation import Excitation, make_excitation
from ..models.base import IMPLICIT_METHODS, Model, SolverSettings
from ..models.stepsize import CALIBRATED_METHODS
from ..params import DesignSpace, Parameter, ParameterSet, clashing_group_names
from .checks import Problems, bound_overrides, check_stages, plugin_problems
from .schema import GainSection, StageSpec, StudyFile
from .units import to_unit


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


def _real_loc(data: Any, error: Mapping[str, Any]) -> tuple:
    """The location of a pydantic ``error`` up to the last key the data has: without the
    member tags of a union (``f1.str``, ``f1.float``: a list where a quantity belongs is one
    problem at ``f1``); a missing key's location as it is."""
    loc = tuple(error["loc"])
    if error["type"] in ("missing", "extra_forbidden"):
        return loc
    node, out = data, []
    for part in loc:
        found = (part in node) if isinstance(node, Mapping) else \
            isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node)
        if not found:
            break
        node = node[part]
        out.append(part)
    return tuple(out)


def _within(path: str, other: str) -> bool:
    """Whether the dotted ``path`` is ``other`` or inside it."""
    return path == other or path.startswith((other + ".", other + "["))


def _section(loc: tuple) -> type[BaseModel] | None:
    """The schema model of the table that holds the key at ``loc`` (None: a free-form table)."""
    node: Any = StudyFile
    for part in loc[:-1]:
        if isinstance(part, int):
            continue
        if isinstance(node, type) and issubclass(node, BaseModel):
            field = node.model_fields.get(part)
            if field is None:
                return None
            node = field.annotation
        else:  # a table of named entries ([parameters.NAME], stages[i].bounds.NAME)
            node = next((a for a in get_args(node)[1:]), None)
        node = _model_in(node)
        if node is None:
            return None
    return node


def _model_in(annotation: Any) -> Any:
    """The schema model (or dict of them) an annotation holds: ``X | None``, ``list[X]``."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    if get_origin(annotation) is dict:
        return annotation
    for arg in get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _unknown_key(loc: tuple) -> str:
    """What to say of an unknown key: the keys its table knows, the closest first."""
    import difflib

    section = _section(loc)
    if section is None or not isinstance(section, type):
        return "unknown key"
    known = list(section.model_fields)
    close = difflib.get_close_matches(str(loc[-1]), known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return f"unknown key{hint}; known: {', '.join(known)}"


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
        before = len(problems)
        self.groups = self._resolve_groups(problems)
        # every design variable is made of the groups: with a bad group the stages are
        # checked without their variables (designs, scorers, surrogates, references)
        grouped = len(problems) == before
        found, self.stage_bounds = check_stages(
            spec.stages, parameters=self.parameters if grouped else None,
            groups=self.groups if grouped else {}, excitation=self.excitation,
            sensors=None if self.model is None else self.model.sensors,
            accepted=None if self.model is None else self.model.parameters(),
            model=self.spec.model.name)
        problems += found
        if not grouped:
            raise StudyError(problems, source)
        self.calibration_bounds = self._check_calibration(problems)
        self._check_comparison(problems)
        if problems:
            raise StudyError(problems, source)

    # ---- construction ------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str | None = None) -> Study:
        try:
            spec = StudyFile.model_validate(data)
        except ValidationError as err:
            errors = [(_real_loc(data, e), e) for e in err.errors()]
            # a validator's own message without pydantic's "Value error, " in front
            problems = [(_path(loc), _unknown_key(loc) if e["type"] == "extra_forbidden"
                         else e["msg"].removeprefix("Value error, ")) for loc, e in errors]
            # one bad value should not hide the other problems: without the values pydantic
            # refused (each table's default takes its place) the file is checked again and
            # what that finds elsewhere is reported too; not where a required value or a
            # list's item is bad (dropping it would leave the file invalid, or move the
            # items after it to other indices)
            locs = [loc for loc, e in errors]
            if all(e["type"] != "missing" and loc and not isinstance(loc[-1], int)
                   for loc, e in errors):
                try:
                    cleaned = StudyFile.model_validate(_without(data, locs))
                except ValidationError:
                    cleaned = None
                if cleaned is not None:
                    told = [_path(loc) for loc in locs]
                    try:
                        cls(cleaned, source)
                    except StudyError as more:
                        problems += [(path, msg) for path, msg in more.problems
                                     if not any(_within(path, t) for t in told)]
            raise StudyError(list(dict.fromkeys(problems)), source) from None
        return cls(spec, source)

    @classmethod
    def load(cls, path: str | Path) -> Study:
        path = Path(path)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise StudyError([("", "file not found")], str(path)) from None
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
            raise StudyError([("", f"not valid TOML: {err}")], str(path)) from None
        return cls.from_dict(data, str(path))

    # ---- resolution --------------------------------------------------------------------------
    def _resolve_model(self, problems: Problems) -> Model | None:
        from ..plugins import models

        model, found = plugin_problems(models, self.spec.model.name, self.spec.model.options,
                                       "model.options", name_at="model.name")
        problems += found
        if model is None:
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
        changes, found = bound_overrides(self.spec.parameters, declared, "parameters",
                                         self.model.parameters(), self.spec.model.name)
        problems += found
        return None if found else declared.with_bounds(changes)

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
        if "amplitude" in vals and not vals["amplitude"] > 0:
            problems.append(("excitation.amplitude", f"{e.amplitude} must be positive"))
            del vals["amplitude"]
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
        except SensfwError as err:
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
        if timeout is not None and not timeout > 0:
            problems.append(("solver.timeout", f"{s.timeout} must be positive (leave it out "
                                               "for no timeout)"))
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
                              tolerance=s.tolerance, stiff_method=s.stiff_method,
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
                    problems.append((f"groups.{g}", f"parameter {m!r} is listed twice" if
                                     seen[m] == g else f"parameter {m!r} is already in "
                                     f"group {seen[m]!r}"))
                seen[m] = g
        if self.parameters is not None:
            problems += [(f"groups.{g}", f"the group's name is the parameter {g!r}, which is "
                                         "not one of its members; name the group otherwise")
                         for g in clashing_group_names(groups, self.parameters)]
        return groups

    def variable_names(self) -> list[str]:
        """All design variables of the study (groups first-member order of the model)."""
        if self.parameters is None:
            return []
        return DesignSpace.from_parameters(self.parameters, self.groups).names

    def _check_calibration(self, problems) -> dict:
        cal = self.spec.calibration
        if cal is None or self.parameters is None:
            return {}
        known = set(self.variable_names())
        for i, name in enumerate(cal.parameters or []):
            if name not in known:
                problems.append((f"calibration.parameters[{i}]",
                                 f"unknown design variable {name!r}; known: "
                                 f"{', '.join(sorted(known))}"))
            elif name in (cal.parameters or [])[:i]:
                problems.append((f"calibration.parameters[{i}]", f"{name!r} is listed twice"))
        changes, found = bound_overrides(cal.bounds, self.parameters, "calibration.bounds")
        problems += found
        r = cal.result
        if r is not None:
            d = len(r.parameters)
            for i, name in enumerate(r.parameters):
                if name not in known:
                    problems.append((f"calibration.result.parameters[{i}]",
                                     f"unknown design variable {name!r}"))
            for key, n in (("scales", len(r.scales)), ("coded", len(r.coded)),
                           ("covariance", len(r.covariance))):
                if n != d:
                    problems.append((f"calibration.result.{key}", f"{n} entries for {d} "
                                     "parameters"))
            if any(len(row) != d for row in r.covariance):
                problems.append(("calibration.result.covariance", f"not a {d} x {d} matrix"))
        return changes

    def calibration_space(self, variables: list[str]) -> DesignSpace:
        """The design space diagnosis calibrates: ``variables`` with the study's and the
        ``[calibration]`` bounds."""
        return DesignSpace.from_parameters(self.parameters, self.groups, select=variables,
                                           bounds=self.calibration_bounds)

    def _check_comparison(self, problems) -> None:
        """``[compare_with]``: the reference exists and maps onto a stage's variables and
        scorers (:func:`sensfw.analysis.paper_comparison.check_study`); ``[agree_with]``:
        its stages exist here (:func:`sensfw.analysis.agreement.check_study`)."""
        if self.spec.compare_with is not None:
            from ..analysis.paper_comparison import check_study

            check_study(self, problems)
        if self.spec.agree_with is not None:
            from ..analysis.agreement import check_study as check_agreement

            check_agreement(self, problems)

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
