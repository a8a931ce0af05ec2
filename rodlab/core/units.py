"""Units: the one place where rodlab converts.

Interfaces use mm, N, s, deg, kg (names carry the unit). Internally the mechanics uses
the consistent set mm - N - tonne(1e3 kg) is *not* used; instead stiffness in N/mm^2
(= MPa) with lengths in mm gives compliances in mm/N directly, and masses in kg are
turned into forces in N with :data:`G0`.
"""
from __future__ import annotations

import numpy as np

__all__ = [
    "G0",
    "gpa_to_mpa",
    "kg_m3_to_kg_mm3",
    "deg2rad",
    "rad2deg",
    "um_from_mm",
    "DEVICE_NOISE_MM",
    "TRACKER_NOISE_MM",
    "PAPER_ROD_SLIP",
    "PAPER_C_ROD_UM_RANGE",
    "PAPER_R_ROD",
]

#: Standard gravity [m/s^2]; loads in the contract are ``mass_kg * G0`` newtons.
G0: float = 9.80665

#: Default measurement noise per coordinate [mm], 1 sigma: the MultiCal device (paper), and a laser tracker at
#: 2-5 m (typical specification U = 15 um + 6 um/m, about 25 um at 1 sigma per coordinate).
DEVICE_NOISE_MM: float = 0.003
TRACKER_NOISE_MM: float = 0.025

#: The study's default rod slip (the rod's non-repeatable deflection, in multiples of its own weight in a random
#: direction; docs/study.md: fitted to the paper's Table 3 Meas column): ``rodlab study`` and the demo's study.
PAPER_ROD_SLIP: float = 2.4

#: The compliance index c_rod [um] of the paper's measured rods (Table 2: 57.9 um carbon 1# .. 1306.2 um steel 6#):
#: the range :data:`PAPER_ROD_SLIP` was fitted on.
PAPER_C_ROD_UM_RANGE: tuple[float, float] = (57.9, 1306.2)

#: The correction factor r_rod (Eq. 21: measured / simulated) of the paper's measured rods (Table 2): 1.01 (the steel
#: rods) to 2.30 (carbon 3#)
PAPER_R_ROD: tuple[float, float] = (1.01, 2.30)


def gpa_to_mpa(value_gpa: float) -> float:
    """Young's/shear modulus GPa -> N/mm^2 (MPa)."""
    return float(value_gpa) * 1.0e3


def kg_m3_to_kg_mm3(density_kg_m3: float) -> float:
    """Density kg/m^3 -> kg/mm^3."""
    return float(density_kg_m3) * 1.0e-9


def deg2rad(value_deg):
    """Degrees -> radians (scalars or arrays)."""
    return np.deg2rad(value_deg)


def rad2deg(value_rad):
    """Radians -> degrees (scalars or arrays)."""
    return np.rad2deg(value_rad)


def um_from_mm(value_mm):
    """Millimetres -> micrometres."""
    return np.asarray(value_mm) * 1.0e3
