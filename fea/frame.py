"""Fast beam-frame model of a rod (for design sweeps), calibrated against the solid model.

The rod is a tree of Timoshenko beams clamped at the flange: tubes with their (transversely isotropic:
E axial for bending and tension, G axial for torsion and shear) sections, rings, holders and the ball
holder's plug as composite sections, the bend as a curved beam whose bending compliance is scaled by
pipe-bend flexibility factors (ovalisation), the ball as the tip's rigid mass. Because the frame is
statically determinate its tip compliance follows exactly from the unit-load method along the centreline
(:func:`rodlab.core.calc.unit_load_compliance`): no element discretisation error, a few ms per design.

Three effects that beam theory misses are modelled from their mechanics and their constants calibrated once
against the solid model (``scripts/calibrate_frame.py``, data in ``fea/data/solid_reference.json``):

- load transfer between a tube and a bonded sleeve or plug (shear lag): the axial stresses pass from one
  wall into the other through the walls' through-thickness shear, decaying as ``exp(-lambda x)`` with
  ``lambda^2 = (1 / (t1 / 3 G1 + t2 / 3 G2)) (1 / E1 t1 + 1 / E2 t2)`` (E axial, G the transverse shear
  modulus of each wall: G13 for bending and tension, G23 for torsion). The frame replaces the decay by
  a zone ``c / lambda`` at each free end of the composite in which the wall that ends there carries mass
  but no stiffness (the sleeve where the sleeve ends, the tube where the tube ends; none where a
  sleeve continues into the next one or at the clamp); exact for ``c = 1`` in 1-D shear-lag theory. At the
  clamped pipe holder a thin, orthotropic tube needs a longer zone than shear lag gives (measured on
  straight holder-only solid runs): ``c`` grows as ``(E_axial / E_transverse)^a (r_m / t)^b`` of the tube;
- the same for torsion (G axial in place of E, G23 through the thickness), its own constant;
- pipe-bend flexibility (ovalisation): ``k(h)`` (``h = t R / r_m^2``; von Karman / ASME B31.3
  :func:`bend_flexibility_factor`), scaled, over the
  middle of the arc only: the rings and tubes at the tangent points hold the section round over a zone of
  ``bend_end r_m rho / (rho + bend_restraint)`` at each end, with ``rho`` the hoop-bending stiffness of
  ring plus tube over that of the bend wall (``(E_ring t_ring^3 + E_t,tube t_tube^3) / E_t,bend t_bend^3``):
  no ring holds the end over a short zone, a ring far stiffer than the bend wall no better than a rigid one.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from difflib import get_close_matches

import numpy as np

from rodlab.core.calc import unit_load_compliance
from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.joint_springs import declared_joint_compliance
from rodlab.core.layout import Segment, SegmentKind, layout
from rodlab.core.massprops import ball_mass_properties
from rodlab.core.materials import Material

from .elasticity import NU23_DEFAULT

__all__ = ["BendFlexibility", "FrameCalibration", "CALIBRATION", "CALIBRATED_RANGE", "FAMILY_FIT", "FRAME_REVISION",
           "asme_bend_flexibility", "bend_flexibility_factor", "shear_lag_mm", "frame_compliance", "frame_segments",
           "calibrate_frame", "frame_errors", "frame_range_notes"]

#: revision of the frame model's physics: part of the sweep cache key, so a changed model never reuses old results
FRAME_REVISION = 3

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


_CAL_FIELDS = ("sleeve_end", "bend_scale_in", "bend_scale_out", "shear", "torsion", "holder_end", "torsion_end",
               "bend_end", "bend_restraint", "holder_orthotropy", "holder_slenderness")
#: constants that are exponents (any sign); the others are lengths or factors (>= 0, or > 0)
_EXPONENTS = ("holder_orthotropy", "holder_slenderness")


@dataclass(frozen=True)
class FrameCalibration:
    """Calibrated constants of the frame model (dimensionless).

    sleeve_end : ineffective zone at each free end of a ring or plug, in units of the shear-lag length 1 / lambda
    holder_end : the same at the free end of the pipe holder (thick, clamped flange adapter), times
        ``(E_axial / E_transverse)^holder_orthotropy (r_m / t)^holder_slenderness`` of the tube
    holder_orthotropy / holder_slenderness : exponents of that correction (0 = plain shear lag)
    torsion_end : the same for torsion, in units of the torsional shear-lag length
    bend_scale_in / _out : multipliers on the pipe-bend factor k(h) in the arc's middle (in-/out-of-plane)
    bend_end : zone at each end of the arc held round by ring and tube, in units of
        ``r_m rho / (rho + bend_restraint)``: it grows with the restraint ratio rho (hoop stiffness of ring +
        tube over the bend wall's) and saturates (a ring far stiffer than the bend wall holds the end no
        rounder than a rigid one)
    bend_restraint : the restraint ratio at which the zone reaches half its saturated length
    shear / torsion : multipliers on the Timoshenko shear and the torsion flexibility (1 = theory)
    """

    sleeve_end: float = 0.0
    bend_scale_in: float = 1.0
    bend_scale_out: float = 1.0
    shear: float = 1.0
    torsion: float = 1.0
    holder_end: float = 0.0
    torsion_end: float = 0.0
    bend_end: float = 0.0
    bend_restraint: float = 0.0
    holder_orthotropy: float = 0.0
    holder_slenderness: float = 0.0

    def __post_init__(self) -> None:
        for k in _CAL_FIELDS:
            v = getattr(self, k)
            positive = k in ("bend_scale_in", "bend_scale_out", "shear", "torsion")
            sign_ok = v > 0 if positive else (True if k in _EXPONENTS else v >= 0)
            if not (isinstance(v, (int, float)) and np.isfinite(v) and sign_ok):
                kind = "positive" if positive else ("finite" if k in _EXPONENTS else "non-negative")
                raise ValueError(f"frame calibration {k} must be a {kind} number, got {v!r}")


#: Global default, fitted against the solid model on 18 designs (the six paper rods, off-grid designs of
#: other materials, sections, bends and parts) and 39 part probes (scripts/calibrate_frame.py,
#: the probes of fea/data/reference_designs.json); errors in docs/fea.md.
CALIBRATION = FrameCalibration(sleeve_end=1.422, bend_scale_in=0.907, bend_scale_out=0.866, holder_end=0.602,
                               torsion_end=0.497, bend_end=1.516, bend_restraint=2.121, holder_orthotropy=0.061,
                               holder_slenderness=0.262)


def _g23(m: Material) -> float:
    """Shear modulus across the tube axis [GPa] (transverse plane of a transversely isotropic wall)."""
    return m.G_axial_GPa if m.is_isotropic else m.E_t_GPa / (2.0 * (1.0 + NU23_DEFAULT))


def shear_lag_mm(tube: Material, t_tube: float, sleeve: Material, t_sleeve: float,
                 torsion: bool = False) -> float:
    """Shear-lag length 1 / lambda [mm] of load transfer between two bonded concentric walls (see module doc)."""
    if torsion:
        E1, E2, G1, G2 = tube.G_axial_GPa, sleeve.G_axial_GPa, _g23(tube), _g23(sleeve)
    else:
        E1, E2, G1, G2 = tube.E_GPa, sleeve.E_GPa, tube.G_axial_GPa, sleeve.G_axial_GPa
    lam2 = (1.0 / E1 / t_tube + 1.0 / E2 / t_sleeve) / (t_tube / (3.0 * G1) + t_sleeve / (3.0 * G2))
    return float(1.0 / np.sqrt(lam2))


def bend_flexibility_factor(h: float) -> float:
    """In-plane flexibility factor k [-] of a long, unrestrained pipe bend of characteristic h = t R / r_m^2.

    The larger of von Karman's second approximation ``(105 + 4136 h^2 + 4800 h^4) / (3 + 536 h^2 + 4800 h^4)``
    (accurate for h >~ 0.3, where ASME's ``1.65 / h`` falls to 1 too early: h = 1.2 gives 1.49, ASME 1.375)
    and ASME B31.3 ``1.65 / h`` (its small-h asymptote); at least 1.
    """
    h2 = h * h
    karman = (105.0 + 4136.0 * h2 + 4800.0 * h2 * h2) / (3.0 + 536.0 * h2 + 4800.0 * h2 * h2)
    return max(1.0, 1.65 / h, karman)


def _bend_rm_h(design: RodDesign) -> tuple[float, float]:
    """The bend's mean wall radius r_m [mm] and pipe-bend characteristic h = t R / r_m^2 [-]."""
    b = design.bend
    r_m = (b.outer_diameter_mm - b.wall_mm) / 2.0
    return r_m, b.wall_mm * b.radius_mm / r_m ** 2


def asme_bend_flexibility(design: RodDesign, cal: FrameCalibration = CALIBRATION) -> BendFlexibility:
    """Pipe-bend flexibility factors of the design's bend (:func:`bend_flexibility_factor`) scaled by the
    calibration: the factors of the arc between its restrained ends (1 if straight; ``FrameCalibration()``
    gives the plain factor)."""
    if not design.has_bend:
        return BendFlexibility(1.0, 1.0)
    k = bend_flexibility_factor(_bend_rm_h(design)[1])
    return BendFlexibility(max(1.0, cal.bend_scale_in * k), max(1.0, cal.bend_scale_out * k))


def _kind(segs: list[Segment], j: int) -> str:
    """What a neighbour segment holds: 'none' (beyond the clamp), 'both', 'base' (tube only), 'sleeve'."""
    if j < 0 or j >= len(segs):
        return "none"
    has_sleeve = any(l.part in _SLEEVES for l in segs[j].layers)
    has_base = any(l.part not in _SLEEVES for l in segs[j].layers)
    return "both" if has_sleeve and has_base else ("base" if has_base else "sleeve")


def _thickness(layers) -> float:
    return max((l.d_out_mm - l.d_in_mm) / 2.0 for l in layers)


def _split(seg: Segment, cuts, piece) -> list[Segment]:
    """``seg`` cut at the local arc lengths ``cuts``; ``piece(a, b)`` gives each piece's replaced fields."""
    out = []
    cuts = sorted(set([0.0, seg.length_mm] + [c for c in cuts if 0.0 < c < seg.length_mm]))
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a > 1e-9:
            out.append(replace(seg, s0_mm=seg.s0_mm + a, length_mm=b - a, start_F=seg.point([a])[0],
                               direction=seg.tangent([a])[0], **piece(a, b)))
    return out


def _sleeve_pieces(segs: list[Segment], k: int, cal: FrameCalibration) -> list[Segment]:
    seg = segs[k]
    sleeve = [l for l in seg.layers if l.part in _SLEEVES]
    base = [l for l in seg.layers if l.part not in _SLEEVES]
    holder = any(l.part is Part.PIPE_HOLDER for l in sleeve)
    c = cal.holder_end if holder else cal.sleeve_end
    if not sleeve or not base or (c <= 0 and cal.torsion_end <= 0):
        return [seg]
    t1, t2 = _thickness(base), _thickness(sleeve)
    m1 = base[0].material
    m2 = max(sleeve, key=lambda l: l.d_out_mm - l.d_in_mm).material
    if holder:      # a thin, orthotropic tube leaves the clamped holder over a longer zone than shear lag says
        r_m = (base[0].d_out_mm - t1) / 2.0
        c *= (m1.E_GPa / m1.E_t_GPa) ** cal.holder_orthotropy * (r_m / t1) ** cal.holder_slenderness
    L = seg.length_mm
    ell = min(c * shear_lag_mm(m1, t1, m2, t2), 0.45 * L)
    ell_t = min(cal.torsion_end * shear_lag_mm(m1, t1, m2, t2, torsion=True), 0.45 * L)
    # the wall that ends at a free end of the composite is ineffective there: the sleeve where the next piece
    # is bare tube or the bend, the tube where it ends inside the sleeve (the plug's stud); none where the
    # composite continues or at the clamp
    ends = {"base": tuple(l.part for l in sleeve), "sleeve": tuple(l.part for l in base)}
    s0, s1 = ends.get(_kind(segs, k - 1)), ends.get(_kind(segs, k + 1))

    def piece(a, b):
        m = 0.5 * (a + b)

        def slack(length):
            return s1 if (s1 and m > L - length) else (s0 if (s0 and m < length) else ())
        return {"slack": slack(ell), "slack_torsion": slack(ell_t)}
    cuts = ([ell, ell_t] if s0 else []) + ([L - ell, L - ell_t] if s1 else [])
    return _split(seg, cuts, piece) if cuts else [seg]


def _restraint(design: RodDesign, tube) -> float:
    """Hoop-bending stiffness of ring + tube over the bend wall's at one end of the bend [-]."""
    b, r = design.bend, design.rings
    ring = r.material.E_t_GPa * ((r.outer_diameter_mm - tube.outer_diameter_mm) / 2.0) ** 3 if r.present else 0.0
    return (ring + tube.material.E_t_GPa * tube.wall_mm ** 3) / (b.material.E_t_GPa * b.wall_mm ** 3)


def _held(rho: float, cal: FrameCalibration) -> float:
    """Saturating restraint ``rho / (rho + bend_restraint)`` [-] (1 for ``bend_restraint = 0``)."""
    return rho / (rho + cal.bend_restraint) if rho > 0 else 0.0


def _bend_pieces(design: RodDesign, seg: Segment, cal: FrameCalibration) -> list[Segment]:
    k = asme_bend_flexibility(design, cal)                  # the scaled factors of the arc's middle
    r_m = _bend_rm_h(design)[0]
    L = seg.length_mm
    e0, e1 = (min(cal.bend_end * r_m * _held(_restraint(design, tube), cal), 0.5 * L)
              for tube in (design.pipe_I, design.pipe_II))

    def piece(a, c):
        middle = e0 < 0.5 * (a + c) < L - e1
        return {"bend_flex": (k.in_plane, k.out_of_plane) if middle else (1.0, 1.0)}
    return _split(seg, [e0, L - e1], piece)


def frame_segments(design: RodDesign, cal: FrameCalibration = CALIBRATION) -> list[Segment]:
    """The layout with the sleeves' load-transfer zones and the bend's restrained ends split off, each piece
    carrying its ineffective parts (``slack``, ``slack_torsion``) and arc flexibility (``bend_flex``)."""
    segs = layout(design)
    out: list[Segment] = []
    for k, seg in enumerate(segs):
        if seg.kind is SegmentKind.ARC:
            out.extend(_bend_pieces(design, seg, cal))
        else:
            out.extend(_sleeve_pieces(segs, k, cal))
    return out


#: the range of the designs and part probes the default calibration was fitted on (scripts/calibrate_frame.py),
#: widened to the thick 40 x 5 mm carbon tubes of the built-in rods 1#-3# it was verified on (r_m / t 3.5, h 1.061:
#: 0.3-0.8 % of the solid's largest entry, tests/test_frame_vs_solid.py; 1.4 % at the L1 / L2 corners,
#: docs/benchmarks/frame_range.md) with the margin of their wall tolerance (5 %: r_m / t 3.3-3.7, h 1.00-1.12):
#: tube r_m / t, bend r_m / t and bend h = t R / r_m^2; outside it the error can exceed the documented bound
#: The curved bends among them are all of isotropic metals (steel, aluminium, titanium: E / G = 2 (1 + nu),
#: E / E_transverse = 1); a carbon bend (a new user's UD-carbon rod, E / G 24, E / E_T 13: c33 42 % too small)
#: ovalises and shears far more than the isotropic bend flexibility says: the bend material's isotropy is checked,
#: E / G against 2 (1 + nu) (``bend_shear_isotropy``, any isotropic material is 1) and E / E_T.
CALIBRATED_RANGE = {"tube_slenderness": (3.3, 10.5), "bend_slenderness": (3.3, 7.9), "bend_h": (0.43, 1.12),
                    "bend_shear_isotropy": (0.95, 1.05), "bend_E_over_E_transverse": (0.95, 1.05)}


def frame_range_notes(design: RodDesign) -> list[str]:
    """Where ``design`` lies outside :data:`CALIBRATED_RANGE` of the default calibration (empty if inside):
    the frame still evaluates, but validate such a design with ``--model solid`` (docs/fea.md: a 1 mm
    titanium bend, r_m / t = 9.5, h = 0.35, was 2.8 % off)."""
    notes = []

    def check(key, value, what):
        lo, hi = CALIBRATED_RANGE[key]
        if not lo <= value <= hi:
            shown = f"{value:.2f}" if f"{value:.2f}" not in (f"{lo:.2f}", f"{hi:.2f}") else f"{value:.4f}"
            notes.append(f"{what} = {shown} is outside the frame's calibrated range {lo:g}-{hi:g}")
    for label, t in (("pipe_I", design.pipe_I), ("pipe_II", design.pipe_II)):
        check("tube_slenderness", (t.outer_diameter_mm - t.wall_mm) / 2.0 / t.wall_mm, f"{label} r_m / t")
    if design.has_bend:
        r_m, h = _bend_rm_h(design)
        check("bend_slenderness", r_m / design.bend.wall_mm, "bend r_m / t")
        check("bend_h", h, "bend h = t R / r_m^2")
        m = design.material_of(Part.BEND)
        G = m.G_GPa or m.E_GPa / (2.0 * (1.0 + m.nu))
        check("bend_shear_isotropy", m.E_GPa / G / (2.0 * (1.0 + m.nu)),
              f"bend material {m.name}: E / G over its isotropic value 2 (1 + nu)")
        check("bend_E_over_E_transverse", m.E_GPa / (m.E_transverse_GPa or m.E_GPa), f"bend material {m.name}: E / E_T")
    return notes


def frame_compliance(design: RodDesign, bend: BendFlexibility | None = None,
                     cal: FrameCalibration = CALIBRATION) -> tuple[np.ndarray, np.ndarray]:
    """Frame-model C_F [mm/N] and C_g [mm/g0] in {T}, shape=(3, 3) each.

    ``bend``: factors for the whole arc instead of the calibrated ones (restrained ends and middle).
    """
    segs = frame_segments(design, cal)
    if bend is not None:
        segs = [replace(s, bend_flex=(bend.in_plane, bend.out_of_plane)) if s.kind is SegmentKind.ARC else s
                for s in segs]
    ball = ball_mass_properties(design)
    CF, Cg = unit_load_compliance(segs, design.tool_mm, ball.mass_kg, True, True,
                                  ball.com_T_mm + design.tool_mm, (1.0, 1.0), cal.shear, cal.torsion)
    dF, dg = declared_joint_compliance(design)        # the design's declared compliant joints, in series
    return 0.5 * (CF + CF.T) + dF, Cg + dg


def frame_errors(design: RodDesign, C_F_solid, C_g_solid, cal: FrameCalibration = CALIBRATION) -> np.ndarray:
    """Relative errors of the frame model against a solid result on every significant entry
    (|entry| > 2 % of its matrix's largest) of C_F and C_g."""
    CF, Cg = frame_compliance(design, cal=cal)
    errs = []
    for mine, ref in ((CF, np.asarray(C_F_solid)), (Cg, np.asarray(C_g_solid))):
        big = np.abs(ref) > 0.02 * np.abs(ref).max()
        errs.append(mine[big] / ref[big] - 1.0)
    return np.concatenate(errs)


#: the constants a per-family calibration refits (the others keep their global values)
FAMILY_FIT = ("bend_scale_in", "bend_scale_out")


def calibrate_frame(designs: list[RodDesign], C_F_solid: list, C_g_solid: list,
                    names: tuple[str, ...] = FAMILY_FIT, start: FrameCalibration = CALIBRATION) -> FrameCalibration:
    """Fit the frame constants ``names`` to solid results (one or more designs), the others as in ``start``.

    Calibrating on one design of a family (same tubes, bend, sleeves) and sweeping its L1 / L2 keeps the
    local physics fixed while the frame moves the lever arms (docs/fea.md: rods 4# -> 5#, 6#).
    """
    from scipy.optimize import least_squares
    for n in names:
        if n not in _CAL_FIELDS:
            near = get_close_matches(n, _CAL_FIELDS, n=1)
            raise ValueError(f"unknown frame constant {n!r}; expected one of {', '.join(_CAL_FIELDS)}"
                             + (f". Did you mean {near[0]!r}?" if near else ""))
    if not (len(designs) == len(C_F_solid) == len(C_g_solid) and designs):
        raise ValueError(f"need one solid C_F and C_g per design, got {len(designs)} designs, {len(C_F_solid)} C_F, "
                         f"{len(C_g_solid)} C_g")

    def cal_of(x):
        return replace(start, **dict(zip(names, (float(v) for v in x))))

    def resid(x):
        cal = cal_of(x)
        return np.concatenate([frame_errors(d, f, g, cal) for d, f, g in zip(designs, C_F_solid, C_g_solid)])
    x0 = np.array([getattr(start, n) for n in names], dtype=float)
    hi = np.array([3.0 if n.startswith("bend_scale") else (2.0 if n in _EXPONENTS else 10.0) for n in names])
    lo = np.array([0.1 if n.startswith("bend_scale") else (-2.0 if n in _EXPONENTS else 0.0) for n in names])
    best = None
    for f in (1.0, 0.6, 1.5):         # kinks (k >= 1, clipped zones): multi-start
        r = least_squares(resid, x0=np.clip(x0 * f, lo, hi), bounds=(lo, hi), x_scale=np.maximum(0.1 * x0, 0.05))
        if best is None or r.cost < best.cost:
            best = r
    return cal_of(best.x)
