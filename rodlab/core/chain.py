"""A cantilever frame cut into intervals: each interval's 6 x 6 flexibility and its transport to the tip.

The rod is a statically determinate chain clamped at the flange, so the tip's motion is the sum over any
partition of the centreline into intervals of each interval's own deformation carried rigidly to the tip.
Interval ``i`` runs from cut ``i - 1`` (the clamp for ``i = 0``) to its *distal point* ``p_i`` (cut ``i``;
the tip for the last interval). With a wrench ``W = (F, M)`` [N, N mm] applied at ``p_i``, the motion
``(delta, phi)`` [mm, rad] of the section at ``p_i`` relative to the interval's proximal section is

    (delta, phi) = F_i W,      F_i = int_i Phi^T blockdiag(Kf^-1, Km^-1) Phi ds,

with ``Phi = [[I, 0], [skew(p_i - r(s)), I]]`` the internal (force, moment) at ``r(s)`` per unit ``W``
(the unit-load method of :func:`rodlab.core.calc.unit_load_compliance`, restricted to the interval). A tip
wrench reaches ``p_i`` as ``Ad_i W_tip``, ``Ad_i = [[I, 0], [skew(p_tip - p_i), I]]``, and the interval's
motion reaches the tip as ``Ad_i^T``, so

    C6_tip = sum_i Ad_i^T F_i Ad_i                                  (tip wrench -> tip motion),
    C6_g   = sum_i Ad_i^T (F_i G_i + H_i)                           (gravity -> tip motion),

``G_i`` the wrench at ``p_i`` of all the weight beyond it (per g0 along x, y, z of {T}) and ``H_i`` the
interval's motion under its own weight. This is what lets the frame carry a *joint* correction measured
on one design (an interval's flexibility from the solid model) to another design of the same family.

Frames: {F} (see :mod:`rodlab.core.layout`); motions and wrenches as (translation, rotation) and (force, moment).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .calc import Centreline, distal_moments, section_flexibility, quadrature_points
from .frames import skew as _skew
from .layout import Segment
from .units import G0

__all__ = ["ChainFlexibility", "split_at", "chain_flexibility", "transport", "centreline_points",
           "distal_weight_wrench", "weight_wrench"]


@dataclass(frozen=True)
class ChainFlexibility:
    """Intervals of a cantilever frame (see module doc), all in {F}.

    points_F : distal point of each interval [mm], shape=(n, 3) (the last is the tip)
    F : flexibility of each interval at its distal point, shape=(n, 6, 6)
        [mm/N, mm/(N mm); rad/N, rad/(N mm)] ((translation, rotation) per (force, moment))
    G : wrench at each distal point of the weight beyond it, per g0 along x, y, z, shape=(n, 6, 3) [N, N mm]
    H : motion of each interval under its own weight, per g0, shape=(n, 6, 3) [mm, rad]
    tip_F : the tip (load point) [mm], shape=(3,)
    """

    points_F: np.ndarray
    F: np.ndarray
    G: np.ndarray
    H: np.ndarray
    tip_F: np.ndarray

    def __post_init__(self) -> None:
        n = self.points_F.shape[0]
        for name, shape in (("points_F", (n, 3)), ("F", (n, 6, 6)), ("G", (n, 6, 3)), ("H", (n, 6, 3)),
                            ("tip_F", (3,))):
            if getattr(self, name).shape != shape:
                raise ValueError(f"ChainFlexibility.{name} must have shape {shape}, got {getattr(self, name).shape}")

    def adjoint(self) -> np.ndarray:
        """``Ad_i``: tip wrench -> wrench at each distal point, shape=(n, 6, 6)."""
        return transport(self.tip_F[None, :] - self.points_F)

    def tip_compliance(self, F=None, G=None, H=None) -> tuple[np.ndarray, np.ndarray]:
        """``C6_tip`` shape=(6, 6) and ``C6_g`` shape=(6, 3) from the intervals (or from other ``F``, ``G``,
        ``H`` of the same shapes, e.g. corrections)."""
        F = self.F if F is None else F
        G = self.G if G is None else G
        H = self.H if H is None else H
        Ad = self.adjoint()
        C6 = np.einsum("nai,nab,nbj->ij", Ad, F, Ad)
        C6g = np.einsum("nai,nab->ib", Ad, np.einsum("nab,nbj->naj", F, G) + H)
        return C6, C6g


def transport(arm: np.ndarray) -> np.ndarray:
    """``[[I, 0], [skew(arm), I]]``: a wrench at ``x`` moved to ``x - arm`` (force kept, moment gains
    ``arm x F``), shape=(..., 6, 6); its transpose carries a motion back from ``x - arm`` to ``x``."""
    arm = np.asarray(arm, dtype=float)
    out = np.zeros(arm.shape[:-1] + (6, 6))
    out[..., :3, :3] = np.eye(3)
    out[..., 3:, 3:] = np.eye(3)
    out[..., 3:, :3] = _skew(arm)
    return out


def split_at(segs: list[Segment], cuts_mm) -> list[Segment]:
    """``segs`` split at the arc lengths ``cuts_mm`` from the flange [mm] (pieces keep all other fields)."""
    out = []
    for seg in segs:
        inner = sorted(c - seg.s0_mm for c in cuts_mm if seg.s0_mm + 1e-9 < c < seg.s0_mm + seg.length_mm - 1e-9)
        bounds = [0.0] + inner + [seg.length_mm]
        if len(bounds) == 2:
            out.append(seg)
            continue
        for a, b in zip(bounds[:-1], bounds[1:]):
            out.append(replace(seg, s0_mm=seg.s0_mm + a, length_mm=b - a, start_F=seg.point([a])[0],
                               direction=seg.tangent([a])[0]))
    return out


def chain_flexibility(segs: list[Segment], cuts_mm, tip_F: np.ndarray, tip_mass_kg: float,
                      tip_com_F: np.ndarray, shear: bool = True, axial: bool = True,
                      shear_factor: float = 1.0, torsion_factor: float = 1.0) -> ChainFlexibility:
    """The intervals between the clamp, the cuts (arc lengths from the flange [mm], strictly inside the
    centreline, increasing) and the tip, for a chain of ``segs`` with a rigid tip mass (see module doc and
    :func:`rodlab.core.calc.unit_load_compliance` for the other arguments)."""
    cuts = np.asarray(cuts_mm, dtype=float)
    total = segs[-1].s0_mm + segs[-1].length_mm
    if cuts.size and (np.any(np.diff(cuts) <= 0) or cuts[0] <= 0 or cuts[-1] >= total):
        raise ValueError(f"cuts must increase strictly inside (0, {total:g}) mm, got {cuts.tolist()}")
    pieces = split_at(segs, cuts)
    mid = np.array([p.s0_mm + 0.5 * p.length_mm for p in pieces])
    interval = np.searchsorted(cuts, mid)                       # piece -> interval
    idx, u, w = quadrature_points(pieces)
    cl = Centreline(pieces)
    r, t = cl.point(idx, u), cl.tangent(idx, u)
    Kf, Km = section_flexibility(pieces, idx, t, (1.0, 1.0), shear, axial, shear_factor, torsion_factor)
    W, Q = distal_moments(pieces, cl, idx, u, tip_mass_kg, tip_com_F)
    n = cuts.size + 1
    first = [int(np.nonzero(interval == i)[0][0]) for i in range(1, n)]   # first piece beyond each cut
    starts = np.array([pieces[j].start_F for j in first]).reshape(-1, 3)
    points = np.vstack([starts, tip_F[None, :]])
    # weight beyond each distal point (for the tip: the tip mass alone)
    Wd, Qd = distal_moments(pieces, cl, np.array(first, dtype=int), np.zeros(len(first)), tip_mass_kg,
                             tip_com_F)
    Wd = np.append(Wd, tip_mass_kg)
    Qd = np.vstack([Qd.reshape(-1, 3), tip_mass_kg * np.asarray(tip_com_F, dtype=float)[None, :]])
    G = weight_wrench(Wd, Qd, points)
    qi = interval[idx]                                          # quadrature point -> interval
    S = _skew(points[qi] - r)                                   # moment arm of the distal wrench
    Fq = np.zeros((idx.size, 6, 6))
    Fq[:, :3, :3] = Kf + np.einsum("qai,qab,qbj->qij", S, Km, S)
    Fq[:, :3, 3:] = np.einsum("qai,qab->qib", S, Km)
    Fq[:, 3:, :3] = np.transpose(Fq[:, :3, 3:], (0, 2, 1))
    Fq[:, 3:, 3:] = Km
    Wl, Ql = W - Wd[qi], Q - Qd[qi]                             # the interval's own weight beyond s
    f = G0 * Wl[:, None, None] * np.eye(3)[None]
    m = G0 * _skew(Ql - Wl[:, None] * r)
    Hq = np.zeros((idx.size, 6, 3))
    Hq[:, :3, :] = np.einsum("qab,qbj->qaj", Kf, f) + np.einsum("qai,qab,qbj->qij", S, Km, m)
    Hq[:, 3:, :] = np.einsum("qab,qbj->qaj", Km, m)
    F = np.zeros((n, 6, 6))
    H = np.zeros((n, 6, 3))
    np.add.at(F, qi, w[:, None, None] * Fq)
    np.add.at(H, qi, w[:, None, None] * Hq)
    return ChainFlexibility(points, F, G, H, np.asarray(tip_F, dtype=float))


def _locate(segs: list[Segment], s_mm):
    """Segment index and local arc length of each arc length ``s_mm`` from the flange (inside the centreline)."""
    s_mm = np.atleast_1d(np.asarray(s_mm, dtype=float))
    starts = np.array([g.s0_mm for g in segs])
    total = segs[-1].s0_mm + segs[-1].length_mm
    if np.any(s_mm < 0) or np.any(s_mm > total):
        raise ValueError(f"arc lengths must lie on the centreline (0 to {total:g} mm), got {s_mm.tolist()}")
    idx = np.clip(np.searchsorted(starts, s_mm, side="right") - 1, 0, len(segs) - 1)
    return idx, s_mm - starts[idx]


def centreline_points(segs: list[Segment], s_mm) -> tuple[np.ndarray, np.ndarray]:
    """Points [mm] in {F} and unit tangents at the arc lengths ``s_mm`` from the flange, shape=(n, 3) each."""
    idx, u = _locate(segs, s_mm)
    cl = Centreline(segs)
    return cl.point(idx, u), cl.tangent(idx, u)


def distal_weight_wrench(segs: list[Segment], s_mm, tip_mass_kg: float, tip_com_F: np.ndarray) -> np.ndarray:
    """Wrench at the centreline points ``s_mm`` [mm from the flange] of all the weight beyond them (the
    segments' and the rigid tip mass), per g0 along x, y, z of {T}, shape=(n, 6, 3) [N, N mm]."""
    idx, u = _locate(segs, s_mm)
    cl = Centreline(segs)
    W, Q = distal_moments(segs, cl, idx, u, tip_mass_kg, np.asarray(tip_com_F, dtype=float))
    return weight_wrench(W, Q, cl.point(idx, u))


def weight_wrench(mass_kg, first_moment_kg_mm, points_F) -> np.ndarray:
    """Wrench at ``points_F`` [mm] of masses ``mass_kg`` with first moments ``first_moment_kg_mm`` (about the
    {F} origin), per g0 along x, y, z of {T}, shape=(n, 6, 3) [N, N mm]."""
    W = np.atleast_1d(np.asarray(mass_kg, dtype=float))
    Q = np.atleast_2d(np.asarray(first_moment_kg_mm, dtype=float))
    G = np.zeros((W.size, 6, 3))
    G[:, :3, :] = G0 * W[:, None, None] * np.eye(3)
    G[:, 3:, :] = G0 * _skew(Q - W[:, None] * np.atleast_2d(points_F))
    return G
