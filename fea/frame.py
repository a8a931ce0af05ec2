"""Fast beam-frame model of a rod (for design sweeps), checked against the solid model.

The rod is a tree of Timoshenko beams clamped at the flange: tubes with their (transversely
isotropic: E axial for bending and tension, G axial for torsion and shear) sections, rings and holders
as composite sections, the bend as a curved beam whose bending compliance is scaled by pipe-bend
flexibility factors (ovalisation), the ball and ball holder as the tip's mass. Because the frame is
statically determinate, its tip compliance follows exactly from the unit-load method along the
centreline (:mod:`rodlab.calc`): no element discretisation error, ~2-4 ms per design.

Bend flexibility: ASME B31.3 Appendix D, ``k = 1.65 / h`` with ``h = t R / r_m^2`` (t wall, R bend
radius, r_m mean tube radius), ``k >= 1``, for in-plane and out-of-plane bending, reduced by the end
restraint of sleeves at both tangent points by ASME's flanged-end factor ``c = h^(1/3)`` (both ends).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.calc import calc_compliance
from rodlab.design import RodDesign

__all__ = ["BendFlexibility", "asme_bend_flexibility", "frame_compliance"]


@dataclass(frozen=True)
class BendFlexibility:
    """Factors on the bend's bending compliance: ``in_plane`` and ``out_of_plane`` [-], >= 1."""

    in_plane: float
    out_of_plane: float

    def __post_init__(self) -> None:
        for k in ("in_plane", "out_of_plane"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"bend flexibility {k} must be a positive number, got {v!r}")


def asme_bend_flexibility(design: RodDesign) -> BendFlexibility:
    """ASME B31.3 flexibility factors of the design's bend (1 for a straight rod)."""
    if not design.has_bend:
        return BendFlexibility(1.0, 1.0)
    b = design.bend
    t = b.wall_mm
    r_m = (b.outer_diameter_mm - t) / 2.0
    h = t * b.radius_mm / r_m ** 2
    k = 1.65 / h
    if design.rings.present:          # sleeves bonded at both tangent points restrain ovalisation
        k *= h ** (1.0 / 3.0)
    k = max(k, 1.0)
    return BendFlexibility(k, k)


def frame_compliance(design: RodDesign, bend: BendFlexibility | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Frame-model C_F [mm/N] and C_g [mm/g0] in {T}, shape=(3, 3) each."""
    bend = asme_bend_flexibility(design) if bend is None else bend
    CF, Cg = calc_compliance(design, shear=True, axial=True, bend_flexibility=(bend.in_plane, bend.out_of_plane))
    return 0.5 * (CF + CF.T), Cg
