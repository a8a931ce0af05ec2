"""Fast beam-frame model of a rod (for design sweeps), calibrated against the solid model.

The rod is a tree of Timoshenko beams clamped at the flange: tubes with their (transversely isotropic:
E axial for bending and tension, G axial for torsion and shear) sections, rings, holders and the ball
holder's plug as composite sections, the bend as a curved beam whose bending compliance is scaled by
pipe-bend flexibility factors (ovalisation), the ball as the tip's rigid mass. Because the frame is
statically determinate its tip compliance follows exactly from the unit-load method along the centreline
(:func:`rodlab.calc.unit_load_compliance`): no element discretisation error, a few ms per design.

Two effects that beam theory misses are modelled and calibrated once against the solid model
(``scripts/calibrate_frame.py``, data in ``fea/data/solid_reference.json``):

- load transfer into a bonded sleeve or plug (shear lag): near each end of a sleeve that is not at the
  clamp, the sleeve is not yet carrying its share of the bending; the frame treats
  ``sleeve_end * sqrt(t_tube * t_sleeve) * sqrt(E / G / 2.6)`` of it (E, G of the tube) as absent there for
  bending, shear and tension. Torsion passes into the sleeve at once (calibrating a separate torsion zone
  gave ~0);
- pipe-bend flexibility: ASME B31.3 ``k = 1.65 / h`` (``h = t R / r_m^2``), scaled by ``bend_scale``
  for the restraint of the rings at both tangent points, ``k >= 1``, for in- and out-of-plane bending.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rodlab.calc import unit_load_compliance
from rodlab.design import RodDesign
from rodlab.enums import Part
from rodlab.layout import Segment, SegmentKind, layout
from rodlab.massprops import ball_mass_properties

__all__ = ["BendFlexibility", "FrameCalibration", "CALIBRATION", "asme_bend_flexibility", "frame_compliance",
           "frame_segments", "calibrate_frame", "frame_errors"]

_SLEEVES = (Part.PIPE_HOLDER, Part.RING_1, Part.RING_2, Part.BALL_HOLDER)


@dataclass(frozen=True)
class BendFlexibility:
    """Factors on the bend's bending compliance: ``in_plane`` and ``out_of_plane`` [-]."""

    in_plane: float
    out_of_plane: float

    def __post_init__(self) -> None:
        for k in ("in_plane", "out_of_plane"):
            v = getattr(self, k)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"bend flexibility {k} must be a positive number, got {v!r}")


@dataclass(frozen=True)
class FrameCalibration:
    """Calibrated constants of the frame model (dimensionless).

    sleeve_end : ineffective length at each free end of a sleeve / plug, in units of
        sqrt(t_tube t_sleeve) sqrt(E / G / 2.6) (shear-lag scaling)
    bend_scale_in / _out : multiplier on the ASME flexibility factor (restraint by the rings)
    shear / torsion : multipliers on the Timoshenko shear and the torsion flexibility (warping restraint at the
        clamp and sleeves, shear coefficient of an anisotropic tube)
    """

    sleeve_end: float = 0.0
    bend_scale_in: float = 1.0
    bend_scale_out: float = 1.0
    shear: float = 1.0
    torsion: float = 1.0


#: Global default, fitted against the solid model on rods 1#, 4# and two off-grid designs
#: (scripts/calibrate_frame.py); errors on all eleven reference designs in docs/fea.md.
CALIBRATION = FrameCalibration(sleeve_end=0.642, bend_scale_in=0.759, bend_scale_out=0.848)


def asme_bend_flexibility(design: RodDesign, cal: FrameCalibration = CALIBRATION) -> BendFlexibility:
    """ASME B31.3 flexibility factors of the design's bend, with the calibrated end restraint (1 if straight)."""
    if not design.has_bend:
        return BendFlexibility(1.0, 1.0)
    b = design.bend
    t = b.wall_mm
    r_m = (b.outer_diameter_mm - t) / 2.0
    k = 1.65 / (t * b.radius_mm / r_m ** 2)
    return BendFlexibility(max(1.0, cal.bend_scale_in * k), max(1.0, cal.bend_scale_out * k))


def frame_segments(design: RodDesign, cal: FrameCalibration = CALIBRATION) -> list[Segment]:
    """The layout with the sleeves' ineffective end zones split off as tube-only segments."""
    segs = layout(design)
    if cal.sleeve_end <= 0:
        return segs
    out: list[Segment] = []
    for k, seg in enumerate(segs):
        sleeve = [l for l in seg.layers if l.part in _SLEEVES]
        base = tuple(l for l in seg.layers if l.part not in _SLEEVES)
        if seg.kind is not SegmentKind.LINE or not sleeve or not base:
            out.append(seg)
            continue
        # shear lag: the bending load passes from the tube into the sleeve over a length that grows with the
        # walls' thicknesses and with sqrt(E / G) of the tube (long in carbon); torsion transfers at once
        mat = base[0].material
        t_tube = max((l.d_out_mm - l.d_in_mm) / 2.0 for l in base)
        t_sleeve = max((l.d_out_mm - l.d_in_mm) / 2.0 for l in sleeve)
        lag = np.sqrt(mat.E_GPa / mat.G_axial_GPa / 2.6)
        ell = min(cal.sleeve_end * np.sqrt(t_tube * t_sleeve) * lag, 0.45 * seg.length_mm)
        at_clamp = k == 0
        slack = tuple(l.part for l in sleeve)
        L = seg.length_mm
        cuts = [0.0] + ([] if at_clamp else [ell]) + [L - ell, L]
        for a, b in zip(cuts[:-1], cuts[1:]):
            if b - a > 1e-9:
                m = 0.5 * (a + b)
                zone = m > L - ell or (not at_clamp and m < ell)
                out.append(replace(seg, s0_mm=seg.s0_mm + a, length_mm=b - a, start_F=seg.point([a])[0],
                                   slack=slack if zone else (), slack_torsion=()))
    return out


def frame_compliance(design: RodDesign, bend: BendFlexibility | None = None,
                     cal: FrameCalibration = CALIBRATION) -> tuple[np.ndarray, np.ndarray]:
    """Frame-model C_F [mm/N] and C_g [mm/g0] in {T}, shape=(3, 3) each."""
    bend = asme_bend_flexibility(design, cal) if bend is None else bend
    ball = ball_mass_properties(design)
    CF, Cg = unit_load_compliance(frame_segments(design, cal), design.tool_mm, ball.mass_kg, True, True,
                                  ball.com_T_mm + design.tool_mm, (bend.in_plane, bend.out_of_plane),
                                  cal.shear, cal.torsion)
    return 0.5 * (CF + CF.T), Cg


def frame_errors(design: RodDesign, C_F_solid, C_g_solid, cal: FrameCalibration = CALIBRATION) -> np.ndarray:
    """Relative errors of the frame model against a solid result on every significant entry
    (|entry| > 2 % of its matrix's largest) of C_F and C_g."""
    CF, Cg = frame_compliance(design, cal=cal)
    errs = []
    for mine, ref in ((CF, np.asarray(C_F_solid)), (Cg, np.asarray(C_g_solid))):
        big = np.abs(ref) > 0.02 * np.abs(ref).max()
        errs.append(mine[big] / ref[big] - 1.0)
    return np.concatenate(errs)


def calibrate_frame(designs: list[RodDesign], C_F_solid: list, C_g_solid: list) -> FrameCalibration:
    """Fit the sleeve transfer length and the bend factors to solid results (one or more designs).

    Calibrating on one design of a family (same tubes, bend, sleeves) and sweeping its L1 / L2 keeps the
    local physics fixed while the frame moves the lever arms (rods 4# -> 5#, 6#: within 0.21 %).
    """
    from scipy.optimize import least_squares

    def resid(x):
        cal = FrameCalibration(*x)
        return np.concatenate([frame_errors(d, f, g, cal) for d, f, g in zip(designs, C_F_solid, C_g_solid)])
    best = None
    for x0 in ([CALIBRATION.sleeve_end, CALIBRATION.bend_scale_in, CALIBRATION.bend_scale_out],
               [0.3, 0.8, 0.5], [0.1, 1.0, 1.0], [0.5, 0.6, 0.8]):   # kinks (k >= 1, clipped zones): multi-start
        r = least_squares(resid, x0=x0, bounds=([0.0, 0.1, 0.1], [5.0, 3.0, 3.0]), x_scale=[0.1, 0.3, 0.3])
        if best is None or r.cost < best.cost:
            best = r
    return FrameCalibration(*[float(v) for v in best.x])
