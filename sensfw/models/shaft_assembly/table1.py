"""Table 1 of the paper (+ the bearings' axial preload) and the fixed data of the shaft model.

Parameters carry Table 1's names, units (N, mm, s) and bounds. Table 1 prints the stiction and
friction velocities with swapped names relative to Table 2 and Adams (stiction transition
velocity < friction transition velocity); we follow Table 2/Adams: ``slide_v_friction`` spans
0.1-10 mm/s and ``slide_v_stiction`` 0.01-1 mm/s (10 % of it, Table 2 footnote).
"""

from __future__ import annotations

from dataclasses import dataclass

from ...params import Parameter, ParameterSet

# --------------------------------------------------------------------------------------------
# Table 1 (+ preload). Stiffness "N/mm" means N/mm^b: force in N for a penetration in mm.
_P = Parameter
PARAMETERS = ParameterSet([
    _P("slide_mu_static", "", 0.10, 0.05, 0.15, "static friction coefficient", "Slide bearing"),
    _P("slide_mu_dynamic", "", 0.05, 0.02, 0.10, "dynamic friction coefficient",
       "Slide bearing"),
    _P("slide_v_stiction", "mm/s", 0.1, 0.01, 1.0,
       "stiction transition velocity (Table 1 'friction velocity')", "Slide bearing"),
    _P("slide_v_friction", "mm/s", 1.0, 0.1, 10.0,
       "friction transition velocity (Table 1 'stiction velocity')", "Slide bearing"),
    _P("slide_stiffness", "N/mm", 7.05e5, 7.05e4, 7.05e6, "contact stiffness coefficient",
       "Slide bearing"),
    _P("slide_exponent", "", 1.33, 1.20, 1.46, "contact stiffness exponent", "Slide bearing"),
    _P("slide_clearance", "mm", 5e-3, 1e-3, 1e-2, "radial clearance", "Slide bearing"),
    _P("slide_damping", "N*s/mm", 234.0, 1.0, 468.0, "contact damping coefficient",
       "Slide bearing"),
    _P("spring_stiffness", "N/mm", 0.3, 0.15, 0.45, "clutch spring stiffness", "Clutch - Spring"),
    _P("spring_damping", "N*s/mm", 1e-3, 1e-4, 1e-2, "clutch spring damping",
       "Clutch - Spring"),
    _P("clutch_drive_stiffness", "N/mm", 3.14e6, 3.14e5, 3.14e7, "contact stiffness coefficient",
       "Clutch - Driveshaft"),
    _P("clutch_drive_exponent", "", 1.31, 1.18, 1.44, "contact stiffness exponent",
       "Clutch - Driveshaft"),
    _P("clutch_drive_damping", "N*s/mm", 257.3, 1.0, 514.6, "contact damping coefficient",
       "Clutch - Driveshaft"),
    _P("clutch_crank_stiffness", "N/mm", 7.78e4, 7.78e3, 7.78e5, "contact stiffness coefficient",
       "Clutch - Crankshaft"),
    _P("clutch_crank_exponent", "", 0.99, 0.89, 1.09, "contact stiffness exponent",
       "Clutch - Crankshaft"),
    _P("clutch_crank_damping", "N*s/mm", 40.5, 1.0, 81.0, "contact damping coefficient",
       "Clutch - Crankshaft"),
    _P("l1_clearance", "mm", 5e-3, 1e-3, 1e-2, "radial clearance", "Bearing L1"),
    _P("l1_damping", "N*s/mm", 1e-2, 1e-3, 1e-1, "damping coefficient", "Bearing L1"),
    _P("l3_clearance", "mm", 5e-3, 1e-3, 1e-2, "radial clearance", "Bearing L3"),
    _P("l3_damping", "N*s/mm", 1e-2, 1e-3, 1e-1, "damping coefficient", "Bearing L3"),
    _P("bearing_preload", "N", 100.0, 50.0, 200.0, "axial preload of L1/L3 (wave spring)",
       "Bearings"),
])

#: Sect. 3.1: parameters moved together in the screen (19 design variables from 21).
GROUPS = {
    "slide_friction_coefficient": ("slide_mu_static", "slide_mu_dynamic"),
    "slide_friction_velocity": ("slide_v_friction", "slide_v_stiction"),
}


@dataclass(frozen=True)
class Geometry:
    """Fixed model data (SI). Not design variables; documented so users can see them."""

    m_drive: float = 0.50  # kg
    j_drive: float = 6.0e-4  # kg m^2
    m_crank: float = 0.40  # kg, crankshaft + shaker armature
    j_crank: float = 8.0e-4
    m_clutch: float = 0.04
    x_l1: float = -0.045  # bearing positions on D (m, from D's centre of mass)
    x_l3: float = 0.045
    x_sb: tuple[float, float] = (-0.035, 0.035)  # slide bearings
    r_sb: float = 0.010  # slide bearing bore radius (friction and the flange act there)
    x_clutch: float = -0.015
    r_clutch: float = 0.016
    ramp_angle_deg: float = 30.0  # clutch-crankshaft ramp face, from the shaft axis
    x_force: float = 0.080  # shaker attachment on C
    x_sensor: float = -0.070  # accelerometers on C
    r_sensor: float = 0.008
    # roller bearings L1/L3 (Adams Bearing AT in the paper; fixed here)
    bearing_radial_k: float = 2.0e5  # N/mm^b
    bearing_radial_b: float = 10.0 / 9.0  # line contact
    bearing_axial_k: float = 1.0e5  # N/mm^b, shoulder contact under preload
    bearing_axial_b: float = 1.5  # point contact
    wave_spring_k: float = 20.0  # N/mm
    spring_precompression: float = 10.0  # mm
    dmax: float = 0.01  # mm, penetration at which contact damping is fully active
