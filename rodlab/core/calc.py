"""Closed-form rod compliance ("Calc", paper Eqs. 15-18) by the unit-load method.

The rod is a statically determinate cantilever clamped at the flange face, so the ball-centre
displacement follows exactly from the internal forces of the load and of a unit load
(Castigliano / virtual work) integrated along the centreline:

    C_ij = integral( m_i^T K_m^-1 m_j + f_i^T K_f^-1 f_j ) ds,

with ``m_i(s) = (p - r(s)) x e_i`` the moment of a unit tip force, ``K_m^-1 = t t^T / GJ +
(I - t t^T) / EI`` and ``K_f^-1 = t t^T / EA + (I - t t^T) / kGA`` along the local tangent ``t``.
For gravity the moment at ``s`` is that of all the mass distal to ``s`` (tubes, rings, bend,
holders and the ball as a point mass at the tip). Each segment carries its composite section
(tube plus sleeve), so the model covers any gamma, the bend arc and every part; with
``pipes_only=True`` it reduces to the paper's idealisation, and :func:`paper_compliance`
evaluates Eqs. 15 and 17 literally (gamma = 90 only).

Frames: forces and gravity in {T}; displacements of the ball centre in {T} [mm]. C_F [mm/N],
C_g [mm per g0] (gravity of magnitude g0 = 9.80665 m/s^2 along the given {T} direction).
"""
from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import numpy as np

from .compliance import RodCompliance
from .design import RodDesign
from .enums import BendModel, Method, Part
from .frames import skew as _skew
from .errors import DesignError, expect_type
from .joint_springs import declared_joint_compliance
from .layout import Layer, Segment, SegmentKind, layout
from .massprops import ball_mass_properties, gauss_legendre
from .units import G0

__all__ = ["BendModel", "calc_compliance", "calc_rod_compliance", "paper_compliance", "pipes_only_segments",
           "unit_load_compliance"]


def pipes_only_segments(design: RodDesign) -> list[Segment]:
    """The paper's idealisation: pipe I (length L1) and pipe II (length L2) meeting at a sharp corner."""
    d = design
    t1 = Layer(Part.PIPE_I, d.pipe_I.material, d.pipe_I.outer_diameter_mm, d.pipe_I.inner_diameter_mm)
    t2 = Layer(Part.PIPE_II, d.pipe_II.material, d.pipe_II.outer_diameter_mm, d.pipe_II.inner_diameter_mm)
    ez = np.array([0.0, 0.0, 1.0])
    return [Segment(SegmentKind.LINE, 0.0, d.L1_mm, np.zeros(3), ez, (t1,)),
            Segment(SegmentKind.LINE, d.L1_mm, d.L2_mm, d.L1_mm * ez, d.pipe_II_direction, (t2,))]


@lru_cache(maxsize=None)
def _gauss(n: int):
    """Gauss-Legendre points and weights on [0, 1] (cached: computing them dominated the frame model)."""
    x, w = gauss_legendre(n)
    x, w = 0.5 * (x + 1.0), 0.5 * w
    x.flags.writeable = False
    w.flags.writeable = False
    return x, w


def quadrature_points(segs: list[Segment], n_line: int = 4, n_arc: int = 8, arc_pieces: int = 8):
    """Quadrature points along all segments: (seg index, local u, weight); ``arc_pieces`` per 90 deg of arc."""
    idx, u, w = [], [], []
    for k, seg in enumerate(segs):
        pieces = 1
        if seg.kind is SegmentKind.ARC:
            pieces = max(1, int(np.ceil(arc_pieces * (seg.length_mm / seg.radius_mm) / (0.5 * np.pi) - 1e-9)))
        xg, wg = _gauss(n_arc if seg.kind is SegmentKind.ARC else n_line)
        h = seg.length_mm / pieces
        p = np.repeat(np.arange(pieces), xg.size)
        u.append((p + np.tile(xg, pieces)) * h)
        w.append(np.tile(wg, pieces) * h)
        idx.append(np.full(p.size, k))
    return np.concatenate(idx), np.concatenate(u), np.concatenate(w)


class Centreline:
    """All segments' geometry as arrays, for positions, tangents and first moments at many points at once
    (the same formulas as :class:`Segment`, vectorised over segments)."""

    def __init__(self, segs: list[Segment]):
        self.start = np.array([s.start_F for s in segs], dtype=float)
        self.t0 = np.array([s.direction for s in segs], dtype=float)
        self.n = np.stack([self.t0[:, 2], np.zeros(len(segs)), -self.t0[:, 0]], axis=1)
        self.arc = np.array([s.kind is SegmentKind.ARC for s in segs])
        self.R = np.array([s.radius_mm if s.kind is SegmentKind.ARC else 1.0 for s in segs])
        self.L = np.array([s.length_mm for s in segs])

    def point(self, idx, u):
        arc, R = self.arc[idx], self.R[idx]
        a = u / R
        c_t = np.where(arc, R * np.sin(a), u)
        c_n = np.where(arc, R * (1.0 - np.cos(a)), 0.0)
        return self.start[idx] + c_t[:, None] * self.t0[idx] + c_n[:, None] * self.n[idx]

    def tangent(self, idx, u):
        arc, a = self.arc[idx], u / self.R[idx]
        return (np.where(arc, np.cos(a), 1.0)[:, None] * self.t0[idx]
                + np.where(arc, np.sin(a), 0.0)[:, None] * self.n[idx])

    def point_integral(self, idx, u):
        """``int_u^L point ds`` [mm^2], shape=(n, 3)."""
        arc, R, L = self.arc[idx], self.R[idx], self.L[idx]
        span, a, b = L - u, u / R, L / R
        c_t = np.where(arc, R * R * (np.cos(a) - np.cos(b)), 0.5 * (L * L - u * u))
        c_n = np.where(arc, R * (span - R * (np.sin(b) - np.sin(a))), 0.0)
        return span[:, None] * self.start[idx] + c_t[:, None] * self.t0[idx] + c_n[:, None] * self.n[idx]


def distal_moments(segs, cl: Centreline, idx, u, tip_mass_kg, tip_com_F):
    """Distal mass W [kg] and first moment Q1 [kg mm] (about {F} origin) at each quadrature point (exact)."""
    mpm = np.array([seg.mass_per_mm for seg in segs])
    all_k = np.arange(len(segs))
    tot_m = mpm * cl.L
    tot_q = cl.point_integral(all_k, np.zeros(len(segs))) * mpm[:, None]
    suf_m = np.concatenate([np.cumsum(tot_m[::-1])[::-1][1:], [0.0]]) + tip_mass_kg
    suf_q = np.concatenate([np.cumsum(tot_q[::-1], axis=0)[::-1][1:], np.zeros((1, 3))]) + tip_mass_kg * tip_com_F
    W = (cl.L[idx] - u) * mpm[idx] + suf_m[idx]
    Q = cl.point_integral(idx, u) * mpm[idx, None] + suf_q[idx]
    return W, Q


def section_flexibility(segs: list[Segment], idx, t, bend_flex, shear: bool, axial: bool, shear_factor: float,
                 torsion_factor: float):
    """Section compliances at the quadrature points: force ``Kf^-1`` [1/N] and moment ``Km^-1``
    [1/(N mm^2)], each shape=(n, 3, 3) in {F}, along the local tangents ``t`` shape=(n, 3)."""
    props = np.array([[s.EI, s.GJ, s.EA, s.kGA] for s in segs])[idx]
    EI, GJ, EA, kGA = props.T
    tt = t[:, :, None] * t[:, None, :]
    # bending flexibility: in-plane (moment about the bend-plane normal y) and out-of-plane factors on arcs
    ey = np.array([0.0, 1.0, 0.0])
    n = np.cross(t, ey)
    flex = np.array([(s.bend_flex or bend_flex) if s.kind is SegmentKind.ARC else (1.0, 1.0) for s in segs])[idx]
    k_in, k_out = flex[:, 0], flex[:, 1]
    yy = np.broadcast_to(np.outer(ey, ey), tt.shape)
    nn = n[:, :, None] * n[:, None, :]
    Km_inv = (torsion_factor * tt / GJ[:, None, None] + (k_in / EI)[:, None, None] * yy
              + (k_out / EI)[:, None, None] * nn)
    Kf_inv = np.zeros_like(tt)
    if axial:
        Kf_inv = Kf_inv + tt / EA[:, None, None]
    if shear:
        Kf_inv = Kf_inv + shear_factor * (np.eye(3)[None] - tt) / kGA[:, None, None]
    return Kf_inv, Km_inv


def unit_load_compliance(segs: list[Segment], tip_F: np.ndarray, tip_mass_kg: float, shear: bool, axial: bool,
               tip_com_F: np.ndarray | None = None, bend_flex: tuple[float, float] = (1.0, 1.0),
               shear_factor: float = 1.0, torsion_factor: float = 1.0):
    """C_F and C_g of a cantilever tree of ``segs`` (clamped at the first) by the unit-load method.

    tip_F : load point (ball centre) in {F} [mm]; tip_mass_kg / tip_com_F : rigid tip mass and its COM;
    shear / axial : include Timoshenko shear / axial flexibility; bend_flex : factors on the arcs' bending
    (a segment's own ``bend_flex`` overrides it); shear_factor / torsion_factor : factors on all shear /
    torsion flexibility (frame-model calibration).
    """
    idx, u, w = quadrature_points(segs)
    cl = Centreline(segs)
    r = cl.point(idx, u)
    t = cl.tangent(idx, u)
    Kf_inv, Km_inv = section_flexibility(segs, idx, t, bend_flex, shear, axial, shear_factor, torsion_factor)
    Mu = _skew(tip_F[None, :] - r)                       # moment of unit tip forces, columns = load dirs
    CF = np.einsum("q,qai,qab,qbj->ij", w, Mu, Km_inv, Mu) + np.einsum("q,qij->ij", w, Kf_inv)
    W, Q = distal_moments(segs, cl, idx, u, tip_mass_kg, tip_F if tip_com_F is None else tip_com_F)
    Mg = G0 * _skew(Q - W[:, None] * r)                  # moment of distal weight per unit g0 along e_j
    Ng = G0 * W[:, None, None] * np.eye(3)[None]
    Cg = np.einsum("q,qai,qab,qbj->ij", w, Mu, Km_inv, Mg) + np.einsum("q,qab,qbj->aj", w, Kf_inv, Ng)
    return CF, Cg


def _corner_segments(design: RodDesign, segs: list[Segment]) -> list[Segment]:
    out = []
    for s in segs:
        if s.kind is SegmentKind.ARC:
            t = design.tangent_mm
            out.append(Segment(SegmentKind.LINE, s.s0_mm, t, s.start_F, s.direction, s.layers))
            out.append(Segment(SegmentKind.LINE, s.s0_mm + t, t, s.start_F + t * s.direction,
                               design.pipe_II_direction, s.layers))
        else:
            out.append(s)
    return out


def calc_compliance(design: RodDesign, *, pipes_only: bool = False, shear: bool = False,
                    axial: bool = True, bend: BendModel = BendModel.ARC,
                    bend_flexibility: tuple[float, float] = (1.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form C_F [mm/N] and C_g [mm/g0] of ``design`` in {T}, each shape=(3, 3).

    Parameters
    ----------
    pipes_only : the paper's idealisation (two tubes, sharp corner, no parts, no ball mass, no declared joints;
        otherwise the design's declared joints, :mod:`rodlab.core.joint_springs`, are added in series)
    shear : add Timoshenko shear flexibility (Euler-Bernoulli when False, as the paper)
    axial : add axial flexibility of the tubes (the paper neglects it)
    bend : :class:`BendModel` of the bend pipe
    bend_flexibility : factors (in-plane, out-of-plane) on the bending compliance of the bend arc
        (pipe-bend ovalisation, e.g. ASME B31.3 k = 1.65 / h); 1 = plain curved beam
    """
    expect_type(design, RodDesign, "design", "load one with rodlab.resolve_design('rod1' or 'FILE.rod.toml')")
    bend = BendModel(bend)
    if pipes_only:
        segs = pipes_only_segments(design)
        tip_mass = 0.0
    else:
        segs = layout(design)
        if bend is BendModel.CORNER:
            segs = _corner_segments(design, segs)
        ball = ball_mass_properties(design)
        CF, Cg = unit_load_compliance(segs, design.tool_mm, ball.mass_kg, shear, axial,
                                      ball.com_T_mm + design.tool_mm, tuple(bend_flexibility))
        dF, dg = declared_joint_compliance(design)
        return CF + dF, Cg + dg
    return unit_load_compliance(segs, design.tool_mm, tip_mass, shear, axial)


def paper_compliance(design: RodDesign) -> tuple[np.ndarray, np.ndarray]:
    """Paper Eqs. 15 and 17 literally: pipes only, one tube section, gamma = 90 deg.

    ``q`` of Eq. 17 is the tube's weight per length at 1 g0 [N/mm]. Raises :class:`DesignError`
    for other gammas or when pipe I and pipe II differ (the formulas assume one section).
    """
    if abs(design.gamma_deg - 90.0) > 1e-9:
        raise DesignError(f"the paper's Eqs. 15/17 hold for gamma = 90 deg only, got {design.gamma_deg}",
                          key="gamma_deg")
    if design.pipe_I != replace(design.pipe_II, key=design.pipe_I.key):
        raise DesignError("the paper's Eqs. 15/17 assume one tube for pipe I and pipe II", key="pipe_II")
    seg = pipes_only_segments(design)[0]
    EI, GJ = seg.EI, seg.GJ
    q = seg.mass_per_mm * G0
    L1, L2 = design.L1_mm, design.L2_mm
    CF = np.array([
        [L1 ** 3 / (3 * EI), 0.0, -L1 ** 2 * L2 / (2 * EI)],
        [0.0, (L1 ** 3 + L2 ** 3) / (3 * EI) + L1 * L2 ** 2 / GJ, 0.0],
        [-L1 ** 2 * L2 / (2 * EI), 0.0, L2 ** 3 / (3 * EI) + L1 * L2 ** 2 / EI]])
    Cg = q * np.array([
        [L1 ** 3 * L2 / (3 * EI) + L1 ** 4 / (8 * EI), 0.0, -L1 ** 2 * L2 ** 2 / (4 * EI)],
        [0.0, L2 ** 4 / (8 * EI) + L1 ** 3 * L2 / (3 * EI) + L1 ** 4 / (8 * EI) + L1 * L2 ** 3 / (2 * GJ), 0.0],
        [-L1 ** 3 * L2 / (6 * EI) - L1 ** 2 * L2 ** 2 / (2 * EI), 0.0, L2 ** 4 / (8 * EI) + L1 * L2 ** 3 / (2 * EI)]])
    return CF, Cg


def calc_rod_compliance(design: RodDesign, *, bend: BendModel = BendModel.ARC, shear: bool = False,
                        axial: bool = True):
    """Closed-form compliance of ``design`` as a :class:`~rodlab.core.compliance.RodCompliance` (method ``calc``)."""
    CF, Cg = calc_compliance(design, bend=bend, shear=shear, axial=axial)
    CF = 0.5 * (CF + CF.T)  # exact in theory; remove round-off
    return RodCompliance.from_design(design, CF, Cg, Method.CALC, {
        "generator": "rodlab closed form (unit-load Euler-Bernoulli frame)",
        "options": {"bend": BendModel(bend).value, "shear": shear, "axial": axial}})
