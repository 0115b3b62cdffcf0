"""Analytic test models: the pipeline on problems whose answers are known.

* ``ishigami``: the Ishigami function (Ishigami & Homma 1990) as a model with one scalar
  output channel ``y`` (score it with the ``value`` scorer); analytic Sobol indices are in
  :mod:`sensfw.testing`.
* ``two_dof``: a linear 2-DOF mass-spring-damper driven by the chirp on mass 1, simulated
  by a first-order-hold discretisation of the state space: exact for a force linear between
  samples, and against the smooth chirp off by about ``(w dt)^2 / 12`` of the force's
  part, which the accelerations' cancelling terms below resonance amplify (its FRF is
  within 8e-4 of :meth:`TwoDOF.frf` at 20 kHz, 5e-3 at 8 kHz); channels ``a1``, ``a2``
  (accelerations). Its FRF and eigenfrequencies are known in closed form.

The test suite's fault-injection and noisy-quadratic models are not shipped here: they live in
``tests/support/sensfw_test_models.py`` and are used by their ``"module:Class"`` name.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import ClassVar

import numpy as np
from pydantic import Field

from ..excitation import Chirp
from ..options import Float, PluginOptions
from ..params import Parameter, ParameterSet
from ..plugins import models
from ..testing import ishigami
from .base import Model, Signals


def scalar_signals(values: Mapping[str, float]) -> Signals:
    """Signals holding one sample per channel (for function-type models)."""
    return Signals(t=np.zeros(1), force=np.zeros(1),
                   channels={k: np.array([float(v)]) for k, v in values.items()}, fs=1.0)


@models.register("ishigami")
class Ishigami(Model):
    """``y = sin x1 + a sin^2 x2 + b x3^4 sin x1`` on [-pi, pi]^3
    (:func:`sensfw.testing.ishigami`)."""

    name = "ishigami"
    version = "1"
    sensors = ("y",)
    default_output = "y"

    class Options(PluginOptions):
        a: Float = Field(7.0, description="a number")
        b: Float = Field(0.1, description="a number")

    def __init__(self, a: float = 7.0, b: float = 0.1):
        self.a, self.b = float(a), float(b)

    def parameters(self) -> ParameterSet:
        return ParameterSet([Parameter(f"x{i}", "", 0.0, -math.pi, math.pi) for i in (1, 2, 3)])

    def options(self) -> dict:
        return {"a": self.a, "b": self.b}

    def simulate(self, params, excitation=None, solver=None) -> Signals:
        p = self.parameters().complete(params)
        y = ishigami([[p["x1"], p["x2"], p["x3"]]], self.a, self.b)[0]
        return scalar_signals({"y": y})


@models.register("two_dof")
class TwoDOF(Model):
    """Linear 2-DOF chain: ground -k1,c1- m1 -k2,c2- m2, chirp force on m1."""

    name = "two_dof"
    version = "1"
    sensors = ("a1", "a2")
    units: ClassVar[Mapping[str, str]] = {"a1": "m/s^2", "a2": "m/s^2"}
    default_output = "a1"

    class Options(PluginOptions):
        """None: the chain is fixed, and it has no places for effects."""

    def parameters(self) -> ParameterSet:
        P = Parameter
        return ParameterSet([
            P("m1", "kg", 1.0, 0.5, 2.0), P("m2", "kg", 0.5, 0.25, 1.0),
            P("k1", "N/mm", 4000.0, 2000.0, 8000.0), P("k2", "N/mm", 2000.0, 1000.0, 4000.0),
            P("c1", "N*s/mm", 0.1, 0.05, 0.2), P("c2", "N*s/mm", 0.05, 0.025, 0.1),
        ])

    @staticmethod
    def matrices(p: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """M, K (N/m), C (N s/m) in SI."""
        k1, k2, c1, c2 = (p["k1"] * 1e3, p["k2"] * 1e3, p["c1"] * 1e3, p["c2"] * 1e3)
        M = np.diag([p["m1"], p["m2"]])
        K = np.array([[k1 + k2, -k2], [-k2, k2]])
        C = np.array([[c1 + c2, -c2], [-c2, c2]])
        return M, K, C

    def frf(self, p: Mapping[str, float], f: np.ndarray) -> np.ndarray:
        """Accelerance of both masses for a force on m1: H[:, i] = a_i / F, shape (n, 2)."""
        M, K, C = self.matrices(self.parameters().complete(p))
        out = np.empty((len(f), 2), dtype=complex)
        for i, fi in enumerate(np.asarray(f, float)):
            w = 2 * np.pi * fi
            x = np.linalg.solve(K - w**2 * M + 1j * w * C, np.array([1.0, 0.0]))
            out[i] = -(w**2) * x
        return out

    def simulate(self, params, excitation: Chirp, solver=None) -> Signals:
        from scipy.signal import cont2discrete, dlsim

        p = self.parameters().complete(params)
        M, K, C = self.matrices(p)
        Mi = np.linalg.inv(M)
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ K, -Mi @ C]])
        B = np.vstack([np.zeros((2, 1)), Mi @ np.array([[1.0], [0.0]])])
        Cout = np.hstack([-Mi @ K, -Mi @ C])  # accelerations
        Dout = Mi @ np.array([[1.0], [0.0]])
        dt = 1 / excitation.fs
        Ad, Bd, Cd, Dd, _ = cont2discrete((A, B, Cout, Dout), dt, method="foh")
        t = excitation.time()
        force = excitation.force(t)
        _, acc, _ = dlsim((Ad, Bd, Cd, Dd, dt), force)
        return Signals(t=t, force=force, channels={"a1": acc[:, 0], "a2": acc[:, 1]},
                       fs=excitation.fs, f_inst=excitation.f_inst(t),
                       sweep_end=excitation.duration)
