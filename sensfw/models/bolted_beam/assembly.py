"""An assembly of flexible beams, force elements, laws and added bodies for one parameter
set: the :class:`~sensfw.models.places.Hooks` effects act through, and its reduced
structure evaluated with numpy (forces, statics, linearisation).

Points of a beam are given in *rig coordinates* ``r = (x, y)``: ``x`` from the clamp edge
along the beam, ``y`` across it, in the reference configuration (m); the beams' points an
assembly uses must lie on the reference line (``y = 0``: the joint's interface plane,
the mid-plane of the full beams). Every point something attaches to becomes a boundary
point of the Craig-Bampton reduction (:mod:`.fe`), i.e. two physical coordinates
``(u, w)`` of the reduced structure, where Exudyn attaches connectors, loads and sensors.
Bodies added by effects are point masses with their own two coordinates.

Reduced coordinate vector ``z = [points (u, w) ..., modal eta ..., added bodies (x, y) ...]``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from ...errors import SensfwError
from ..contact import numpy_ops
from ..places import Place, Point
from ..planar import Contacts, Link
from ..planar.mechanism import LinkHooks, anchored
from .fe import Beam, Mesh, Reduction, craig_bampton

Key = tuple[str, float]  # (beam, x)


class BeamContacts(Contacts):
    """The contact evaluator of :class:`~sensfw.models.planar.Contacts` plus joint laws:
    force elements call :meth:`slip` and :meth:`gap` with the joint's place name."""

    def slip(self, place: str, s, s_dot):
        """Tangential force of joint ``place`` for the slip ``s`` and its rate."""
        return self.laws[place].tangential(self.ops, s, s_dot)

    def gap(self, place: str, g, g_dot):
        """Normal force of joint ``place`` for the relative normal displacement ``g``."""
        return self.laws[place].normal(self.ops, g, g_dot)


@dataclass
class BeamAssembly(LinkHooks):
    """Beams, force elements, laws by place, places, point masses and added bodies.

    Implements :class:`~sensfw.models.places.Hooks`. ``required`` are points the model
    needs as coordinates whatever the effects (sensors, the shaker); ``masses`` are point
    masses ``(beam, x, kg)`` lumped into the FE mass matrix; ``supports`` are FE nodes
    ``(beam, x, (component, ...))`` held at zero (0 = u, 1 = w, 2 = theta).
    """

    beams: list[Beam]
    links: list[Link]
    laws: dict
    places: dict[str, Place]
    required: list[Key]
    masses: list[tuple[str, float, float]]
    supports: list[tuple[str, float, tuple[int, ...]]]
    ground: str = "ground"
    added: dict[str, tuple[float, Key]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # the model's own force elements and laws, before effects (the structure's damping)
        self.base_links, self.base_laws = len(self.links), dict(self.laws)

    # ---- hooks for effects (and LinkHooks') -------------------------------------------------
    def add_jenkins(self, name: str, body0: str, r0: Point, body1: str, r1: Point,
                    direction: Point, stiffness: float, slip_force: float) -> None:
        d = tuple(float(c) for c in direction)
        if d not in ((1.0, 0.0), (0.0, 1.0)):
            raise SensfwError(f"Jenkins element {name!r}: direction {direction} must be a "
                              "coordinate axis, (1, 0) or (0, 1)")
        if not (stiffness > 0 and slip_force > 0):
            raise SensfwError(f"Jenkins element {name!r} needs a positive stiffness and slip "
                              f"force, got {stiffness:g} N/m, {slip_force:g} N")
        k = float(stiffness)

        def stuck(ops, u, v):
            s = u[0] * d[0] + u[1] * d[1]
            return -k * s * d[0], -k * s * d[1]

        self.add_force(name, body0, r0, body1, r1, stuck, about_static=True)
        self.links[-1] = replace(self.links[-1], jenkins=(k, float(slip_force), d))

    def add_body(self, name: str, mass: float, follows: tuple[str, Point]) -> None:
        body, r = follows
        if name in self.added or name == self.ground or name in self.beam_names:
            raise SensfwError(f"a body named {name!r} exists already")
        if not mass > 0:
            raise SensfwError(f"body {name!r} needs a positive mass, got {mass}")
        self._check(body, r)
        self.added[name] = (float(mass), (body, float(r[0])))

    def add_mass(self, body: str, mass: float, at: Point) -> None:
        if body in self.added:
            m, follows = self.added[body]
            self.added[body] = (m + float(mass), follows)
            return
        self._check(body, at)
        if body == self.ground:
            return  # mass on the ground changes nothing
        self.masses.append((body, float(at[0]), float(mass)))

    # ---- points -------------------------------------------------------------------------------
    @property
    def beam_names(self) -> list[str]:
        return [b.name for b in self.beams]

    def _check(self, body: str, r: Point) -> None:
        if body == self.ground or body in self.added:
            return
        beam = {b.name: b for b in self.beams}.get(body)
        if beam is None:
            raise SensfwError(f"no body {body!r}; bodies: "
                              f"{', '.join([*self.beam_names, *self.added])}")
        if abs(r[1]) > 1e-12:
            raise SensfwError(f"points of {body} must lie on its reference line (y = 0, the "
                              f"joint's interface plane); got y = {r[1]:g} m")
        if not beam.contains(r[0]):
            raise SensfwError(f"x = {r[0] * 1e3:g} mm is not on {body} "
                              f"({beam.x0 * 1e3:g} ... {beam.x1 * 1e3:g} mm)")

    def points(self) -> list[Key]:
        """The boundary points, in order: required ones, then those of force elements and
        followed by added bodies (first use)."""
        out: list[Key] = []

        def use(body, x):
            key = (body, round(float(x), 9))
            if body in self.beam_names and key not in out:
                out.append(key)

        for body, x in self.required:
            use(body, x)
        for ln in self.links:
            use(ln.body0, ln.r0[0])
            use(ln.body1, ln.r1[0])
        for _, (body, x) in self.added.values():
            use(body, x)
        return out

    # ---- reduction ---------------------------------------------------------------------------
    def reduce(self, E: float, rho: float, width: float, h: float, max_element: float,
               cutoff_hz: float) -> Structure:
        """The Craig-Bampton reduced structure of the beams with the current points."""
        pts = self.points()
        required: dict[str, list[float]] = {b: [] for b in self.beam_names}
        for body, x in [*pts, *[(b, x) for b, x, _ in self.masses],
                        *[(b, x) for b, x, _ in self.supports]]:
            required[body].append(x)
        mesh = Mesh(self.beams, required, max_element)
        K, M = mesh.matrices(E, rho, width, h, self.masses)
        boundary = [mesh.dof(b, x) + c for b, x in pts for c in (0, 1)]
        fixed = [mesh.dof(b, x) + c for b, x, comps in self.supports for c in comps]
        red = craig_bampton(K, M, boundary, fixed, cutoff_hz)
        return Structure(self, pts, red, mesh)


class Structure:
    """The reduced beams of an assembly and the coordinates of its points and bodies.

    ``n_struct`` coordinates belong to the beams (``2 * len(points)`` physical, then modal),
    then two per added body. :meth:`forces` evaluates the force elements with numpy.
    """

    def __init__(self, assembly: BeamAssembly, points: list[Key], red: Reduction, mesh: Mesh):
        self.assembly, self.points, self.red, self.mesh = assembly, points, red, mesh
        self.index = {k: 2 * i for i, k in enumerate(points)}
        self.n_struct = len(red.K)
        self.bodies = list(assembly.added)
        self.body_index = {b: self.n_struct + 2 * i for i, b in enumerate(self.bodies)}
        self.n = self.n_struct + 2 * len(self.bodies)

    def coordinate(self, body: str, r: Point) -> int | None:
        """Index of the x coordinate of a point (``None`` for the ground)."""
        a = self.assembly
        if body == a.ground:
            return None
        if body in self.body_index:
            return self.body_index[body]
        return self.index[(body, round(float(r[0]), 9))]

    def masses(self) -> np.ndarray:
        """Mass matrix of all coordinates (reduced beams, then added bodies)."""
        M = np.zeros((self.n, self.n))
        M[:self.n_struct, :self.n_struct] = self.red.M
        for b in self.bodies:
            i = self.body_index[b]
            M[i, i] = M[i + 1, i + 1] = self.assembly.added[b][0]
        return M

    def stiffness(self) -> np.ndarray:
        """Stiffness of the beams themselves (force elements excluded)."""
        K = np.zeros((self.n, self.n))
        K[:self.n_struct, :self.n_struct] = self.red.K
        return K

    def start(self) -> np.ndarray:
        """Zero displacement; added bodies start where the point they follow is."""
        return np.zeros(self.n)

    def follow(self, z: np.ndarray) -> None:
        """Set added bodies to the displacement of the point they follow (in place)."""
        for b in self.bodies:
            body, x = self.assembly.added[b][1]
            i = self.coordinate(body, (x, 0.0))
            j = self.body_index[b]
            z[j:j + 2] = (0.0, 0.0) if i is None else z[i:i + 2]

    def anchor(self, z: np.ndarray | None) -> None:
        """Measure the links declared ``about_static`` from the static state ``z`` (see
        :class:`~sensfw.models.planar.Link`); ``None`` releases them."""
        def displacement(body, r):
            i = self.coordinate(body, r)
            return (0.0, 0.0) if i is None else (z[i], z[i + 1])

        a = self.assembly
        a.links = anchored(a.links, None if z is None else displacement)

    def reference(self, body: str, r: Point) -> tuple[float, float]:
        """Reference position (rig coordinates) of a point of a body."""
        if body in self.assembly.added:
            return (self.assembly.added[body][1][1], 0.0)
        return (float(r[0]), float(r[1]))

    def forces(self, z, zd, contact=None, base: bool = False) -> np.ndarray:
        """Generalised forces of all force elements (numpy, SI); ``base``: only the model's
        own, with the laws they had before effects. ``z``, ``zd`` may hold several states
        as columns (shape ``(n, m)``): the laws evaluate them at once."""
        ops = numpy_ops()
        a = self.assembly
        contact = contact or BeamContacts(ops, a.base_laws if base else a.laws)
        z, zd = np.asarray(z, float), np.asarray(zd, float)
        f = np.zeros(np.broadcast_shapes(z.shape, zd.shape))
        zero = np.zeros(f.shape[1:])
        for ln in (a.links[:a.base_links] if base else a.links):
            if ln.about_static and ln.offset is None:
                continue  # solving the static state: the link carries no static force
            i0, i1 = self.coordinate(ln.body0, ln.r0), self.coordinate(ln.body1, ln.r1)
            u0 = (zero, zero) if i0 is None else (z[i0], z[i0 + 1])
            v0 = (zero, zero) if i0 is None else (zd[i0], zd[i0 + 1])
            u1 = (zero, zero) if i1 is None else (z[i1], z[i1 + 1])
            v1 = (zero, zero) if i1 is None else (zd[i1], zd[i1 + 1])
            ox, oy = ln.offset or (0.0, 0.0)
            fx, fy = ln.law(ops, (u1[0] - u0[0] - ox, u1[1] - u0[1] - oy),
                            (v1[0] - v0[0], v1[1] - v0[1]), contact)
            for i, s in ((i1, 1.0), (i0, -1.0)):
                if i is not None:
                    f[i] += s * fx
                    f[i + 1] += s * fy
        return f

    def residual(self, z, zd=None, load=None) -> np.ndarray:
        """``f_links + f_load - K z``: zero at a static state."""
        zd = np.zeros(self.n) if zd is None else zd
        r = self.forces(z, zd) - self.stiffness() @ z
        return r if load is None else r + load

    def linear_matrices(self, z0: np.ndarray, base: bool = False
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``M``, ``K`` (beams + force elements) and the force elements' damping at ``z0``
        (central differences, all coordinates at once); ``base``: the model's own force
        elements only."""
        n, h = self.n, 1e-9
        a = self.assembly
        contact = BeamContacts(numpy_ops(), a.base_laws if base else a.laws)
        E = np.eye(n) * h
        Z = np.asarray(z0, float)[:, None] + np.zeros((n, n))
        zero = np.zeros((n, n))
        K = self.stiffness() - (self.forces(Z + E, zero, contact, base)
                                - self.forces(Z - E, zero, contact, base)) / (2 * h)
        D = -(self.forces(Z, E, contact, base) - self.forces(Z, -E, contact, base)) / (2 * h)
        return self.masses(), K, D

    def displacement_rows(self, body: str, x: float) -> np.ndarray:
        """FE coordinates of the node of ``body`` at ``x`` as rows of the reduction
        (``q_fe[u, w, theta] = rows @ z_struct``); for mode shapes."""
        i = self.mesh.dof(body, x)
        return self.red.T[i:i + 3]


def modal_damping(M: np.ndarray, K: np.ndarray, zeta: float) -> np.ndarray:
    """``D = M Phi diag(2 zeta omega) Phi^T M`` (mass-normalised ``Phi``): every mode of
    ``(K, M)`` gets the damping ratio ``zeta`` (modes with ``omega^2 <= 0`` none)."""
    import scipy.linalg as sl

    w2, Phi = sl.eigh(K, M)
    w = np.sqrt(np.maximum(w2, 0.0))
    MP = M @ Phi
    D = (MP * (2.0 * zeta * w)) @ MP.T
    return 0.5 * (D + D.T)


def solve_static(structure: Structure, load: np.ndarray | None = None,
                 model: str = "model", params: Mapping[str, float] | None = None,
                 guess: np.ndarray | None = None) -> np.ndarray:
    """Static state of the force elements and the beams under ``load`` (trust-region least
    squares, displacements scaled by 1 um; zero when nothing loads the structure)."""
    from scipy.optimize import least_squares

    from ...errors import SimulationError

    z = structure.start() if guess is None else np.array(guess, float)
    structure.follow(z)
    structure.anchor(None)  # links centred on the static state carry no static force
    r0 = structure.residual(z, load=load)
    if np.max(np.abs(r0), initial=0.0) < 1e-9:
        structure.anchor(z)
        return z
    scale = 1e-6
    sol = least_squares(lambda x: structure.residual(x * scale, load=load), z / scale,
                        method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    worst = float(np.max(np.abs(sol.fun)))
    if not np.all(np.isfinite(sol.x)) or worst > 1e-6:
        raise SimulationError(model, f"no static equilibrium (residual {worst:.3g} N)",
                              params or {})
    structure.anchor(sol.x * scale)
    return sol.x * scale
