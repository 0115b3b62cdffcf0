"""The schema of a study file: one pydantic model per TOML section (unknown keys are
errors). Values with units stay strings here; :mod:`sensfw.study` resolves them against the
model and the registries."""

from __future__ import annotations

from typing import Annotated, Any, Literal, get_args

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StrictInt, field_validator

from ..models.stepsize import DEFAULT_TOLERANCE


def _no_bool(value: Any) -> Any:
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        got = str(value).lower() if isinstance(value, bool) else repr(value)
        raise ValueError(f"expected a number or a quantity with its unit (\"1e6 N/mm\"), "
                         f"got {got}")
    return value


#: a value with or without its unit: "1e6 N/mm", 1e6, 3; a ``true`` (a typo in a study
#: file) is an error, not the number 1 that pydantic's lax mode would make of it
Quantity = Annotated[str | float | int, BeforeValidator(_no_bool)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


#: a seed: a non-negative integer as written (numpy's generators refuse negative seeds, and
#: "7", true or 1.0 are typos for a study file, not seeds)
Seed = Annotated[StrictInt, Field(ge=0)]


class StudyInfo(_Strict):
    name: str
    description: str = ""
    seed: Seed = 0


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
    seed: Seed = 0  # random
    drive: Literal["auto", "measured", "ideal"] = "auto"
    gain: GainSection | None = None


class SolverSection(_Strict):
    # explicit Runge-Kutta methods, or Exudyn's implicit ones (stiff models: the bolted beam)
    method: Literal["RK44", "RK67", "ExplicitMidpoint", "ExplicitEuler", "DOPRI5",
                    "GeneralizedAlpha", "TrapezoidalIndex2"] = "RK44"
    step: Quantity = "1e-5 s"
    timeout: Quantity | None = None
    halvings: int = Field(default=1, ge=0, le=4)  # retries at half the step after divergence
    # smaller steps where the run's linearised eigenvalues need them (models/stepsize.py),
    # adaptive steps with this absolute error tolerance where they are over-damped and stiff
    auto_step: bool = True
    tolerance: float = Field(default=DEFAULT_TOLERANCE, gt=0, lt=1e-3)
    # over-damped stiff runs (friction stick band): DOPRI5 with error control
    # (``tolerance``), or velocity Verlet at a fixed step (faster, first order); see
    # models/stepsize.py
    stiff_method: Literal["DOPRI5", "VelocityVerlet"] = "DOPRI5"
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


class _PluginSpec(BaseModel):
    """A plugin named in a stage with its options (every other key; checked against the
    plugin's declared options, :mod:`sensfw.options`); ``label`` names it in the results
    (default: its name)."""

    model_config = ConfigDict(extra="allow")
    name: str
    label: str | None = None

    def options(self) -> dict[str, Any]:
        return dict(self.model_extra or {})

    @property
    def key(self) -> str:
        return self.label or self.name


class ScorerSpec(_PluginSpec):
    """A scorer, its options and the channel it scores (default: the study's output)."""

    channel: str | None = None


class SurrogateSpec(_PluginSpec):
    """A surrogate and its options."""


class SelectSpec(_Strict):
    by: str | None = None  # scorer label; default: the stage's first scorer
    threshold: float = Field(default=0.10, ge=0.0)
    max_variables: int | None = Field(default=None, ge=1)

    @field_validator("threshold")
    @classmethod
    def _below_one(cls, v: float) -> float:
        if v >= 1.0:
            raise ValueError(f"{v:g} selects nothing: importance is normalised to at most 1 "
                             "(the most important variable) and a variable is selected "
                             "above the threshold; use a value in [0, 1)")
        return v


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

    @property
    def groups(self) -> dict[str, list[str]]:
        """The groups this stage's design screens (``design_options.groups`` of ``oat`` or
        ``morris``; empty without): a later stage's ``selected:NAME`` takes their members."""
        return dict(self.design_options.get("groups") or {})

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
        if isinstance(v, list) and not v:
            raise ValueError("an empty list: a stage needs at least one variable")
        return v


class CalibrationResult(_Strict):
    """What a calibration found, written into the calibrated study by ``sensfw calibrate``
    and ``sensfw augment`` (:mod:`sensfw.measure.prediction` draws the prediction band of
    ``sensfw compare`` from it): the calibrated quantities in order, their coding, the
    calibrated point and its Laplace covariance in that coding, and the records it saw."""

    parameters: list[str]
    scales: list[Literal["linear", "log", "log1p"]]
    coded: list[float]
    covariance: list[list[float]]
    records: list[dict[str, str | float]] = Field(default_factory=list)


#: how a band entry's standard error is estimated (``[calibration] noise``; the models are
#: described at :data:`sensfw.measure.compare.NOISE_MODELS`)
NoiseModel = Literal["scatter", "propagated"]
NOISE_MODELS: tuple[str, ...] = get_args(NoiseModel)


class CalibrationSection(_Strict):
    """The base parameters diagnosis calibrates (design-variable names), optionally with
    narrower bounds; without it, every variable the screening stage ranks above its
    threshold. ``noise``: how the standard error of a band entry of the residual vector is
    estimated, ``"scatter"`` (the record's scatter about a local fit, the default) or
    ``"propagated"`` (its white noise on output and excitation carried through the band's
    H1, with the THD read against the record's noise floor; :mod:`sensfw.measure.discrepancy`).
    ``result``: what the calibration that wrote the study found."""

    parameters: list[str] | None = None
    bounds: dict[str, ParameterOverride] = Field(default_factory=dict)
    #: how a band entry's standard error is estimated (:data:`NOISE_MODELS`)
    noise: NoiseModel = "scatter"
    result: CalibrationResult | None = None

    @field_validator("parameters")
    @classmethod
    def _not_empty(cls, v: list[str] | None) -> list[str] | None:
        if v is not None and not v:
            raise ValueError("an empty list calibrates nothing (it ran a screen to choose "
                             "the parameters instead): name at least one, or leave "
                             "parameters out to take the screen's selection")
        return v


class CompareSection(_Strict):
    """A published study to set a stage's Eq. 18 results beside (the report's comparison
    section): ``reference`` names a data file of :mod:`sensfw.analysis.paper_comparison`,
    ``factors`` maps the reference's factors to the stage's design variables and
    ``responses`` its responses to the stage's scorer labels."""

    reference: str
    stage: str
    factors: dict[str, str] = Field(default_factory=dict)
    responses: dict[str, str] = Field(default_factory=dict)


class AgreeSection(_Strict):
    """A finished run of a fuller pipeline on the same model (its output folder: absolute,
    relative to the study file, or else to the working folder) whose conclusions the report
    checks this study against (:mod:`sensfw.analysis.agreement`): the selection of stage
    ``screen`` and the second stage ``stage``, named alike in both studies."""

    results: str
    screen: str = "screen"
    stage: str = "doe"


class StudyFile(_Strict):
    study: StudyInfo
    model: ModelSection = Field(default_factory=ModelSection)
    excitation: ExcitationSection = Field(default_factory=ExcitationSection)
    solver: SolverSection = Field(default_factory=SolverSection)
    execution: ExecutionSection = Field(default_factory=ExecutionSection)
    parameters: dict[str, ParameterOverride] = Field(default_factory=dict)
    groups: dict[str, list[str]] | None = None  # None: the model's default grouping
    stages: list[StageSpec] = Field(min_length=1)
    calibration: CalibrationSection | None = None
    compare_with: CompareSection | None = None
    agree_with: AgreeSection | None = None
