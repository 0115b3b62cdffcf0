"""Declarative study files (TOML): their schema, their checks and the resolved :class:`Study`.

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

* :mod:`.schema` — the file's schema, one pydantic model per section;
* :mod:`.units` — values with units;
* :mod:`.checks` — the checks of stages and plugins, pure functions of the parsed file;
* :mod:`.resolve` — :class:`Study`, the file resolved against the model and the registries;
* :mod:`.edit` — editing a study file in place, comments kept (``sensfw augment``).
"""

from .resolve import Study
from .schema import (
    CalibrationSection,
    ExcitationSection,
    ExecutionSection,
    GainSection,
    ModelSection,
    ParameterOverride,
    Quantity,
    ScorerSpec,
    SelectSpec,
    SolverSection,
    StageSpec,
    StudyFile,
    StudyInfo,
    SurrogateSpec,
)
from .units import to_unit, units

__all__ = ["CalibrationSection", "ExcitationSection", "ExecutionSection", "GainSection",
           "ModelSection", "ParameterOverride", "Quantity", "ScorerSpec", "SelectSpec",
           "SolverSection", "StageSpec", "Study", "StudyFile", "StudyInfo", "SurrogateSpec",
           "to_unit", "units"]
