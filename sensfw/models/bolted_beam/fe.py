"""Finite elements of the two beams and their Craig-Bampton reduction (numpy/scipy).

Each beam is a chain of planar Euler-Bernoulli frame elements (axial + bending, cubic
Hermite bending, consistent mass; e.g. Przemieniecki 1968, Ch. 5 and 11) with three
coordinates per node, ``(u, w, theta)``: the axial and transverse displacement of the
*reference line* and the rotation ``theta = dw/dx``. The reference line of both beams is the
plane of the lap joint's interface (the mid-plane of the full beams). Where a beam is thinned
to half its thickness in the overlap, its centroid lies ``e = +-h/4`` off the reference line
and the element is written in reference-line coordinates through the eccentricity transform
``u_centroid = u - e theta`` (plane sections), so the axial displacement of a node is the
displacement of the material *at the interface*: the slip of the joint is ``u2 - u1``.

The structure is reduced by Craig & Bampton (1968): the *boundary* coordinates are the
``(u, w)`` of every point where something attaches (joint interface points, clamp, shaker,
sensors, points used by effects); the rest is represented by the static constraint modes
``Psi = -K_ii^-1 K_ib`` and the lowest fixed-interface modes. The reduced coordinates are
``[u_1, w_1, u_2, w_2, ..., eta_1, ..., eta_m]``: the first are the physical displacements of
the points (where Exudyn attaches its connectors, loads and sensors), the last modal.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
import scipy.linalg as sl

from ...errors import SensfwError

#: Positions closer than this (m) are the same node.
SNAP = 1e-9


def frame_element(length: float, E: float, rho: float, width: float, thickness: float,
                  offset: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass matrices (6 x 6) of a planar Euler-Bernoulli frame
    element in the coordinates ``(u1, w1, theta1, u2, w2, theta2)`` of a reference line
    ``offset`` (m) below the element's centroid (``u_c = u - offset * theta``).

    Axial: ``EA/L [[1, -1], [-1, 1]]`` and ``rho A L/6 [[2, 1], [1, 2]]``; bending: the cubic
    Hermite matrices ``EI/L^3 [...]`` and ``rho A L/420 [...]`` (rotary inertia of the
    section itself neglected, as in Euler-Bernoulli theory; that of the offset mass enters
    through the transform).
    """
    L = float(length)
    if not L > 0:
        raise ValueError(f"element length must be > 0, got {L}")
    A = width * thickness
    EA, EI, m = E * A, E * width * thickness**3 / 12.0, rho * A
    K, M = np.zeros((6, 6)), np.zeros((6, 6))
    ax, be = [0, 3], [1, 2, 4, 5]
    K[np.ix_(ax, ax)] = EA / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[np.ix_(be, be)] = EI / L**3 * np.array([
        [12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
        [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    M[np.ix_(ax, ax)] = m * L / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    M[np.ix_(be, be)] = m * L / 420.0 * np.array([
        [156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
        [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    if offset:
        T = np.eye(6)
        T[0, 2] = T[3, 5] = -offset
        K, M = T.T @ K @ T, T.T @ M @ T
    return K, M


@dataclass(frozen=True)
class Beam:
    """A straight beam along x from ``x0`` to ``x1`` (m, rig coordinates); thickness ``h``
    except on ``thin = (a, b)``, where it is ``h/2`` with its centroid ``offset`` (m) off the
    reference line (the half-lap tongue)."""

    name: str
    x0: float
    x1: float
    thin: tuple[float, float] | None = None
    offset: float = 0.0

    def section(self, xm: float, h: float) -> tuple[float, float]:
        """(thickness, centroid offset) at the position ``xm``."""
        if self.thin is not None and self.thin[0] < xm < self.thin[1]:
            return h / 2.0, self.offset
        return h, 0.0

    def contains(self, x: float) -> bool:
        return self.x0 - SNAP <= x <= self.x1 + SNAP


class Mesh:
    """Nodes of every beam (sorted positions) and their coordinate numbering.

    Every beam gets nodes at its ends, at the ends of its thinned part, at every ``required``
    position and in between at most ``max_element`` apart.
    """

    def __init__(self, beams: Sequence[Beam], required: Mapping[str, Sequence[float]],
                 max_element: float):
        if not max_element > 0:
            raise ValueError(f"max_element must be > 0, got {max_element}")
        self.beams = {b.name: b for b in beams}
        self.nodes: dict[str, np.ndarray] = {}
        self.first: dict[str, int] = {}
        n = 0
        for b in beams:
            keys = [b.x0, b.x1, *(b.thin or ()), *required.get(b.name, ())]
            for x in required.get(b.name, ()):
                if not b.contains(x):
                    raise SensfwError(f"point x = {x * 1e3:g} mm is not on {b.name} "
                                      f"({b.x0 * 1e3:g} ... {b.x1 * 1e3:g} mm)")
            keys = np.unique(np.round(np.asarray(keys, float), 9))
            xs = [keys[0]]
            for a, c in pairwise(keys):
                k = max(1, int(np.ceil((c - a) / max_element - 1e-9)))
                xs += list(a + (c - a) * np.arange(1, k + 1) / k)
            self.nodes[b.name] = np.array(xs)
            self.first[b.name] = n
            n += 3 * len(xs)
        self.n = n

    def dof(self, beam: str, x: float) -> int:
        """Index of ``u`` of the node of ``beam`` at ``x`` (``w`` is +1, ``theta`` +2)."""
        xs = self.nodes[beam]
        i = int(np.argmin(np.abs(xs - x)))
        if abs(xs[i] - x) > 1e-7:
            raise KeyError(f"no node of {beam} at x = {x}")
        return self.first[beam] + 3 * i

    def matrices(self, E: float, rho: float, width: float, h: float,
                 point_masses: Sequence[tuple[str, float, float]] = ()
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Free-free stiffness and mass matrices of all beams (no supports, no coupling),
        with point masses ``(beam, x, kg)`` on ``u`` and ``w`` of their nodes."""
        K, M = np.zeros((self.n, self.n)), np.zeros((self.n, self.n))
        for name, xs in self.nodes.items():
            beam = self.beams[name]
            for i in range(len(xs) - 1):
                t, e = beam.section(0.5 * (xs[i] + xs[i + 1]), h)
                Ke, Me = frame_element(xs[i + 1] - xs[i], E, rho, width, t, e)
                idx = np.arange(6) + self.first[name] + 3 * i
                K[np.ix_(idx, idx)] += Ke
                M[np.ix_(idx, idx)] += Me
        for beam, x, m in point_masses:
            i = self.dof(beam, x)
            M[i, i] += m
            M[i + 1, i + 1] += m
        return K, M


@dataclass
class Reduction:
    """A Craig-Bampton reduced structure: ``q_fe = T z`` with ``z = [q_b, eta]``.

    ``K``, ``M`` are the reduced matrices, ``nb`` the number of boundary coordinates (the
    first ones of ``z``), ``interface_hz`` the fixed-interface frequencies kept.
    """

    T: np.ndarray
    K: np.ndarray
    M: np.ndarray
    nb: int
    interface_hz: np.ndarray


def craig_bampton(K: np.ndarray, M: np.ndarray, boundary: Sequence[int], fixed: Sequence[int],
                  cutoff_hz: float, min_modes: int = 2) -> Reduction:
    """Craig-Bampton reduction (Craig & Bampton 1968) of ``K``, ``M`` with the coordinates
    ``fixed`` held at zero.

    Parameters
    ----------
    boundary : FE coordinates kept as physical coordinates (in this order).
    cutoff_hz : fixed-interface modes below this frequency are kept (at least
        ``min_modes``). The reduced model's modes are accurate well below the cutoff
        (checked against the full model in ``tests/models/test_bolted_beam.py``).
    """
    n = len(K)
    boundary = list(boundary)
    if len(set(boundary)) != len(boundary) or set(boundary) & set(fixed):
        raise ValueError("boundary coordinates must be distinct and not fixed")
    interior = np.setdiff1d(np.arange(n), np.concatenate([boundary, fixed]).astype(int))
    Kii, Kib = K[np.ix_(interior, interior)], K[np.ix_(interior, boundary)]
    Mii = M[np.ix_(interior, interior)]
    try:
        cho = sl.cho_factor(Kii)
    except np.linalg.LinAlgError:
        raise SensfwError("the beams are not held once their attachment points are fixed "
                          "(a beam needs two points or a support)") from None
    Psi = -sl.cho_solve(cho, Kib)
    w2, Phi = sl.eigh(Kii, Mii)
    keep = max(min_modes, int(np.sum(w2 < (2 * np.pi * cutoff_hz) ** 2)))
    keep = min(keep, len(interior))
    w2, Phi = w2[:keep], Phi[:, :keep]
    nb = len(boundary)
    T = np.zeros((n, nb + keep))
    T[boundary, np.arange(nb)] = 1.0
    T[np.ix_(interior, np.arange(nb))] = Psi
    T[np.ix_(interior, nb + np.arange(keep))] = Phi
    Kr, Mr = T.T @ K @ T, T.T @ M @ T
    return Reduction(T=T, K=0.5 * (Kr + Kr.T), M=0.5 * (Mr + Mr.T), nb=nb,
                     interface_hz=np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi))
