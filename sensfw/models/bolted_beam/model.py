"""The bolted lap-joint beam (UNESP-BERT rig) as an Exudyn model.

Two aluminium beams joined by a bolted half-lap joint, clamped at one end, driven by a
shaker at 85 mm from the clamp (:mod:`.parameters` for the geometry, :mod:`.mechanics` for the
mechanics). Outputs named like the measured channels: ``Acc1`` (free end), ``Acc2`` (below
the joint, on beam2), ``Acc3`` (above it, on beam1), ``Acc4`` (near the clamp), transverse
accelerations in m/s^2, and ``Laser``, the transverse velocity of the free end in m/s.

**Why a Craig-Bampton reduction of Euler-Bernoulli frame elements, integrated implicitly.**
The beams are slender (L/h ~ 40) and move micrometres to millimetres: linear
Euler-Bernoulli kinematics are exact enough, and the joint's nonlinearity sits in a few force
elements. The half-lap's eccentric halves and the interface slip are exact in frame elements
written on the interface plane (:mod:`.fe`). The reduced structure has the 14 attachment
points' 28 physical coordinates and 3 fixed-interface modes (31 coordinates at the nominal
values); against an independent 5 mm Euler-Bernoulli model of the same geometry its first two
eigenfrequencies agree within 5e-5 and the 3rd and 4th (313, 515 Hz) within 4.4e-4, the
reduction's truncation (3e-5 with a 16 kHz cutoff; tests). Exudyn's ANCF cable elements
(``ObjectANCFCable2D``) were the alternative: geometrically nonlinear (not needed here), no
eccentric sections (the half-lap would need extra constraints), and slower: ``bench/model.py``
integrates a plain 20-element ANCF cantilever 3-4x slower per simulated second than this
model with the same integrator and step. Both are *stiff*: the reduced model's fastest
eigenvalue is 8e5 rad/s (short segments' axial and interface coordinates, the stiff normal
contacts), so RK4 would need 1.8 us steps (8.7 M for a 16 s record); the implicit
generalised-alpha method at 1/8192 s (8 steps per output sample) damps those modes
numerically and resolves the 70-330 Hz band (sweep and third harmonic) with a period error of
4e-4 (0.04 Hz at 91 Hz; tests). One 16 s record at 1024 Hz takes ~1.7 s on one core
(``bench/model.py``).

Damping: every mode of the base linear structure (the beams with the joint's and the
clamp's own laws linearised) has the modal damping ratio ``damping_ratio``; the joint's
viscous ``joint_damping`` acts on its slip.

Effects (:mod:`sensfw.effects`) act at the model's places through the hooks of
:class:`~.assembly.BeamAssembly`; the model applies them without knowing their names.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import asdict, replace
from typing import Any, ClassVar

import numpy as np
from pydantic import Field

from ...errors import DivergenceError, SimulationError
from ...excitation import Excitation
from ...options import PluginOptions
from ...params import ParameterSet
from ..base import EFFECTS, Model, Signals, SolverSettings, check_channels
from ..contact import numpy_ops, symbolic_ops
from ..drive import LoadSignal
from ..places import Place
from ..stepsize import StepChoice, explicit_step, first_order_eigenvalues, grid_step
from . import mechanics, simulation
from .assembly import BeamAssembly, BeamContacts, Structure, modal_damping, solve_static
from .parameters import PARAMETERS, Geometry

GPA = 1e9


class BoltedBeam(Model):
    """Clamped two-beam assembly with a bolted lap joint (see module docstring).

    Parameters
    ----------
    geometry : fixed model data (enters the run hash).
    effects : physical effects at the model's places: names, ``{"name": ..., "attach":
        ...}`` specs or :class:`sensfw.effects.Effect` objects.
    """

    name = "bolted_beam"
    # 2: the reduced beams' exact Jacobian (simulation.REDUCED_JACOBIAN); where the micro-slip
    # sliders slip hard the runs move within their step's own discretisation error
    # 3: modified Newton's limits (simulation.MODIFIED): the same, where sliders switch
    version = "3"
    sensors = ("Acc1", "Acc2", "Acc3", "Acc4", "Laser")
    default_output = "Laser"
    units: ClassVar[dict[str, str]] = {"Acc1": "m/s^2", "Acc2": "m/s^2", "Acc3": "m/s^2",
                                       "Acc4": "m/s^2", "Laser": "m/s"}

    #: where an effect goes without ``attach``: the joint's effects at the joint (the only
    #: joint), dry friction at beam1 (the shaker's drive point)
    preferred_places: ClassVar[dict[str, tuple[str, ...]]] = {
        "cubic_stiffness": ("joint",), "dry_friction": ("beam1",)}

    class Options(PluginOptions):
        geometry: Geometry | None = Field(
            None, description="a table of the fixed data (Geometry's fields) or none")
        effects: list[Any] = Field((), description=EFFECTS)

    def __init__(self, geometry: Geometry | dict | None = None, effects: tuple = ()):
        if isinstance(geometry, dict):
            geometry = Geometry(**{k: tuple(v) if isinstance(v, list) else v
                                   for k, v in geometry.items()})
        self.geometry = geometry or Geometry()
        super().__init__(effects)

    # ---- declarations ------------------------------------------------------------------------
    def parameters(self) -> ParameterSet:
        return self.with_effect_parameters(PARAMETERS)

    def places(self) -> dict[str, Place]:
        return mechanics.places(self.geometry)

    def options(self) -> dict:
        return {"geometry": asdict(self.geometry), **self.effect_options()}

    # ---- mechanics ---------------------------------------------------------------------------
    def assembly(self, p: Mapping[str, float]) -> BeamAssembly:
        """The assembly for full parameter values ``p`` with every effect applied."""
        asm = mechanics.assembly(p, self.geometry)
        self.apply_effects(asm, p)
        return asm

    def structure(self, p: Mapping[str, float], asm: BeamAssembly | None = None) -> Structure:
        """The reduced structure (Craig-Bampton) of the assembly."""
        g = self.geometry
        asm = asm or self.assembly(p)
        return asm.reduce(p["youngs_modulus"] * GPA, p["density"], g.width, g.thickness,
                          g.max_element, g.cutoff_hz)

    def state(self, params: Mapping[str, float]) -> tuple[dict, Structure, np.ndarray,
                                                          np.ndarray]:
        """(full parameters, structure, static state, modal damping matrix of the
        structure's coordinates).

        The modal damping is that of the *base* structure (the beams with the model's own
        joint and clamp laws, linearised), whatever the effects: structural damping is a
        property of the beams. Computed from a structure stiffened or loosened by an effect
        (e.g. a Jenkins spring seen grounded, since the slider's stick is a damper) it would
        put the large damping ``2 zeta omega`` of that system's high modes into the
        measured mode."""
        p = self.parameters().complete(params)
        st = self.structure(p)
        z0 = solve_static(st, model=self.name, params=p)
        M, K, _ = st.linear_matrices(z0, base=True)
        ns = st.n_struct
        D = np.zeros_like(M)
        D[:ns, :ns] = modal_damping(M[:ns, :ns], K[:ns, :ns], p["damping_ratio"])
        return p, st, z0, D

    def linear_matrices(self, params: Mapping[str, float]
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass, stiffness and damping matrices (modal damping + force elements) at the
        static state, over all coordinates."""
        _, st, z0, D = self.state(params)
        M, K, Dl = st.linear_matrices(z0)
        return M, K, D + Dl

    def eigenfrequencies(self, params: Mapping[str, float], n: int = 6) -> np.ndarray:
        """The ``n`` lowest undamped eigenfrequencies (Hz) of the linearised model."""
        import scipy.linalg as sl

        M, K, _ = self.linear_matrices(params)
        w2 = sl.eigh(K, M, eigvals_only=True, subset_by_index=[0, n - 1])
        return np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi)

    def frequency_response(self, params: Mapping[str, float], f: np.ndarray,
                           channel: str) -> np.ndarray:
        """FRF of the linearised model from the shaker force to ``channel`` at the
        frequencies ``f`` (Hz): ``H = c (K - w^2 M + i w D)^-1 b`` times ``-w^2`` for an
        accelerometer (m/s^2 per N) or ``i w`` for the laser (m/s per N)."""
        _, st, z0, D = self.state(params)
        M, K, Dl = st.linear_matrices(z0)
        D = D + Dl
        g = self.geometry
        b = np.zeros(st.n)
        b[st.coordinate("beam1", (g.shaker_x, 0.0)) + 1] = 1.0
        body, x = mechanics.sensor_points(g)[channel]
        c = np.zeros(st.n)
        c[st.coordinate(body, (x, 0.0)) + 1] = 1.0
        out = []
        for w in 2 * np.pi * np.asarray(f, float):
            u = c @ np.linalg.solve(K - w * w * M + 1j * w * D, b)
            out.append(u * (1j * w if channel == "Laser" else -w * w))
        return np.array(out)

    # ---- Exudyn ------------------------------------------------------------------------------
    def build(self, params: Mapping[str, float], excitation: Excitation | None,
              user_functions: str = "symbolic", step: float | None = None):
        """Assemble the Exudyn system at the static state (not yet solved); ``step`` is the
        integrator's step (default ``1/fs``), at which a sampled excitation is fed."""
        _, st, z0, D = self.state(params)
        ops = symbolic_ops() if user_functions == "symbolic" else numpy_ops()
        contact = BeamContacts(ops, st.assembly.laws)
        g = self.geometry
        loads, signal = [], None
        if excitation is not None:
            signal = LoadSignal(excitation, step or 1.0 / excitation.fs)
            loads.append(("beam1", g.shaker_x, lambda ops, t: (0.0, signal.value(ops, t))))
        sensors = [(name, body, x, "Velocity" if name == "Laser" else "Acceleration", 1)
                   for name, (body, x) in mechanics.sensor_points(g).items()]
        built = simulation.build(st, z0, D, contact, ops, loads, sensors, user_functions)
        if signal is not None:
            installed = signal.install(built.mbs, before=built.prestep)
            built.keep += installed
            if installed:  # the system's pre-step function is now the drive's
                built.prestep = installed[0]
        return built

    def simulate(self, params: Mapping[str, float], excitation: Excitation,
                 solver: SolverSettings | None = None,
                 user_functions: str = "symbolic") -> Signals:
        import exudyn as exu

        solver = solver or SolverSettings(method="GeneralizedAlpha", step=1 / 8192,
                                          auto_step=False)
        p = self.parameters().complete(params)
        exu.config.printToConsole = False
        t0 = time.perf_counter()
        choice = self.time_step(p, excitation.fs, solver)
        n_out = excitation.n_samples
        force = excitation.force()
        scale = float(np.max(np.abs(force)))
        silent_from = simulation.silence(force, excitation.fs)
        # Newton: modified (Jacobian kept while it converges: one iteration per step for the
        # linear model; Jenkins elements switch between stick and slip inside it, where a
        # contraction above 0.5 or a fourth iteration renews it, simulation.MODIFIED); where
        # effects added bodies, modified with a patient renewal (simulation.PATIENT); a
        # failure is retried with full Newton.
        # A step that fails with full Newton too, at every step Exudyn may reduce it to
        # (simulation.solve), is a divergence at this step, which the runs retry at half the
        # step (sensfw.runs.spec.simulate_with_halving, [solver] halvings)
        newton = "patient" if self.assembly(p).added else "modified"
        while True:
            built = self.build(p, excitation, user_functions=user_functions,
                               step=choice.step)
            try:
                channels = simulation.solve(built, excitation.fs, n_out, choice.substeps,
                                            solver.method, solver.spectral_radius, scale,
                                            newton=newton, silent_from=silent_from)
                break
            except exu.SolverError as exc:
                if newton == "full" or solver.method not in simulation.IMPLICIT:
                    raise DivergenceError(self.name, f"Exudyn solver error: {exc}", p,
                                          step=choice.step) from None
                newton = "full"
        if not channels:
            raise SimulationError(self.name, "Exudyn solver did not finish", p)
        check_channels(self.name, channels, n_out, p, choice.step)
        t = excitation.time()
        return Signals(t=t, force=excitation.force(t), channels=channels, fs=excitation.fs,
                       f_inst=excitation.f_inst(t),
                       units={"force": "N", **{c: self.units[c] for c in channels}},
                       meta={"model": self.name, "wall_s": time.perf_counter() - t0,
                             "method": solver.method, "newton": newton,
                             "steps": built.steps, "quiet_from": built.stopped_at,
                             **{f"newton_{k}": v for k, v in built.newton.items()},
                             **choice.to_meta()},
                       sweep_end=excitation.sweep_end)

    def time_step(self, p: Mapping[str, float], fs: float, solver: SolverSettings
                  ) -> StepChoice:
        """The step of a run: with an implicit method ``solver.step`` on the output grid
        (the method is unconditionally stable; the step is chosen for accuracy in the study);
        with an explicit one and ``auto_step``, small enough for the fastest eigenvalues
        (:mod:`sensfw.models.stepsize`; ~1 us: slow, see the module docstring)."""
        if solver.method in simulation.IMPLICIT or not solver.auto_step:
            return replace(grid_step(solver.step, fs), method=solver.method)
        M, K, D = self.linear_matrices(p)
        return replace(explicit_step(first_order_eigenvalues(M, K, D), solver.step, fs),
                       method=solver.method)
