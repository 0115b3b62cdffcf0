"""Test-only models, used by the test suite through their ``"module:Class"`` names
(``"sensfw_test_models:FaultInjection"``), not shipped as built-ins that ``sensfw plugins``
offers users.

Why a module name and not a runtime ``models.add(...)``: runs execute in other processes
(forkserver pool workers, spawned timeout guards, Dask workers, ``python -m sensfw``
subprocesses), which import sensfw afresh and would not see a registration made in the test
process. ``tests/conftest.py`` puts this folder on ``sys.path`` and ``PYTHONPATH`` so that
every such process can import the module, and the registry imports ``"module:Class"`` names
on first use (:mod:`sensfw.registry`).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping

import numpy as np

from sensfw.errors import DivergenceError
from sensfw.excitation import Chirp
from sensfw.models.analytic import scalar_signals
from sensfw.models.base import Model, Signals, SolverSettings
from sensfw.params import Parameter, ParameterSet
from sensfw.plugins import models

FAULT_INJECTION = "sensfw_test_models:FaultInjection"
NOISY_QUADRATIC = "sensfw_test_models:NoisyQuadratic"


class FaultInjection(Model):
    """Another model with injected faults, for testing fault tolerance.

    Options map a fault to a condition ``{"parameter": name, "above": value}`` (or
    ``"below"``, or both: outside the interval): ``diverge``
    raises the model's divergence error, ``hang`` sleeps ``hang_seconds``, ``crash`` kills
    the worker process (``os._exit``). ``slow`` adds ``slow_seconds`` to every run;
    ``chatter`` is printed to stdout by every run (through Python and through the file
    descriptor, as a C library would); ``unpicklable`` puts a function into every run's
    ``signals.meta``.
    """

    name = "fault_injection"
    version = "1"

    def __init__(self, model: str = "ishigami", model_options: dict | None = None,
                 diverge: dict | None = None, hang: dict | None = None,
                 crash: dict | None = None, hang_seconds: float = 3600.0,
                 slow_seconds: float = 0.0, chatter: str = "", unpicklable: bool = False):
        self.inner = models.get(model)(**(model_options or {}))
        self.sensors, self.default_output = self.inner.sensors, self.inner.default_output
        self.faults = {"diverge": diverge, "hang": hang, "crash": crash}
        self.hang_seconds, self.slow_seconds = float(hang_seconds), float(slow_seconds)
        self._spec = {"model": model, "model_options": model_options or {},
                      **{k: v for k, v in self.faults.items() if v},
                      "hang_seconds": hang_seconds, "slow_seconds": slow_seconds,
                      **({"chatter": chatter} if chatter else {}),
                      **({"unpicklable": True} if unpicklable else {})}
        self.chatter, self.unpicklable = chatter, unpicklable

    def parameters(self) -> ParameterSet:
        return self.inner.parameters()

    def groups(self):
        return self.inner.groups()

    def options(self) -> dict:
        return self._spec

    def _hit(self, fault: str, p: Mapping[str, float]) -> bool:
        cond = self.faults[fault]
        if not cond:
            return False
        v = p[cond["parameter"]]
        return v > cond.get("above", math.inf) or v < cond.get("below", -math.inf)

    def simulate(self, params, excitation: Chirp, solver: SolverSettings | None = None):
        p = self.parameters().complete(params)
        if self.chatter:
            print(self.chatter, flush=True)
            os.write(1, self.chatter.encode() + b"\n")
        if self.slow_seconds:
            time.sleep(self.slow_seconds)
        if self._hit("crash", p):
            os._exit(13)
        if self._hit("hang", p):
            time.sleep(self.hang_seconds)
        if self._hit("diverge", p):
            raise DivergenceError(self.name, "diverged (injected fault)", p)
        signals = self.inner.simulate(p, excitation, solver)
        if self.unpicklable:
            signals.meta["callback"] = lambda: None
        return signals


class NoisyQuadratic(Model):
    """``y = 1 + x1 - 2 x2 + 1.5 x1^2 + 0.5 x1 x3 + noise`` on [-1, 1]^3 with Gaussian noise
    of standard deviation ``noise``, drawn from a generator seeded by the parameter values
    (the same run gives the same value: runs stay cacheable). A test model for regression
    validation: Eq. 18 is the true model, so its prediction intervals must cover at their
    nominal level."""

    name = "noisy_quadratic"
    version = "1"
    sensors = ("y",)
    default_output = "y"

    def __init__(self, noise: float = 0.2):
        self.noise = float(noise)

    def parameters(self) -> ParameterSet:
        return ParameterSet([Parameter(f"x{i}", "", 0.0, -1.0, 1.0) for i in (1, 2, 3)])

    def options(self) -> dict:
        return {"noise": self.noise}

    def simulate(self, params, excitation=None, solver=None) -> Signals:
        import hashlib

        p = self.parameters().complete(params)
        x1, x2, x3 = p["x1"], p["x2"], p["x3"]
        seed = int.from_bytes(hashlib.sha256(repr((x1, x2, x3)).encode()).digest()[:8],
                              "little")
        eps = np.random.default_rng(seed).standard_normal()
        y = 1 + x1 - 2 * x2 + 1.5 * x1**2 + 0.5 * x1 * x3 + self.noise * eps
        return scalar_signals({"y": y})
