"""What identifies one simulation run, and how a worker executes it."""

from __future__ import annotations

import hashlib
import json
import math
import pickle
import time
import traceback
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from ..errors import DivergenceError, SensfwError, SimulationError
from ..excitation import Excitation, make_excitation
from ..models.base import Model, Signals, SolverSettings


def _canonical(obj: Any) -> Any:
    """JSON-stable form: floats by repr (exact), dict keys sorted, tuples as lists."""
    if isinstance(obj, float):
        if not math.isfinite(obj):
            return str(obj)
        return float(repr(obj)) if obj != 0 else 0.0
    if isinstance(obj, Mapping):
        return {str(k): _canonical(v) for k, v in sorted(obj.items(), key=lambda kv: str(kv[0]))}
    if isinstance(obj, (list, tuple)):
        return [_canonical(v) for v in obj]
    if hasattr(obj, "item") and callable(obj.item):  # numpy scalar
        return _canonical(obj.item())
    return obj


@dataclass(frozen=True)
class RunSpec:
    """One simulation: model (name, version, options), full parameter values, excitation and
    solver settings. Its :meth:`key` (a hash of all of these) names the run in the store, so
    the same run is never computed twice."""

    model: str
    model_version: str
    params: Mapping[str, float]
    excitation: Mapping[str, float]
    solver: Mapping[str, Any]
    model_options: Mapping[str, Any] = field(default_factory=dict)
    timeout: float | None = None  # wall seconds; not part of the key

    def identity(self) -> dict:
        excitation = dict(self.excitation)
        if "samples" in excitation:  # a recorded excitation enters by its content hash
            excitation = make_excitation(excitation).identity()
        return _canonical({
            "model": self.model, "model_version": self.model_version,
            "model_options": dict(self.model_options), "params": dict(self.params),
            "excitation": excitation, "solver": dict(self.solver),
        })

    def key(self) -> str:
        blob = json.dumps(self.identity(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode()).hexdigest()[:24]

    @classmethod
    def create(cls, model: Model, params: Mapping[str, float], excitation: Excitation,
               solver: SolverSettings, model_ref: Mapping[str, Any] | None = None) -> RunSpec:
        """Spec for ``model``; ``model_ref`` (registry name + constructor options) is what a
        worker uses to rebuild the model."""
        ref = dict(model_ref or {"name": model.name, "options": {}})
        return cls(model=ref["name"], model_version=str(model.version),
                   params={k: float(v) for k, v in params.items()},
                   excitation=excitation.to_dict(), solver=solver.to_dict(),
                   model_options=_canonical({**ref.get("options", {}),
                                             "_declared": model.options()}),
                   timeout=solver.timeout)


@dataclass
class RunResult:
    """Outcome of one run: signals, or the reason it failed."""

    key: str
    ok: bool
    signals: Signals | None = None
    error: str | None = None
    wall: float = 0.0
    cached: bool = False


def build_model(spec: RunSpec) -> Model:
    from ..plugins import models

    options = {k: v for k, v in spec.model_options.items() if not k.startswith("_")}
    return models.get(spec.model)(**options)


def simulate_with_halving(model: Model, params: dict, excitation: Excitation,
                          solver: SolverSettings) -> Signals:
    """``model.simulate``, retried with half the step after a divergence, up to
    ``solver.halvings`` times: an explicit integrator at a fixed step is only stable while
    step x highest eigenfrequency stays small; a model that chooses its step from its
    linearisation (``auto_step``) rarely gets here, but the dynamics can stiffen beyond the
    static estimate. The retry halves the step that diverged (``err.step`` where the model
    reports it). The step actually used is in ``signals.meta["step"]``; a run that diverges
    at every step fails with all steps named.

    A voltage record drives the model through the parameter ``excitation_gain`` (N/V,
    :func:`sensfw.models.drive.apply_gain`); the signals then carry the voltage as their
    input (``units["force"] == "V"``), as the measurement does."""
    from ..models.drive import GAIN, apply_gain

    gain = params.get(GAIN)
    driving, params = apply_gain(excitation, params)
    step, tried = solver.step, []
    while True:
        try:
            signals = model.simulate(params, driving, replace(solver, step=step))
        except DivergenceError as err:
            used = err.step or step
            tried.append(used)
            if len(tried) > solver.halvings:
                steps = ", ".join(f"{h:g}" for h in tried)
                raise DivergenceError(err.model, f"{err.reason} at step {steps} s",
                                      err.parameters, step=used) from None
            step = used / 2
        else:
            if driving is not excitation:  # the record is the input, as measured
                signals.force = excitation.force(signals.t)
                signals.units["force"] = excitation.unit
                # (a closed-form sweep scaled to N has no gain attribute)
                signals.meta["excitation_gain"] = float(gain)
            signals.meta.setdefault("step", step)
            signals.meta["step_halvings"] = len(tried)
            if tried:  # the step that diverged last is twice the step used
                signals.meta["step_limited_by"] = "divergence"
            return signals


def _picklable_meta(signals: Signals) -> None:
    """Leave out the entries of ``signals.meta`` that cannot be pickled (a function, a
    solver object a model kept there), naming them in ``meta["unpicklable_meta"]``: a
    result goes back from a worker process pickled, and one that cannot be was lost
    there, while the serial backend stored the run (the store keeps no such entry)."""
    dropped = []
    for k, v in list(signals.meta.items()):
        try:
            pickle.dumps(v, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception:
            dropped.append(str(k))
            del signals.meta[k]
    if dropped:
        signals.meta["unpicklable_meta"] = dropped


def execute(spec: RunSpec) -> RunResult:
    """Run one simulation (in a worker). Never raises: a failure becomes a failed result."""
    t0 = time.perf_counter()
    key = spec.key()
    try:
        model = build_model(spec)
        exc = make_excitation(spec.excitation)
        solver = SolverSettings(**{k: v for k, v in spec.solver.items()
                                   if k in SolverSettings.__dataclass_fields__})
        signals = simulate_with_halving(model, dict(spec.params), exc, solver)
        _picklable_meta(signals)
        return RunResult(key, True, signals=signals, wall=time.perf_counter() - t0)
    except SimulationError as err:
        return RunResult(key, False, error=str(err), wall=time.perf_counter() - t0)
    except SensfwError as err:
        return RunResult(key, False, error=f"{type(err).__name__}: {err}",
                         wall=time.perf_counter() - t0)
    except Exception as err:  # a model bug must not lose the study
        tb = traceback.format_exc(limit=3)
        return RunResult(key, False, error=f"{type(err).__name__}: {err}\n{tb}",
                         wall=time.perf_counter() - t0)
