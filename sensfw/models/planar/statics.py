"""Static equilibrium and linearisation of a :class:`~sensfw.models.planar.mechanism.Mechanism`
with numpy (the same force laws Exudyn evaluates in C++)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ...errors import SimulationError
from ..contact import numpy_ops
from ..places import ContactLaw
from .mechanism import Contacts, CoordinateIndex, Mechanism

#: scipy ``least_squares`` (method, x_scale) tried in turn for the static state; see
#: :func:`equilibrium` for why MINPACK ``lm`` is not among them.
EQUILIBRIUM_SOLVERS = (("trf", 1.0), ("dogbox", "jac"), ("trf", "jac"), ("dogbox", 1.0))


class RecordingContacts:
    """Contact evaluator recording each contact's static coordinate (returns no force)."""

    def __init__(self):
        self.static: dict[str, tuple[float, float | None]] = {}

    def one_sided(self, place, delta, delta_dot):
        self.static[place] = (float(delta), None)
        return 0.0

    def two_sided(self, place, e, e_dot, gap):
        self.static[place] = (float(e), float(gap))
        return 0.0

    def tangential(self, place, fn, v):
        return None


class LinearContacts:
    """Contact evaluator of the linearised model: every contact closed at the static state
    becomes a bilateral spring with the tangent stiffness and damping of its law there
    (``ContactLaw.linearized``), carrying the static force; contacts open at the static state
    stay absent; no friction."""

    def __init__(self, laws: Mapping[str, ContactLaw], static: Mapping[str, tuple]):
        self.table: dict[str, tuple[float, float, float, float] | None] = {}
        for place, (x0, gap) in static.items():
            # penetration, and the sign of the force on the moving part
            d0, sign = (x0, 1.0) if gap is None else (abs(x0) - gap, -float(np.sign(x0)))
            if d0 > 0:  # (static force, tangent stiffness, tangent damping, static coordinate)
                f0, k, c = laws[place].linearized(d0)
                self.table[place] = (sign * f0, k, c, x0)
            else:
                self.table[place] = None

    def one_sided(self, place, delta, delta_dot):
        entry = self.table[place]
        if entry is None:
            return 0.0
        f0, k, c, x0 = entry
        return f0 + k * (delta - x0) + c * delta_dot

    def two_sided(self, place, e, e_dot, gap):
        entry = self.table[place]
        if entry is None:
            return 0.0
        f0, k, c, x0 = entry  # restoring force on the moving part
        return f0 - k * (e - x0) - c * e_dot

    def tangential(self, place, fn, v):
        return None


def forces(mech: Mechanism, q, qd, contact=None, index: CoordinateIndex | None = None
           ) -> np.ndarray:
    """Generalised link and gravity forces (numpy); ``contact`` defaults to the nonlinear
    laws."""
    ops = numpy_ops()
    return mech.generalized_forces(q, qd, contact or Contacts(ops, mech.laws), ops, index)


def equilibrium(mech: Mechanism, guess: np.ndarray, model: str = "model",
                params: Mapping[str, float] | None = None) -> np.ndarray:
    """Static state under gravity and static loads, from ``guess`` (trust-region least
    squares on the numpy force laws; translations scaled by 10 um, rotations by 0.1 mrad).

    Bitwise reproducible: the state every run starts from must not depend on what the
    process did before. scipy's ``method="lm"`` (MINPACK) is not: the same call from the
    same start returned states a few ulps apart depending on what the process had solved
    before (measured at the all-min corner of Table 1 of the shaft model, 13 of 60 calls
    after other solves), which stiff contacts amplify to 5e-10 m/s^2 in the first sample.
    The trust-region methods (trf, dogbox) were reproducible; in the order of
    ``EQUILIBRIUM_SOLVERS`` they solved all of 235 shaft-model points tried (193 of Table 1:
    OAT min/max, corners, uniform samples; 42 with an added effect) in 58 s, where the former
    trf -> lm -> dogbox chain missed 2 in 67 s. Plain trf is tried first because it is the
    fastest where it converges (0.03 s with most effects, against up to 13 s for dogbox).
    """
    from scipy.optimize import least_squares

    index = mech.coordinates()
    mech.anchor(None)  # links centred on the static state carry no static force
    zero = np.zeros(index.n)
    scale = np.full(index.n, 1e-5)
    scale[index.rotation_index()] = 1e-4
    contact = Contacts(numpy_ops(), mech.laws)

    def res(z):
        return forces(mech, z * scale, zero, contact, index)

    start = np.array(guess, float)
    mech.follow(index, start)
    best = None
    for method, x_scale in EQUILIBRIUM_SOLVERS:
        sol = least_squares(res, start / scale, method=method, x_scale=x_scale, xtol=1e-15,
                            ftol=1e-15, gtol=1e-15, max_nfev=20000)
        worst = float(np.max(np.abs(sol.fun)))
        if best is None or worst < best[0]:
            best = (worst, sol.x)
        if worst < 1e-8:
            break
    worst, z = best
    if not np.all(np.isfinite(z)) or worst > 1e-6:
        raise SimulationError(model, f"no static equilibrium (residual {worst:.3g} N)",
                              params or {})
    return z * scale


def linear_contacts(mech: Mechanism, q0: np.ndarray) -> LinearContacts:
    """The linearised contacts at the static state ``q0``."""
    mech.anchor(q0)
    rec = RecordingContacts()
    forces(mech, q0, np.zeros(len(q0)), rec)
    return LinearContacts(mech.laws, rec.static)


def linear_matrices(mech: Mechanism, q0: np.ndarray, contact=None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, stiffness and damping matrices at the static state ``q0`` (central differences
    of the numpy forces; friction enters the damping through ``mu'(0)``)."""
    index = mech.coordinates()
    mech.anchor(q0)
    contact = contact or Contacts(numpy_ops(), mech.laws)
    rot = set(index.rotation_index())
    n = len(q0)
    K, D, z = np.zeros((n, n)), np.zeros((n, n)), np.zeros(n)
    for i in range(n):
        e = np.zeros(n)
        e[i] = 1e-10 if i not in rot else 1e-9
        h = e[i]
        K[:, i] = -(forces(mech, q0 + e, z, contact, index)
                    - forces(mech, q0 - e, z, contact, index)) / (2 * h)
        ev = e * (1e-9 / h)
        D[:, i] = -(forces(mech, q0, ev, contact, index)
                    - forces(mech, q0, -ev, contact, index)) / 2e-9
    return np.diag(index.masses()), K, D
