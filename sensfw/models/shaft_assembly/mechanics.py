"""Mechanics of the shaft assembly: its bodies, its places and its force elements for one
parameter set (a :class:`~sensfw.models.planar.Mechanism`).

Axial (x) / vertical radial (y) plane, gravity along -y, SI units inside (parameters come in
Table 1's N, mm, s):

* **driveshaft D** (rigid body) in the housing on the roller bearings **L1** and **L3**:
  radial penalty contacts with radial clearance and ramped damping; an axial shoulder contact
  at L3 closed by the wave-spring **preload**.
* **crankshaft C** (rigid body, the shaker armature attached at its end) nested in D on two
  **slide bearings**: radial contacts with clearance, Hertz-like exponent and ramped damping,
  regularised stick-slip **friction** in the axial direction driven by the normal force, and
  the bushing **flange** that stops C axially against D.
* **clutch K** (point mass) guided radially in D's bore (**clutch-driveshaft** contact, no
  play), pushed axially by the **clutch spring** (seated on D) onto an inclined ramp face at
  the bottom of C (**clutch-crankshaft** contact). The ramp turns relative radial motion
  into axial force: the path by which the radial shaker force reaches the axial crankshaft
  acceleration; its radial component keeps both slide bearings loaded.

Every contact is a named :class:`~sensfw.models.places.Place` with its own law; the force
elements evaluate their contacts through the contact evaluator by place name, so an effect
that replaces a place's law changes exactly that contact. Every contact evaluates its
tangential law too (``None``, i.e. nothing, unless the law has friction).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from ...errors import ParameterError
from ...params import MM
from ..contact import FrictionLaw, PenaltyLaw, stiffness_si
from ..places import Place
from ..planar import Body, Link, Mechanism, plus
from .table1 import Geometry

HOUSING = "H"  # ground


def places(g: Geometry) -> dict[str, Place]:
    """The places of the assembly: its eight contacts and its three bodies."""
    a = math.radians(g.ramp_angle_deg)
    ca, sa = math.cos(a), math.sin(a)
    sb = g.r_sb
    axial, radial = (1.0, 0.0), (0.0, 1.0)
    out = [
        Place("bearing_l1", "contact", "roller bearing L1, radial (housing - driveshaft)",
              HOUSING, (g.x_l1, 0.0), "D", (g.x_l1, 0.0), radial, axial),
        Place("bearing_l3", "contact", "roller bearing L3, radial (housing - driveshaft)",
              HOUSING, (g.x_l3, 0.0), "D", (g.x_l3, 0.0), radial, axial),
        Place("bearing_l3_shoulder", "contact", "axial shoulder of L3 under the wave-spring "
              "preload (housing - driveshaft)", HOUSING, (g.x_l3, 0.0), "D", (g.x_l3, 0.0),
              (-1.0, 0.0), radial),
        Place("slide_bearing_1", "contact", "slide bearing 1, radial, with axial stick-slip "
              "friction (driveshaft - crankshaft)", "D", (g.x_sb[0], -sb), "C",
              (g.x_sb[0], -sb), radial, axial),
        Place("slide_bearing_2", "contact", "slide bearing 2, radial, with axial stick-slip "
              "friction (driveshaft - crankshaft)", "D", (g.x_sb[1], -sb), "C",
              (g.x_sb[1], -sb), radial, axial),
        Place("flange", "contact", "bushing flange of slide bearing 2, axial stop "
              "(driveshaft - crankshaft)", "D", (g.x_sb[1], -sb), "C", (g.x_sb[1], -sb),
              (-1.0, 0.0), radial),
        Place("clutch_drive", "contact", "radial guidance of the clutch in the driveshaft's "
              "bore (driveshaft - clutch)", "D", (g.x_clutch, 0.0), "K", (0.0, 0.0),
              radial, axial),
        Place("clutch_crank", "contact", "inclined ramp face between clutch and crankshaft",
              "C", (g.x_clutch, -g.r_clutch), "K", (0.0, 0.0), (-ca, sa), (sa, ca)),
        Place("driveshaft", "body", "driveshaft, at bearing L3 (its accelerometers)",
              HOUSING, (g.x_l3, 0.0), "D", (g.x_l3, 0.0), radial, axial),
        Place("crankshaft", "body", "crankshaft, at its end (shaker and armature)",
              HOUSING, (g.x_force, 0.0), "C", (g.x_force, 0.0), radial, axial),
        Place("clutch", "body", "clutch", HOUSING, (g.x_clutch, 0.0), "K", (0.0, 0.0),
              radial, axial),
    ]
    return {p.name: p for p in out}


def laws(p: Mapping[str, float], g: Geometry) -> dict[str, PenaltyLaw]:
    """The law of every contact place (SI) for parameter values ``p`` (paper units)."""
    dmax = g.dmax * MM

    def law(k, b, c, friction=None):
        return PenaltyLaw(k=stiffness_si(k, b), b=b, c=c * 1e3, dmax=dmax, friction=friction)

    mu_s, mu_d = p["slide_mu_static"], p["slide_mu_dynamic"]
    v_s, v_t = p["slide_v_stiction"] * MM, p["slide_v_friction"] * MM
    if not v_s < v_t:
        raise ParameterError(
            f"slide_v_stiction ({p['slide_v_stiction']:g} mm/s) must be below "
            f"slide_v_friction ({p['slide_v_friction']:g} mm/s): Eq. 3 blends the static "
            "into the dynamic coefficient between the two (group them to move together)")
    slide = (p["slide_stiffness"], p["slide_exponent"], p["slide_damping"])
    friction = FrictionLaw(mu_s, mu_d, v_s, v_t)
    return {
        "bearing_l1": law(g.bearing_radial_k, g.bearing_radial_b, p["l1_damping"]),
        "bearing_l3": law(g.bearing_radial_k, g.bearing_radial_b, p["l3_damping"]),
        "bearing_l3_shoulder": law(g.bearing_axial_k, g.bearing_axial_b, p["l3_damping"]),
        "slide_bearing_1": law(*slide, friction),
        "slide_bearing_2": law(*slide, friction),
        "flange": law(*slide),
        "clutch_drive": law(p["clutch_drive_stiffness"], p["clutch_drive_exponent"],
                            p["clutch_drive_damping"]),
        "clutch_crank": law(p["clutch_crank_stiffness"], p["clutch_crank_exponent"],
                            p["clutch_crank_damping"]),
    }


def bodies(g: Geometry) -> list[Body]:
    """Driveshaft D, crankshaft C (with the shaker armature), clutch K."""
    return [Body("D", 3, g.m_drive, g.j_drive), Body("C", 3, g.m_crank, g.j_crank),
            Body("K", 2, g.m_clutch, 0.0, (g.x_clutch, 0.0))]


def links(p: Mapping[str, float], g: Geometry) -> list[Link]:
    """The force elements of the assembly; each evaluates its contacts by place name."""

    def bearing(place, clearance):
        def law(ops, u, v, contact):
            fy = contact.two_sided(place, u[1], v[1], clearance * MM)
            return plus(0.0, contact.tangential(place, ops.abs(fy), v[0])), fy
        return law

    def bearing_l3(ops, u, v, contact):
        # radial play as L1; axially the wave spring's preload pushes D (+x) onto the
        # shoulder of L3 (the housing)
        fy = contact.two_sided("bearing_l3", u[1], v[1], p["l3_clearance"] * MM)
        shoulder = contact.one_sided("bearing_l3_shoulder", u[0], v[0])
        fx = p["bearing_preload"] - g.wave_spring_k * 1e3 * u[0] - shoulder
        fx = plus(fx, contact.tangential("bearing_l3", ops.abs(fy), v[0]))
        fy = plus(fy, contact.tangential("bearing_l3_shoulder", shoulder, v[1]))
        return fx, fy

    def slide(place, flange):
        def law(ops, u, v, contact):
            # C relative to D at the bottom of the bore: radial play; axial stick-slip
            # friction driven by the normal force (Eq. 3); SB2's bushing flange stops C
            # moving +x
            fy = contact.two_sided(place, u[1], v[1], p["slide_clearance"] * MM)
            friction = contact.tangential(place, ops.abs(fy), v[0])
            fx = 0.0 if friction is None else friction
            if flange:
                stop = contact.one_sided("flange", u[0], v[0])
                fx = fx - stop
                fy = plus(fy, contact.tangential("flange", stop, v[1]))
            return fx, fy
        return law

    def clutch_drive(ops, u, v, contact):
        # K relative to D: radial guidance (no play); the clutch spring seated on D
        fy = contact.two_sided("clutch_drive", u[1], v[1], 0.0)
        fx = p["spring_stiffness"] * 1e3 * (g.spring_precompression * MM - u[0]) \
            - p["spring_damping"] * 1e3 * v[0]
        return plus(fx, contact.tangential("clutch_drive", ops.abs(fy), v[0])), fy

    a = math.radians(g.ramp_angle_deg)
    ca, sa = math.cos(a), math.sin(a)

    def clutch_crank(ops, u, v, contact):
        # K relative to C: ramp face at the bottom of the clutch, normal (-cos a, sin a)
        # on K; K moving +x (or -y) into C penetrates
        fn = contact.one_sided("clutch_crank", ca * u[0] - sa * u[1], ca * v[0] - sa * v[1])
        fx, fy = -ca * fn, sa * fn
        ft = contact.tangential("clutch_crank", fn, sa * v[0] + ca * v[1])
        if ft is not None:
            fx, fy = fx + sa * ft, fy + ca * ft
        return fx, fy

    sb = g.r_sb
    return [
        Link("bearing_l1", HOUSING, (g.x_l1, 0.0), "D", (g.x_l1, 0.0),
             bearing("bearing_l1", p["l1_clearance"])),
        Link("bearing_l3", HOUSING, (g.x_l3, 0.0), "D", (g.x_l3, 0.0), bearing_l3),
        Link("slide_bearing_1", "D", (g.x_sb[0], -sb), "C", (g.x_sb[0], -sb),
             slide("slide_bearing_1", False)),
        Link("slide_bearing_2", "D", (g.x_sb[1], -sb), "C", (g.x_sb[1], -sb),
             slide("slide_bearing_2", True)),
        Link("clutch_drive", "D", (g.x_clutch, 0.0), "K", (0.0, 0.0), clutch_drive),
        Link("clutch_crank", "C", (g.x_clutch, -g.r_clutch), "K", (0.0, 0.0), clutch_crank),
    ]


def mechanism(p: Mapping[str, float], g: Geometry) -> Mechanism:
    """The assembly for parameter values ``p`` (before any effect)."""
    return Mechanism(bodies=bodies(g), links=links(p, g), laws=laws(p, g), places=places(g),
                     ground=HOUSING)
