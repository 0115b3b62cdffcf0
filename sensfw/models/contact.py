"""Contact and friction laws as Exudyn symbolic expressions (paper Eqs. 2-3, Adams style).

These functions take and return ``exudyn.symbolic.Real`` expressions (or plain floats, for
testing with numbers), so the whole contact set of a model compiles into one symbolic user
function that Exudyn evaluates in C++ during time integration; no Python runs in the time
loop. The same functions evaluate with numpy (:func:`numpy_ops`) for the static equilibrium
and the linearisation, because they only use ``+ - * /`` and the small set of functions
passed as ``ops``. :class:`PenaltyLaw` bundles Eqs. 2-3 as the
:class:`~sensfw.models.places.ContactLaw` of a contact place.

Units: all arguments in SI (m, m/s, N); stiffness ``k`` in N/m^b (see
:func:`stiffness_si`).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

Expr = Any  # exudyn.symbolic.Real or float


def symbolic_ops() -> SimpleNamespace:
    """Elementary functions on ``exudyn.symbolic.Real``."""
    import exudyn as exu

    esym = exu.symbolic
    return SimpleNamespace(
        max=lambda a, b: esym.max(_real(a), _real(b)),
        min=lambda a, b: esym.min(_real(a), _real(b)),
        pow=lambda a, b: esym.pow(_real(a), _real(b)),
        where=lambda c, a, b: esym.IfThenElse(c, _real(a), _real(b)),
        abs=lambda a: esym.abs(_real(a)),
        sign=lambda a: esym.sign(_real(a)),
        sin=esym.sin,
        exp=esym.exp,
    )


def numpy_ops() -> SimpleNamespace:
    """The same functions on numpy arrays/floats (for tests and static equilibrium)."""
    return SimpleNamespace(
        max=np.maximum, min=np.minimum, pow=lambda a, b: np.power(np.maximum(a, 0.0), b),
        where=np.where, abs=np.abs, sign=np.sign, sin=np.sin, exp=np.exp,
    )


def _real(x):
    import exudyn as exu

    return x if isinstance(x, exu.symbolic.Real) else exu.symbolic.Real(float(x))


def step(ops, x: Expr, x0: float, h0: float, x1: float, h1: float) -> Expr:
    """Adams ``STEP(x, x0, h0, x1, h1)``: cubic blend from ``h0`` at ``x0`` to ``h1`` at ``x1``
    (constant outside), ``h0 + (h1 - h0) s^2 (3 - 2 s)`` with ``s`` clamped to [0, 1]."""
    s = ops.min(ops.max((x - x0) * (1.0 / (x1 - x0)), 0.0), 1.0)
    return h0 + (h1 - h0) * s * s * (3.0 - 2.0 * s)


def impact_force(ops, delta: Expr, delta_dot: Expr, k: float, b: float, c: float,
                 dmax: float) -> Expr:
    """Normal force of a penalty contact, Eq. 2 with Adams IMPACT damping.

    ``F = k delta^b + STEP(delta, 0, 0, dmax, c) * delta_dot`` for ``delta > 0`` (closed),
    zero when open; the damping ramps in over the penetration ``dmax`` so the force is
    continuous at first touch. The force is clipped at zero (a contact pushes, never pulls),
    which Adams leaves to the user. The closed branch is only evaluated when closed (Exudyn's
    ``IfThenElse`` is lazy), which keeps open contacts nearly free.

    Parameters
    ----------
    delta, delta_dot : penetration (m) and its rate (m/s); positive closes the contact.
    k : stiffness in N/m^b.  b : force exponent.  c : maximum damping, N s/m.
    dmax : penetration (m) at which the full damping ``c`` is reached.
    """
    return ops.where(delta > 0.0, _closed_force(ops, delta, delta_dot, k, b, c, dmax), 0.0)


def _closed_force(ops, delta: Expr, delta_dot: Expr, k: float, b: float, c: float,
                  dmax: float) -> Expr:
    """Eq. 2 for a closed contact (``delta > 0``), clipped at zero.

    Written for the cost of Exudyn's symbolic expression trees, which are evaluated node by
    node with no common subexpressions: ``STEP(delta, 0, 0, dmax, c)`` inside the ramp is the
    cubic ``c s^2 (3 - 2 s)`` with ``s = delta / dmax``, expanded in ``delta`` so that no
    clamping ``min``/``max`` is needed (the ramp branch is only taken for ``delta < dmax``).
    """
    a2, a3 = 3.0 * c / dmax**2, 2.0 * c / dmax**3
    damping = ops.where(delta < dmax, delta * delta * (a2 - a3 * delta), c)
    return ops.max(k * ops.pow(delta, b) + damping * delta_dot, 0.0)


def clearance_force(ops, e: Expr, e_dot: Expr, gap: float, k: float, b: float, c: float,
                    dmax: float) -> Expr:
    """Signed force of a two-sided contact with play ``gap`` on each side (a shaft in a bore).

    ``e`` is the relative displacement along the contact normal; the contact closes when
    ``|e| > gap`` with penetration ``|e| - gap`` and pushes back: the result is the force on
    the moving part, ``-sign(e) F(|e| - gap)`` (Eq. 2 on the closed side). Each side is its
    own lazily evaluated branch, so an open contact costs two comparisons."""
    pushed_down = -_closed_force(ops, e - gap, e_dot, k, b, c, dmax)
    pushed_up = _closed_force(ops, -e - gap, -e_dot, k, b, c, dmax)
    return ops.where(e > gap, pushed_down, ops.where(e < -gap, pushed_up, 0.0))


def friction_coefficient(ops, v: Expr, mu_s: float, mu_d: float, v_s: float,
                         v_t: float) -> Expr:
    """Regularised stick-slip coefficient ``mu(v)`` (Eq. 3, Adams convention).

    ``|v| <= v_s``: ``STEP(v, -v_s, -mu_s, v_s, mu_s)`` (so ``mu(0) = 0``);
    ``v_s < |v| <= v_t``: ``sign(v) STEP(|v|, v_s, mu_s, v_t, mu_d)``;
    ``|v| > v_t``: ``sign(v) mu_d``. Requires ``v_s < v_t`` (stiction transition velocity
    below the friction transition velocity).

    The stick band is a viscous element of slope ``mu'(0) = 1.5 mu_s / v_s``: with
    ``x = v / v_s`` the STEP there is exactly ``mu_s x (3 - x^2) / 2``, evaluated in that form
    (no clamping; Exudyn's ``IfThenElse`` only evaluates the branch it takes).
    """
    a1, a3 = 1.5 * mu_s / v_s, 0.5 * mu_s / v_s**3
    stick = v * (a1 - a3 * v * v)
    slip = ops.where(v >= v_t, mu_d, ops.where(v <= -v_t, -mu_d, ops.where(
        v > 0.0, _stribeck(v, mu_s, mu_d, v_s, v_t), -_stribeck(-v, mu_s, mu_d, v_s, v_t))))
    return ops.where(ops.abs(v) <= v_s, stick, slip)


def _stribeck(av: Expr, mu_s: float, mu_d: float, v_s: float, v_t: float) -> Expr:
    """``STEP(av, v_s, mu_s, v_t, mu_d)`` for ``v_s < av < v_t`` (no clamping needed)."""
    s = (av - v_s) * (1.0 / (v_t - v_s))
    return mu_s + (mu_d - mu_s) * (s * s * (3.0 - 2.0 * s))


def stiffness_si(k_n_per_mm: float, b: float) -> float:
    """Contact stiffness given in N/mm^b (Table 1: force in N for a penetration in mm)
    converted to N/m^b: ``F = k (1000 delta_m)^b = (k 1000^b) delta_m^b``."""
    return float(k_n_per_mm) * 1000.0**b


@dataclass(frozen=True)
class FrictionLaw:
    """Regularised stick-slip friction (Eq. 3): the tangential force on the sliding body is
    ``-mu(v) fn`` for the slip velocity ``v`` and the normal force magnitude ``fn``."""

    mu_s: float
    mu_d: float
    v_s: float  # m/s, stiction transition velocity
    v_t: float  # m/s, friction transition velocity

    def force(self, ops, fn: Expr, v: Expr) -> Expr:
        return -friction_coefficient(ops, v, self.mu_s, self.mu_d, self.v_s, self.v_t) * fn


@dataclass(frozen=True)
class PenaltyLaw:
    """Penalty contact law of Eq. 2 in SI units, optionally with friction (Eq. 3); a
    :class:`~sensfw.models.places.ContactLaw`."""

    k: float  # N/m^b
    b: float
    c: float  # N s/m
    dmax: float  # m
    friction: FrictionLaw | None = None

    def normal(self, ops, delta: Expr, delta_dot: Expr) -> Expr:
        return impact_force(ops, delta, delta_dot, self.k, self.b, self.c, self.dmax)

    def tangential(self, ops, fn: Expr, v: Expr) -> Expr | None:
        return None if self.friction is None else self.friction.force(ops, fn, v)

    def linearized(self, delta0: float) -> tuple[float, float, float]:
        """(force, tangent stiffness ``k b delta0^(b-1)``, damping of Eq. 2) at the static
        penetration ``delta0`` (all zero when open)."""
        if delta0 <= 0:
            return 0.0, 0.0, 0.0
        ops = numpy_ops()
        return (self.k * delta0**self.b, self.k * self.b * delta0 ** (self.b - 1.0),
                float(self.c * step(ops, delta0, 0.0, 0.0, self.dmax, 1.0)))

    def static_deflection(self, force: float) -> float:
        """Penetration (m) that carries ``force`` N statically."""
        return (max(force, 0.0) / self.k) ** (1.0 / self.b)

    def tangent_stiffness(self, force: float) -> float:
        """dF/d(delta) at the static penetration for ``force`` (N/m)."""
        d = self.static_deflection(force)
        return self.k * self.b * d ** (self.b - 1.0) if d > 0 else 0.0


def fit_power_law(u, force, g=None, k0: float | None = None, b0: float = 1.5,
                  b_bounds: tuple[float, float] = (0.5, 3.0)) -> tuple[float, float]:
    """Contact stiffness ``k`` and exponent ``b`` from a force-deflection curve (Eq. 5):
    ``min_{k,b} sum_i (F_i - g(u_i) k u_i^b)^2`` by sequential quadratic programming
    (scipy SLSQP; MATLAB's fmincon or Adams' MSCADS-SQP in the paper), with ``k`` optimised
    on a log scale for conditioning. ``u`` and ``force`` are the reference curve (e.g.
    Hertz/Kunert or FEM), ``g`` the kinematic scaling between local and global deflection
    (default 1). Returns ``(k, b)`` in the units of ``force`` and ``u``.
    """
    from scipy.optimize import minimize

    u = np.asarray(u, float)
    F = np.asarray(force, float)
    if u.shape != F.shape or len(u) < 2 or np.any(u <= 0):
        raise ValueError("fit_power_law needs matching positive deflections and forces")
    gu = np.ones_like(u) if g is None else np.asarray(g(u), float)
    scale = float(np.max(np.abs(F)))
    if k0 is None:
        k0 = float(F[-1] / (gu[-1] * u[-1] ** b0))

    def cost(z):
        k, b = 10.0 ** z[0], z[1]
        return float(np.sum(((F - gu * k * u**b) / scale) ** 2))

    res = minimize(cost, x0=[np.log10(k0), b0], method="SLSQP",
                   bounds=[(np.log10(k0) - 6, np.log10(k0) + 6), b_bounds],
                   options={"ftol": 1e-14, "maxiter": 500})
    return float(10.0 ** res.x[0]), float(res.x[1])


def critical_damping(k_red: float, m_red: float) -> float:
    """Critical damping ``2 sqrt(k_red m_red)`` of a contact with reduced stiffness and mass,
    the upper bound of the damping range (Sect. 2.2). Eq. 6 prints ``sqrt(k_red / m_red)``,
    which is the contact's natural angular frequency, not a damping coefficient; the
    dimensionally consistent critical damping is used here."""
    if k_red <= 0 or m_red <= 0:
        raise ValueError("reduced stiffness and mass must be positive")
    return 2.0 * float(np.sqrt(k_red * m_red))
