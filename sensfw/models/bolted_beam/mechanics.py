"""Mechanics of the bolted lap-joint beam for one parameter set: its beams, places, laws
and force elements (a :class:`~.assembly.BeamAssembly`).

* **beam1** (clamped) from inside the clamp (``-clamp_depth``, pinned there) to the end of
  the overlap; **beam2** from the start of the overlap to the free end. Over the overlap
  each is thinned to half the thickness, beam1 above the interface plane, beam2 below.
* **clamp** (a contact place): the two jaws at the clamp edge push on beam1 from either side,
  each a one-sided penalty contact preloaded by the clamp's bolts; with the pin at the back
  of the clamped length they hold the root's displacement and rotation.
* **joint** (a joint place): the interface of the half-lap joint, a linear law shared by
  ``interface_points`` equally spaced point pairs (beam1 and beam2 at the same x): the
  tangential law acts on the slip ``u2 - u1`` (bending of the overlap makes the interface
  slip, since each half bends about its own centroid), the normal law keeps the halves
  together.
* **beam1**, **beam2** (body places): at the shaker's drive point and at the free end.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from ...params import MM
from ..contact import PenaltyLaw
from ..joint import LinearJoint
from ..places import Place
from ..planar import Link, plus
from .assembly import BeamAssembly
from .fe import Beam
from .parameters import Geometry

GROUND = "ground"
TRANSVERSE, AXIAL = (0.0, 1.0), (1.0, 0.0)


def beams(g: Geometry) -> list[Beam]:
    """The two beams; the half-lap tongues are offset by a quarter thickness."""
    thin = (g.joint_start, g.joint_end)
    return [Beam("beam1", -g.clamp_depth, g.joint_end, thin, +g.thickness / 4),
            Beam("beam2", g.joint_start, g.free_end, thin, -g.thickness / 4)]


def places(g: Geometry) -> dict[str, Place]:
    """The joint, the clamp and the two beams."""
    xj = g.joint_x
    pairs = tuple(((x, 0.0), (x, 0.0)) for x in g.interface_x())
    out = [
        Place("joint", "joint", "bolted half-lap joint, interface slip along the beams "
              "(beam1 - beam2, at the free-side end of the overlap)", "beam1", (xj, 0.0),
              "beam2", (xj, 0.0), TRANSVERSE, AXIAL, pairs),
        Place("clamp", "contact", "clamp jaws at the clamp edge (ground - beam1)", GROUND,
              (0.0, 0.0), "beam1", (0.0, 0.0), TRANSVERSE, AXIAL),
        Place("beam1", "body", "clamped beam, at the shaker's drive point", GROUND,
              (g.shaker_x, 0.0), "beam1", (g.shaker_x, 0.0), TRANSVERSE, AXIAL),
        Place("beam2", "body", "free beam, at its free end (Acc1, laser)", GROUND,
              (g.free_end, 0.0), "beam2", (g.free_end, 0.0), TRANSVERSE, AXIAL),
    ]
    # the beam's integrator carries Jenkins sliders (simulation.JenkinsSliders) anywhere
    return {p.name: replace(p, offers=frozenset({"add_jenkins"})) for p in out}


def laws(p: Mapping[str, float], g: Geometry) -> dict:
    """Joint: linear (``joint_stiffness``, ``joint_damping``, stiff normal contact);
    clamp: a linear penalty law per jaw (half of ``clamp_stiffness`` each)."""
    return {
        "joint": LinearJoint(k_t=p["joint_stiffness"] / MM, c_t=p["joint_damping"] / MM,
                             k_n=g.joint_normal_stiffness),
        "clamp": PenaltyLaw(k=0.5 * p["clamp_stiffness"] / MM, b=1.0, c=0.0, dmax=1e-6),
    }


def links(p: Mapping[str, float], g: Geometry) -> list[Link]:
    """Joint interface points and the clamp jaws; each evaluates its place's law."""
    share = 1.0 / g.interface_points

    def interface(ops, u, v, contact):
        # beam2 relative to beam1 at the same x: slip along the beam, normal across it
        return (share * contact.slip("joint", u[0], v[0]),
                share * contact.gap("joint", u[1], v[1]))

    preload = g.clamp_preload / (0.5 * p["clamp_stiffness"] / MM)  # jaw penetration, m

    def clamp(ops, u, v, contact):
        # beam1 relative to the ground: the lower jaw pushes +y, the upper one -y
        lower = contact.one_sided("clamp", preload - u[1], -v[1])
        upper = contact.one_sided("clamp", preload + u[1], v[1])
        fx = plus(0.0, contact.tangential("clamp", lower + upper, v[0]))
        return fx, lower - upper

    out = [Link(f"joint_{i + 1}", "beam1", (x, 0.0), "beam2", (x, 0.0), interface)
           for i, x in enumerate(g.interface_x())]
    out.append(Link("clamp", GROUND, (0.0, 0.0), "beam1", (0.0, 0.0), clamp))
    return out


def sensor_points(g: Geometry) -> dict[str, tuple[str, float]]:
    """Accelerometers (transverse acceleration) and the laser (transverse velocity)."""
    return {"Acc1": ("beam2", g.acc1_x), "Acc2": ("beam2", g.acc2_x),
            "Acc3": ("beam1", g.acc3_x), "Acc4": ("beam1", g.acc4_x),
            "Laser": ("beam2", g.acc1_x)}


def assembly(p: Mapping[str, float], g: Geometry) -> BeamAssembly:
    """The assembly for parameter values ``p`` (before any effect)."""
    sensors = sensor_points(g)
    masses = [("beam1", x, g.bolt_mass) for x in g.bolt_x]
    masses += [(b, x, g.sensor_mass) for name, (b, x) in sensors.items() if name != "Laser"]
    if p["shaker_mass"] > 0:
        masses.append(("beam1", g.shaker_x, p["shaker_mass"]))
    required = [("beam1", g.shaker_x), *dict.fromkeys(sensors.values())]
    return BeamAssembly(beams=beams(g), links=links(p, g), laws=laws(p, g), places=places(g),
                        required=required, masses=masses,
                        supports=[("beam1", -g.clamp_depth, (0, 1))], ground=GROUND)
