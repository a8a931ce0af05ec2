"""Joint fit of the frame model: one solid run of a family member, carried to any L1 x L2.

A design family (one set of tubes, bend, rings, holders and ball; any L1 and L2) differs only in the free
lengths of pipe I and pipe II. Away from the joints a tube is a prismatic beam; everything beam theory
misses (load transfer into sleeves and holders, the ovalising bend and the rings that restrain it, the
clamp, the ball holder) sits within about a diameter of a joint (Saint-Venant). So one solid run is cut into

    clamp block | pipe I span | bend block | pipe II span | ball block

by four sections through the free tubes, ``margin`` tube diameters from their ends. The sections' motions
(:mod:`fea.sections`) under nine load cases (unit tip forces and moments, self-weight along x, y, z of {T})
give every interval's own 6 x 6 flexibility and self-weight motion (:mod:`rodlab.core.chain`):

- a block's *correction* is its solid flexibility minus the frame's, lumped at its distal section;
- a span's is a correction of its section compliances per unit length (1/EA, 1/kGA, 1/GJ, 1/EI; e.g. the
  shear coefficient of a thick orthotropic wall), which any other span length takes over.

A member of the family is its own frame plus these corrections, carried by its own lever arms and weights
(:func:`joint_frame_compliance`). Where a member's free tube is shorter than two margins, the two blocks'
regions overlap: their end effects superpose and the overlap's section correction, counted twice, is taken
off once (a negative span length). Accuracy in docs/fea.md: within 0.35 % on every paper rod and 10 hard
random families (the global frame: up to 5 %), one solid run per family.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.frames import skew as _skew
from rodlab.core.chain import (ChainFlexibility, centreline_points, chain_flexibility, distal_weight_wrench, transport,
                          weight_wrench)
from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.layout import Layer, layout
from rodlab.core.massprops import ball_mass_properties
from rodlab.core.units import G0

from .errors import FeaError
from .frame import CALIBRATION, FrameCalibration, frame_compliance, frame_segments
from .sections import solid_section_motions

__all__ = ["JointFit", "free_spans", "joint_margins", "measure_sections", "fit_joints", "joints_from_motions",
           "JointCalibration", "calibrate_joints", "section_cuts", "frame_chain",
           "joint_frame_compliance", "span_basis", "DEFAULT_MARGIN", "WRENCH_CASES", "GRAVITY_CASES",
           "SECTION_TERMS"]

log = logging.getLogger(__name__)

#: columns of the solid's nine load cases (:func:`fea.solve_compliance` with ``tip_moments``): tip wrench
#: (F_x, F_y, F_z, M_x, M_y, M_z) and self-weight (g_x, g_y, g_z)
WRENCH_CASES = (0, 1, 2, 6, 7, 8)
GRAVITY_CASES = (3, 4, 5)
#: distance of a section from the end of its free tube, in tube outer diameters (chosen on the paper's two
#: families; 0.8-2 diameters keep every tested member within 0.4 %, docs/fea.md)
DEFAULT_MARGIN = 1.0
#: half-length of the stretch of tube whose nodes give a section's motion, in tube outer diameters
SECTION_REACH = 0.5
#: shortest span left between the two sections of a tube on the calibrated design [mm]
MIN_SPAN_MM = 5.0
#: the span section compliances a joint fit corrects (per unit length: 1 / EA, 1 / kGA across and
#: in the bend plane, 1 / GJ, 1 / EI about the bend-plane normal and about the in-plane normal)
SECTION_TERMS = ("axial", "shear_out", "shear_in", "torsion", "bend_in", "bend_out")
_TUBES = (Part.PIPE_I, Part.PIPE_II)


def span_basis(axis: np.ndarray, length_mm: float, weight_N_per_mm: float = 0.0):
    """A straight span of ``length_mm`` along ``axis``, per unit of each section compliance of
    :data:`SECTION_TERMS`: its flexibility at the distal end, shape=(6, 6, 6), and its motion under its own
    weight (``weight_N_per_mm`` per g0 along x, y, z), shape=(6, 6, 3) ({F} axes; see :mod:`rodlab.core.chain`).
    A negative length takes the span off (the overlap of two blocks)."""
    t = np.asarray(axis, dtype=float)
    ey = np.array([0.0, 1.0, 0.0])
    n = np.cross(t, ey)
    St = _skew(t)
    F, H = np.zeros((6, 6, 6)), np.zeros((6, 6, 3))
    L, q = float(length_mm), float(weight_N_per_mm)
    # at x behind the distal end: unit distal wrench -> (f, m) = (F, M + x t x F); own weight (q x g, q x^2/2 t x g)
    for k, (P, moment) in enumerate(((np.outer(t, t), False), (np.outer(ey, ey), False), (np.outer(n, n), False),
                                     (np.outer(t, t), True), (np.outer(ey, ey), True), (np.outer(n, n), True))):
        if moment:
            F[k, :3, :3] = St.T @ P @ St * L ** 3 / 3.0
            F[k, :3, 3:] = St.T @ P * L ** 2 / 2.0
            F[k, 3:, :3] = P @ St * L ** 2 / 2.0
            F[k, 3:, 3:] = P * L
            H[k, :3] = St.T @ P @ St * q * L ** 4 / 8.0
            H[k, 3:] = P @ St * q * L ** 3 / 6.0
        else:
            F[k, :3, :3] = P * L
            H[k, :3] = P * q * L ** 2 / 2.0
    return F, H


def free_spans(design: RodDesign) -> dict[Part, tuple[float, float]]:
    """Arc lengths from the flange [mm] where pipe I and pipe II are bare tube: ``{part: (start, end)}`` (an
    empty interval where a tube has no free length: its sleeves meet)."""
    d = design
    segs = layout(d)
    total = segs[-1].s0_mm + segs[-1].length_mm
    a1 = d.pipe_holder.length_mm if d.pipe_holder.present else 0.0
    tail = d.plug_mm + d.ball_holder.length_mm + d.ball.radius_mm - d.seat_offset_mm if d.ball_holder.present else 0.0
    b2 = total - tail
    return {Part.PIPE_I: (a1, a1 + d.pipe_I_free_mm()), Part.PIPE_II: (b2 - d.pipe_II_free_mm(), b2)}


def joint_margins(design: RodDesign, margin: float = DEFAULT_MARGIN) -> dict[Part, float]:
    """Section distance [mm] from the ends of each free tube: ``margin`` tube diameters, shortened to leave
    ``MIN_SPAN_MM`` between the two sections of a short tube (a warning: the end effects have not decayed
    there; calibrate on a member with longer tubes, :func:`fea.family.joint_fit_member`)."""
    if not (isinstance(margin, (int, float)) and np.isfinite(margin) and margin > 0):
        raise FeaError(f"margin must be a positive number of tube diameters, got {margin!r}", key="margin")
    spans = free_spans(design)
    out = {}
    for part, tube in zip(_TUBES, (design.pipe_I, design.pipe_II)):
        a, b = spans.get(part, (0.0, 0.0))
        m = margin * tube.outer_diameter_mm
        out[part] = min(m, 0.5 * (b - a - MIN_SPAN_MM))
        if out[part] <= 0:
            raise FeaError(f"{design.name}: {part.value} has {b - a:.1f} mm of free tube, too little for two "
                           f"sections {MIN_SPAN_MM:g} mm apart: calibrate on a family member with longer tubes",
                           key=part.value)
        if out[part] < m:
            log.warning("%s: %s's free tube (%.1f mm) leaves its sections only %.1f mm from the joints (asked "
                        "%.1f mm): the family's other members will be less accurate", design.name, part.value,
                        b - a, out[part], m)
    return out


def section_cuts(design: RodDesign, margins: dict[Part, float]) -> list[tuple[Part, float]]:
    """The four sections ``(tube, arc length [mm])``: ``margins[tube]`` inside each end of its free tube (for a
    member with a short tube the second may come before the first)."""
    spans = free_spans(design)
    return [(p, s) for p in _TUBES for s in (spans[p][0] + margins[p], spans[p][1] - margins[p])]


def _span_geometry(design: RodDesign, cuts) -> list[tuple[np.ndarray, float, float]]:
    """(axis, signed length [mm], weight per g0 [N/mm]) of pipe I's and pipe II's span between its sections."""
    out = []
    for k, tube, part in ((0, design.pipe_I, Part.PIPE_I), (2, design.pipe_II, Part.PIPE_II)):
        axis = np.array([0.0, 0.0, 1.0]) if part is Part.PIPE_I else design.pipe_II_direction
        layer = Layer(part, tube.material, tube.outer_diameter_mm, tube.inner_diameter_mm)
        out.append((axis, cuts[k + 1][1] - cuts[k][1], layer.mass_per_mm * G0))
    return out


@dataclass(frozen=True, eq=False)
class JointFit:
    """Corrections of the frame's intervals measured on one solid run of a family member (module doc).

    base : the solid-run design; margins_mm : section distance from the ends of pipe I's and pipe II's free
        tube [mm]; D : correction of each interval's flexibility at its distal point, shape=(5, 6, 6), {F}
        axes [mm/N, mm/(N mm); rad/N, rad/(N mm)] (clamp block, pipe I span, bend block, pipe II span, ball
        block; the spans' entries are zero: ``section`` gives them); dH : correction of each interval's
        self-weight motion, shape=(5, 6, 3) [mm/g0, rad/g0]; section : corrections of the spans' section
        compliances (:data:`SECTION_TERMS`), shape=(2, 6) (pipe I, pipe II) [1/N x 3, 1/(N mm^2) x 3];
    calibration : the frame constants underneath; asymmetry : largest Maxwell-Betti defect of the measured
        block flexibilities [-]; span_residual : what the section corrections leave of the spans' measured
        difference, largest entry relative to sqrt(F_aa F_bb) [-].
    """

    base: RodDesign
    margins_mm: tuple[float, float]
    D: np.ndarray
    dH: np.ndarray
    section: np.ndarray
    calibration: FrameCalibration = CALIBRATION
    asymmetry: float = 0.0
    span_residual: float = 0.0

    def __post_init__(self) -> None:
        if self.D.shape != (5, 6, 6) or self.dH.shape != (5, 6, 3) or self.section.shape != (2, 6):
            raise ValueError(f"JointFit needs D shape (5, 6, 6), dH (5, 6, 3) and section (2, 6), got "
                             f"{self.D.shape}, {self.dH.shape}, {self.section.shape}")
        if not all(np.all(np.isfinite(a)) for a in (self.D, self.dH, self.section, self.margins_mm)):
            raise ValueError("JointFit corrections and margins must be finite")

    @property
    def margins(self) -> dict[Part, float]:
        return dict(zip(_TUBES, self.margins_mm))

    def check_member(self, design: RodDesign) -> None:
        """Raise :class:`FeaError` unless ``design`` differs from the base in L1, L2 (and name) only."""
        other = replace(design, L1_mm=self.base.L1_mm, L2_mm=self.base.L2_mm, name=self.base.name)
        if other != self.base:
            mine, base = other.summary(), self.base.summary()
            diff = [k for k in base if mine.get(k) != base[k]]
            raise FeaError(f"{design.name} is not a member of {self.base.name}'s family (it differs in "
                           f"{', '.join(diff) or 'its parts'}, not only in L1 / L2): the joint calibration does "
                           f"not apply", key="design")

    def __repr__(self) -> str:     # the sweep's cache key: every number that changes a result; it keeps the
        # class's old name, so the caches of earlier sweeps stay valid
        return (f"JointCalibration(base={self.base.summary()!r}, margins_mm={self.margins_mm!r}, "
                f"D={self.D.tolist()!r}, dH={self.dH.tolist()!r}, section={self.section.tolist()!r}, "
                f"calibration={self.calibration!r})")


def frame_chain(design: RodDesign, cuts, cal: FrameCalibration):
    """The frame model's cantilever chain of ``design`` (calibration ``cal``) cut at the arc lengths of ``cuts``
    (:func:`section_cuts`), the ball's mass at the tip: the flexibilities the joint fit compares with the solid's
    section motions."""
    ball = ball_mass_properties(design)
    return chain_flexibility(frame_segments(design, cal), [s for _, s in cuts], design.tool_mm, ball.mass_kg,
                             ball.com_T_mm + design.tool_mm, True, True, cal.shear, cal.torsion)


def joints_from_motions(base: RodDesign, section_motion: np.ndarray, tip_motion: np.ndarray,
                        margins: dict[Part, float], cal: FrameCalibration = CALIBRATION) -> JointFit:
    """The joint fit from the motions of ``base``'s four sections (:func:`section_cuts` of ``margins``),
    shape=(4, 6, 9), and of the tip, shape=(6, 9) [mm, rad; {F} axes], under the nine load cases
    (:data:`WRENCH_CASES`, :data:`GRAVITY_CASES`). Pure: motions in, corrections out."""
    cuts = section_cuts(base, margins)
    if any(b - a < MIN_SPAN_MM - 1e-9 for (_, a), (_, b) in (cuts[:2], cuts[2:])):
        raise FeaError(f"{base.name}: the sections of a calibrated design must leave {MIN_SPAN_MM:g} mm of span "
                       f"(use joint_margins)", key="margins")
    frame = frame_chain(base, cuts, cal)
    motion = np.concatenate([np.zeros((1, 6, 9)), section_motion, tip_motion[None]], axis=0)
    pts = np.vstack([np.zeros((1, 3)), frame.points_F])
    # each interval's motion relative to its proximal section (rigid transport of that section's motion)
    rel = motion[1:] - np.einsum("nji,njc->nic", transport(pts[1:] - pts[:-1]), motion[:-1])
    F = np.einsum("nac,ncb->nab", rel[:, :, list(WRENCH_CASES)], np.linalg.inv(frame.adjoint()))
    Ft = np.transpose(F, (0, 2, 1))
    asym = np.abs(F - Ft).max(axis=(1, 2)) / np.abs(F).max(axis=(1, 2))
    F = 0.5 * (F + Ft)
    H = rel[:, :, list(GRAVITY_CASES)] - np.einsum("nab,nbj->naj", F, frame.G)
    D, dH = F - frame.F, H - frame.H
    # the spans: the section compliances (per unit length) that make the frame's span the measured one
    section, resid = np.zeros((2, len(SECTION_TERMS))), 0.0
    for j, (i, geo) in enumerate(zip((1, 3), _span_geometry(base, cuts))):
        B, _ = span_basis(*geo)
        scale = np.sqrt(np.abs(np.einsum("ii->i", frame.F[i])))
        scale = np.outer(scale, scale)
        A = (B / scale).reshape(len(SECTION_TERMS), -1).T
        section[j] = np.linalg.lstsq(A, (D[i] / scale).ravel(), rcond=None)[0]
        resid = max(resid, float(np.abs(A @ section[j] - (D[i] / scale).ravel()).max()))
    D[[1, 3]], dH[[1, 3]] = 0.0, 0.0
    jc = JointFit(base, (margins[Part.PIPE_I], margins[Part.PIPE_II]), D, dH, section, cal,
                          float(asym[[0, 2, 4]].max()), resid)
    log.info("joint calibration on %s: sections %.1f / %.1f mm from the tube ends, block asymmetry %.1e, "
             "span fit residual %.2f %%", base.name, *jc.margins_mm, jc.asymmetry, 100 * resid)
    return jc


def measure_sections(base: RodDesign, solid, margin: float = DEFAULT_MARGIN):
    """What the joint fit measures on ``base``'s solid run ``solid`` (a :class:`fea.SolidResult`
    solved with ``tip_moments=True, keep_displacements=True``): the motions of its four sections, shape=(4, 6,
    9), and of the tip, shape=(6, 9) [mm, rad; {F} axes], and the margins [mm] (:func:`joint_margins` of
    ``margin`` tube diameters)."""

    U, rm = solid.displacements, solid.rod_mesh
    if U is None or U.shape[1] != 9 or solid.ball_motion is None or rm is None:
        raise FeaError("the joint calibration needs the solid run's displacements of all nine load cases: "
                       "solve with tip_moments=True, keep_displacements=True", key="solid")
    margins = joint_margins(base, margin)
    cuts = section_cuts(base, margins)
    centres, axes = centreline_points(layout(base), [s for _, s in cuts])
    reach = {p: min(SECTION_REACH * t.outer_diameter_mm, 0.9 * margins[p])
             for p, t in zip(_TUBES, (base.pipe_I, base.pipe_II))}
    return solid_section_motions(base, rm, U, cuts, centres, axes, reach), solid.ball_motion, margins


def fit_joints(base: RodDesign, solid, margin: float = DEFAULT_MARGIN,
               cal: FrameCalibration = CALIBRATION) -> JointFit:
    """The joint fit of ``base``'s family from its solid run ``solid`` (:func:`measure_sections`,
    :func:`joints_from_motions`); ``margin`` in tube diameters (:func:`joint_margins`)."""
    return joints_from_motions(base, *measure_sections(base, solid, margin), cal)


def joint_frame_compliance(design: RodDesign, jc: JointFit) -> tuple[np.ndarray, np.ndarray]:
    """C_F [mm/N] and C_g [mm/g0] in {T}, shape=(3, 3) each, of a member of ``jc``'s family: the frame of
    ``design`` plus the base's block corrections lumped at their distal sections and the spans' section
    corrections over the member's span lengths, all carried by the member's own lever arms and weights."""
    jc.check_member(design)
    CF, Cg = frame_compliance(design, cal=jc.calibration)
    segs = layout(design)
    cuts = section_cuts(design, jc.margins)
    s = np.array([c for _, c in cuts])
    total = segs[-1].s0_mm + segs[-1].length_mm
    if np.any(s <= 0) or np.any(s >= total):
        raise FeaError(f"{design.name}: the joint calibration's sections ({jc.margins_mm[0]:.1f} / "
                       f"{jc.margins_mm[1]:.1f} mm from the free tubes' ends) fall outside the rod", key="design")
    ball = ball_mass_properties(design)
    com = ball.com_T_mm + design.tool_mm
    pts = np.vstack([centreline_points(segs, s)[0], design.tool_mm[None, :]])   # distal point of each interval
    G = np.concatenate([distal_weight_wrench(segs, s, ball.mass_kg, com),
                        weight_wrench(ball.mass_kg, ball.mass_kg * com, design.tool_mm)])
    D, dH = jc.D.copy(), jc.dH.copy()
    for j, (i, geo) in enumerate(zip((1, 3), _span_geometry(design, cuts))):
        B, Bh = span_basis(*geo)
        D[i], dH[i] = np.tensordot(jc.section[j], B, 1), np.tensordot(jc.section[j], Bh, 1)
    C6, C6g = ChainFlexibility(pts, D, G, dH, design.tool_mm).tip_compliance()
    return CF + 0.5 * (C6[:3, :3] + C6[:3, :3].T), Cg + C6g[:3]


#: the names this concept had before "calibration" was kept for the robot's (kept for callers of rodlab.fea)
JointCalibration = JointFit
calibrate_joints = fit_joints
