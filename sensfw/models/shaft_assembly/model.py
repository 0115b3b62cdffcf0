"""The benchmark model: a nested output-shaft assembly with contacts, simulated with Exudyn.

An analogue of the paper's e-bike output shaft (Sect. 2.2, Fig. 2, Fig. 6); its mechanics are
in :mod:`.mechanics`, its parameters (Table 1) in :mod:`.table1`. The shaker pushes the
crankshaft radially at its end with the excitation force; accelerometers sit on C (axial, the
paper's output; radial) and on D (axial, radial).

Every contact is one Exudyn ``ObjectConnectorCartesianSpringDamper`` between two body points
whose force is a *symbolic* user function (Eqs. 2-3, :mod:`sensfw.models.contact`); Exudyn
evaluates it in C++ inside its explicit RK4 integrator, with no Python in the time loop
(``bench/model.py`` compares with the same model built with Python user functions). The same
force laws evaluate with numpy for the static equilibrium the simulation starts from.

Effects (:mod:`sensfw.effects`) act at the model's places (:func:`.mechanics.places`) through the
hooks of :class:`~sensfw.models.planar.Mechanism`; the model applies them without knowing
their names.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import asdict, replace
from typing import Any, ClassVar

import numpy as np
from pydantic import Field

from ...errors import SimulationError
from ...excitation import Excitation
from ...options import Bool, PluginOptions
from ...params import MM, ParameterSet
from ..base import EFFECTS, Model, Signals, SolverSettings, check_channels
from ..contact import numpy_ops, symbolic_ops
from ..drive import LoadSignal
from ..places import Place
from ..planar import Contacts, CoordinateIndex, Mechanism, statics
from ..planar import exudyn as planar_exudyn
from ..stepsize import StepChoice, choose_integration, first_order_eigenvalues, grid_step
from . import mechanics
from .table1 import GROUPS, PARAMETERS, Geometry


class ShaftAssembly(Model):
    """Nested shaft assembly with contacts (see module docstring).

    Parameters
    ----------
    linearised : replace every contact by a bilateral linear spring-damper at the static
        equilibrium (clearances closed, exponents effectively 1, friction off); the
        reference for the model's linear checks.
    geometry : fixed model data (enters the run hash).
    effects : physical effects added at the model's places: names,
        ``{"name": ..., "attach": ...}`` specs or :class:`sensfw.effects.Effect` objects.
    """

    name = "shaft_assembly"
    version = "1"
    sensors = ("crank_axial", "crank_radial", "drive_axial", "drive_radial")
    units: ClassVar[Mapping[str, str]] = {name: "m/s^2" for name in sensors}
    default_output = "crank_axial"

    #: where an effect goes without ``attach``: play and friction at the clutch's guide,
    #: hardening at roller bearing L1, damping at L3, the body effects at the crankshaft
    preferred_places: ClassVar[dict[str, tuple[str, ...]]] = {
        "clearance": ("clutch_drive",), "friction": ("clutch_drive",),
        "contact_hardening": ("bearing_l1",), "damping": ("bearing_l3",),
        **dict.fromkeys(("preload", "added_mass", "flexible_mode", "limit_stop",
                         "cubic_stiffness"), ("crankshaft",)),
    }

    class Options(PluginOptions):
        linearised: Bool = Field(False, description="true or false")
        geometry: Geometry | None = Field(
            None, description="a table of the fixed data (Geometry's fields) or none")
        effects: list[Any] = Field((), description=EFFECTS)

    def __init__(self, linearised: bool = False, geometry: Geometry | dict | None = None,
                 effects: tuple = ()):
        if isinstance(geometry, dict):
            geometry = Geometry(**{k: tuple(v) if isinstance(v, list) else v
                                   for k, v in geometry.items()})
        self.linearised = bool(linearised)
        self.geometry = geometry or Geometry()
        super().__init__(effects)

    # ---- declarations ------------------------------------------------------------------------
    def parameters(self) -> ParameterSet:
        return self.with_effect_parameters(PARAMETERS)

    def groups(self) -> dict[str, tuple[str, ...]]:
        return dict(GROUPS)

    def places(self) -> dict[str, Place]:
        return mechanics.places(self.geometry)

    def options(self) -> dict:
        return {"linearised": self.linearised, "geometry": asdict(self.geometry),
                **self.effect_options()}

    # ---- mechanics ---------------------------------------------------------------------------
    def mechanism(self, p: Mapping[str, float]) -> Mechanism:
        """The assembly for full parameter values ``p`` with every effect applied."""
        mech = mechanics.mechanism(p, self.geometry)
        self.apply_effects(mech, p)
        return mech

    def coordinates(self, p: Mapping[str, float]) -> CoordinateIndex:
        """Where each body's coordinates start in the state vector (parameter values ``p``)."""
        return self.mechanism(p).coordinates()

    def generalized_forces(self, q, qd, p: Mapping[str, float], contact=None) -> np.ndarray:
        """Static and contact forces on the coordinates (numpy, SI, no excitation)."""
        return statics.forces(self.mechanism(p), q, qd, contact)

    def equilibrium(self, p: Mapping[str, float], mech: Mechanism | None = None) -> np.ndarray:
        """Static state under gravity, preload and spring load
        (:func:`sensfw.models.planar.statics.equilibrium`), started where gravity has closed
        the radial clearances and the preload the shoulder: D rests on L1/L3, C on its slide
        bearings, K follows D; each contact lightly loaded."""
        mech = mech or self.mechanism(p)
        g = self.geometry
        c1, c3, cs = (p["l1_clearance"] * MM, p["l3_clearance"] * MM,
                      p["slide_clearance"] * MM)
        th_d = (c1 - c3) / (g.x_l3 - g.x_l1)
        y_d = -c1 - th_d * g.x_l1
        x_d = (p["bearing_preload"] / g.bearing_axial_k) ** (1 / g.bearing_axial_b) * MM
        guess = np.zeros(mech.coordinates().n)
        guess[:8] = [x_d, y_d, th_d, x_d, y_d - cs, th_d, x_d, y_d + th_d * g.x_clutch]
        return statics.equilibrium(mech, guess, self.name, p)

    def linear_matrices(self, p: Mapping[str, float], q0: np.ndarray | None = None
                        ) -> tuple[np.ndarray, ...]:
        """Mass, stiffness and damping matrices at the static state (central differences
        of the numpy forces; friction enters the damping through ``mu'(0)``)."""
        p = self.parameters().complete(p)
        mech = self.mechanism(p)
        q0 = self.equilibrium(p, mech) if q0 is None else q0
        contact = statics.linear_contacts(mech, q0) if self.linearised else None
        return statics.linear_matrices(mech, q0, contact)

    # ---- Exudyn ------------------------------------------------------------------------------
    def build(self, p: Mapping[str, float], excitation: Excitation | None,
              q0: np.ndarray | None = None, user_functions: str = "symbolic",
              step: float | None = None) -> planar_exudyn.Built:
        """Assemble the Exudyn system at the static equilibrium (not yet solved); ``step``
        is the integrator's step (default ``1/fs``), at which a sampled excitation is fed."""
        p = self.parameters().complete(p)
        mech = self.mechanism(p)
        q0 = self.equilibrium(p, mech) if q0 is None else q0
        ops = symbolic_ops() if user_functions == "symbolic" else numpy_ops()
        contact = statics.linear_contacts(mech, q0) if self.linearised else \
            Contacts(ops, mech.laws)
        g = self.geometry
        loads, signal = [], None
        if excitation is not None:
            signal = LoadSignal(excitation, step or 1.0 / excitation.fs)
            loads.append(("C", (g.x_force, 0.0), lambda ops, t: (0.0, signal.value(ops, t))))
        sensors = [("crank_axial", "C", (g.x_sensor, g.r_sensor), 0),
                   ("crank_radial", "C", (g.x_force, 0.0), 1),
                   ("drive_axial", "D", (g.x_l3, 0.0), 0),
                   ("drive_radial", "D", (g.x_l3, 0.0), 1)]
        built = planar_exudyn.build(mech, q0, contact, ops, loads, sensors, user_functions)
        if signal is not None:
            built.keep += signal.install(built.mbs)
        return built

    def simulate(self, params: Mapping[str, float], excitation: Excitation,
                 solver: SolverSettings | None = None,
                 user_functions: str = "symbolic") -> Signals:
        import exudyn as exu

        solver = solver or SolverSettings()
        p = self.parameters().complete(params)
        exu.config.printToConsole = False
        t0 = time.perf_counter()
        mech = self.mechanism(p)
        q0 = self.equilibrium(p, mech)
        choice = self.time_step(p, excitation.fs, solver, q0)
        built = self.build(p, excitation, q0=q0, user_functions=user_functions,
                           step=choice.step)
        n_out = excitation.n_samples
        try:
            channels, stats = planar_exudyn.solve(built, excitation.fs, n_out, choice)
        except exu.SolverError as exc:
            raise SimulationError(self.name, f"Exudyn solver error: {exc}", p) from None
        check_channels(self.name, channels, n_out, p, choice.step, unit="m/s^2")
        t = excitation.time()
        return Signals(t=t, force=excitation.force(t), channels=channels, fs=excitation.fs,
                       f_inst=excitation.f_inst(t),
                       units={"force": "N", **{c: self.units[c] for c in channels}},
                       meta={"model": self.name, "wall_s": time.perf_counter() - t0,
                             **choice.to_meta(), **stats.to_meta()},
                       sweep_end=excitation.sweep_end)

    def time_step(self, p: Mapping[str, float], fs: float, solver: SolverSettings,
                  q0: np.ndarray | None = None) -> StepChoice:
        """The integrator and step of a run (:mod:`sensfw.models.stepsize`): at most
        ``solver.step``, dividing the sample period ``1/fs``, and with ``solver.auto_step``
        small enough for the fastest eigenvalues of the model linearised at its static state
        ``q0`` (over-damped and stiff contacts); RK4, or ``solver.stiff_method`` where the
        stick band of the slide-bearing friction lies beyond RK4's stability."""
        if not solver.auto_step:
            return replace(grid_step(solver.step, fs), method=solver.method)
        M, K, D = self.linear_matrices(p, q0)
        return choose_integration(first_order_eigenvalues(M, K, D), solver.step, fs,
                                  solver.method, solver.tolerance, solver.stiff_method)
