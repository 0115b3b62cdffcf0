"""The model contract: what a simulation model declares and returns."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from ..errors import DivergenceError, SignalError
from ..excitation import Excitation
from ..params import ParameterSet
from .places import Hooks, Place, attach_effects
from .stepsize import DEFAULT_TOLERANCE, STIFF_METHOD


@dataclass
class Signals:
    """Sampled signals of one run (simulated or measured).

    ``force`` is the excitation force (N, the FRF input); ``channels`` maps a sensor name to
    its samples (accelerations in m/s^2); ``f_inst`` is the sweep's instantaneous frequency
    per sample (Hz), the rotation frequency of the order analysis.
    """

    t: np.ndarray
    force: np.ndarray
    channels: dict[str, np.ndarray]
    fs: float
    f_inst: np.ndarray | None = None
    units: dict[str, str] = field(default_factory=dict)
    meta: dict = field(default_factory=dict)
    sweep_end: float | None = None  # time (s) at which the sweep ends (a silent tail follows)

    def __post_init__(self) -> None:
        n = len(self.t)
        for name, x in [("force", self.force), *self.channels.items()]:
            if len(x) != n:
                raise SignalError(f"signal {name!r} has {len(x)} samples, time has {n}")

    def channel(self, name: str) -> np.ndarray:
        if name == "force":
            return self.force
        try:
            return self.channels[name]
        except KeyError:
            raise SignalError(
                f"no channel {name!r}; available: {', '.join(['force', *self.channels])}"
            ) from None

    def sweep(self) -> Signals:
        """The part recorded while the sweep runs (without the silent tail): what order
        analysis looks at, since the tail holds ring-down only."""
        if self.sweep_end is None:
            return self
        n = min(len(self.t), max(8, round(self.sweep_end * self.fs)))
        return Signals(t=self.t[:n], force=self.force[:n],
                       channels={k: v[:n] for k, v in self.channels.items()}, fs=self.fs,
                       f_inst=None if self.f_inst is None else self.f_inst[:n],
                       units=dict(self.units), meta=dict(self.meta), sweep_end=None)

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Flat dict of arrays (for ``np.savez``)."""
        out = {"t": self.t, "force": self.force, "fs": np.array(self.fs)}
        if self.sweep_end is not None:
            out["sweep_end"] = np.array(self.sweep_end)
        if self.f_inst is not None:
            out["f_inst"] = self.f_inst
        out.update({f"ch:{k}": v for k, v in self.channels.items()})
        return out

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, np.ndarray], **kw) -> Signals:
        channels = {k[3:]: np.asarray(v) for k, v in arrays.items() if k.startswith("ch:")}
        f_inst = arrays["f_inst"] if "f_inst" in arrays else None
        end = float(arrays["sweep_end"]) if "sweep_end" in arrays else None
        return cls(t=np.asarray(arrays["t"]), force=np.asarray(arrays["force"]),
                   channels=channels, fs=float(arrays["fs"]), f_inst=f_inst, sweep_end=end,
                   **kw)


def check_channels(model: str, channels: Mapping[str, np.ndarray], n: int,
                   params: Mapping[str, float], step: float | None, unit: str = "") -> None:
    """Raise :class:`~sensfw.errors.DivergenceError` for the first channel that is not ``n``
    finite samples, or that exceeds 1e7 (``unit``): a run that blew up."""
    limit = f"1e7 {unit}" if unit else "1e7"
    for name, x in channels.items():
        if len(x) != n or not np.all(np.isfinite(x)):
            raise DivergenceError(model, f"diverged (non-finite {name!r})", params, step=step)
        if np.max(np.abs(x)) > 1e7:
            raise DivergenceError(model, f"diverged ({name!r} exceeds {limit})", params,
                                  step=step)


#: the description of a model's ``effects`` option (:mod:`sensfw.options`)
EFFECTS = ("a list of effects: registered names or {name, attach} tables "
           "(`sensfw places MODEL` lists where each fits)")

#: Exudyn's implicit integrators (unconditionally stable; the step is chosen for accuracy)
IMPLICIT_METHODS = ("GeneralizedAlpha", "TrapezoidalIndex2")


@dataclass(frozen=True)
class SolverSettings:
    """Time integration settings that enter the run hash.

    ``step`` is the largest step; a model may take a smaller one: always one that divides
    the output sample period, and with ``auto_step`` one that keeps the fastest eigenvalues
    of the run's own parameters within the integrator's accuracy limits
    (:mod:`sensfw.models.stepsize`), or, where an over-damped eigenvalue would force a much
    smaller fixed step, the ``stiff_method``: error-controlled adaptive DOPRI5 steps of at
    most ``step`` with the absolute ``tolerance`` (resampled onto the output grid,
    :mod:`sensfw.models.integration`), or velocity Verlet at a fixed step (faster, first
    order; :mod:`sensfw.models.stepsize`).
    The step a run used is in ``signals.meta["step"]``, the integrator in
    ``signals.meta["integrator"]``.
    """

    method: str = "RK44"
    step: float = 1e-5
    timeout: float | None = None  # wall seconds per run; None = no limit
    halvings: int = 1  # retries with half the step after a divergence (explicit stability)
    auto_step: bool = True
    tolerance: float = DEFAULT_TOLERANCE  # absolute error tolerance of adaptive runs
    stiff_method: str = STIFF_METHOD  # over-damped stiff runs: "DOPRI5" or "VelocityVerlet"
    #: numerical dissipation of the implicit generalised-alpha method (rho_inf, 0..1)
    spectral_radius: float = 0.8

    def to_dict(self) -> dict:
        out = {"method": self.method, "step": self.step, "halvings": self.halvings,
               "auto_step": self.auto_step, "tolerance": self.tolerance}
        if self.stiff_method != STIFF_METHOD:  # runs of the default keep their hashes
            out["stiff_method"] = self.stiff_method
        if self.method in IMPLICIT_METHODS:  # explicit runs keep the hashes they had
            out["spectral_radius"] = self.spectral_radius
        return out


class Model(ABC):
    """A simulation model plugin (group ``sensfw.models``).

    Subclasses declare ``name``, ``version``, their :meth:`parameters` (name, unit, nominal,
    bounds), the default grouping of parameters into design variables (:meth:`groups`) and
    their ``sensors``; :meth:`simulate` turns a full parameter dict and an excitation into
    :class:`Signals`.

    A model that takes physical effects declares its :meth:`places` and which of them it
    prefers per effect (:attr:`preferred_places`), calls ``super().__init__(effects)`` once
    its places are known, and applies them with :meth:`apply_effects` while it assembles
    itself; :meth:`with_effect_parameters` and :meth:`effect_options` add their parameters
    and specs. Effects are resolved against the model here and nowhere else: the model
    never names an effect, nor an effect a model's place.
    """

    name: str = "model"
    version: str = "0"
    sensors: tuple[str, ...] = ()
    #: the SI unit of each sensor's signal (``"m/s^2"``, ``"m/s"``, ...) where the model
    #: states it: a measured channel of another quantity is refused, not compared
    units: ClassVar[Mapping[str, str]] = {}
    default_output: str = ""
    #: effect name -> the places tried first when such an effect is added without
    #: ``attach`` (else the only place it fits; else the effect must say where)
    preferred_places: ClassVar[Mapping[str, tuple[str, ...]]] = {}
    #: the model's effects, each with ``attach`` resolved, and the place each acts at
    effects: tuple = ()
    attached: tuple = ()

    def __init__(self, effects: Sequence = ()):
        """Resolve ``effects`` (registered names, ``{"name": ..., "attach": ...}`` specs or
        :class:`sensfw.effects.Effect` objects) against the model's places
        (:func:`~sensfw.models.places.attach_effects`: every problem at its path,
        ``effects[1].attach``, in one :class:`~sensfw.errors.OptionError`)."""
        self.effects, self.attached = attach_effects(self.places(), effects, self.name,
                                                     self.preferred_places)

    @abstractmethod
    def parameters(self) -> ParameterSet: ...

    def groups(self) -> dict[str, tuple[str, ...]]:
        return {}

    def options(self) -> dict:
        """Model options that change results (enter the run hash)."""
        return {}

    def places(self) -> dict[str, Place]:
        """Where effects can act (:mod:`sensfw.models.places`); none by default."""
        return {}

    def with_effect_parameters(self, own: ParameterSet) -> ParameterSet:
        """``own`` (the model's parameters) followed by those its effects add."""
        extra = [p for e in self.effects for p in e.parameters()]
        return ParameterSet([*own.values(), *extra]) if extra else own

    def effect_options(self) -> dict:
        """``{"effects": [spec, ...]}`` for :meth:`options` (empty without effects); an
        effect whose physics was revised (:attr:`Effect.revision`) carries its revision, so
        runs of its former physics are not reused."""
        return {"effects": [{**e.spec(), **({"revision": e.revision}
                                            if getattr(e, "revision", 0) else {})}
                            for e in self.effects]} if self.effects else {}

    def apply_effects(self, hooks: Hooks, p: Mapping[str, float]) -> None:
        """Apply every effect at its place through ``hooks`` (the model's assembly) for the
        full parameter values ``p``."""
        for effect, place in self.attached:
            effect.apply(place, hooks, p)

    @abstractmethod
    def simulate(
        self, params: Mapping[str, float], excitation: Excitation,
        solver: SolverSettings | None = None,
    ) -> Signals: ...
