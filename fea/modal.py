"""Natural frequencies of a rod clamped on the flange, from the beam frame.

The centreline (the frame's segments, :func:`fea.frame.frame_segments`) is cut into ``pieces`` intervals of
about equal length; each interval's mass is lumped at its distal point and the ball (with the holder's stud
beyond the last cut) at the ball centre. The translational flexibility between the lumped points follows from
the cantilever chain (:mod:`rodlab.core.chain`): a force at point ``b`` deforms every interval ``k`` up to ``b``,
and point ``a`` sees interval ``k``'s motion carried rigidly,

    D[a, b] = sum_{k <= min(a, b)} (Ad_{a,k}^T F_k Ad_{b,k})[:3, :3],   Ad_{x,k} = transport(p_x - p_k),

so ``omega^2`` are the eigenvalues of ``(M^1/2 D M^1/2)^-1``. Rotary inertia is neglected (the ball's is
~1e-5 kg m^2, the tubes' sections are thin). The frame's global calibration gives the interval
flexibilities (a family's joint fit is not applied here); the clamp is rigid.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.chain import chain_flexibility, transport
from rodlab.core.design import RodDesign
from rodlab.core.massprops import ball_mass_properties

from .frame import CALIBRATION, FrameCalibration, frame_segments

__all__ = ["frame_frequencies", "chain_frequencies"]


def _lumped(segs, cuts: np.ndarray, n_points: int, tip_mass: float) -> np.ndarray:
    """Mass [kg] at each interval's distal point: half of each interval's mass at either end (the clamp's half
    is held), the tip mass at the last point."""
    bounds = np.concatenate([[0.0], cuts, [segs[-1].s0_mm + segs[-1].length_mm]])
    per = np.zeros(n_points)
    for seg in segs:
        a, b = seg.s0_mm, seg.s0_mm + seg.length_mm
        per += seg.mass_per_mm * np.clip(np.minimum(b, bounds[1:]) - np.maximum(a, bounds[:-1]), 0.0, None)
    m = 0.5 * per
    m[:-1] += 0.5 * per[1:]
    m[-1] += tip_mass
    return m


def chain_frequencies(segs, tip_F, tip_mass_kg: float, tip_com_F, modes: int = 3, pieces: int = 40,
                      shear_factor: float = 1.0, torsion_factor: float = 1.0) -> np.ndarray:
    """The first ``modes`` natural frequencies [Hz] of the cantilever chain ``segs`` (clamped at arc length 0)
    with a rigid tip mass at ``tip_com_F`` [mm] in {F} (see the module docstring)."""
    total = segs[-1].s0_mm + segs[-1].length_mm
    cuts = np.linspace(0.0, total, pieces + 1)[1:-1]
    tip = np.asarray(tip_F, float)
    ch = chain_flexibility(segs, cuts, tip, tip_mass_kg, np.asarray(tip_com_F, float), True, True, shear_factor,
                           torsion_factor)
    P = ch.points_F
    n = len(P)
    m = _lumped(segs, cuts, n, tip_mass_kg)
    Ad = transport(P[:, None, :] - P[None, :, :])          # Ad[x, k]: a wrench at point x seen at point k
    D = np.zeros((n, 3, n, 3))
    for k in range(n):
        A = Ad[k:, k, :, :3]                               # forces at the points beyond interval k, (r, 6, 3)
        r = A.shape[0]
        B = np.einsum("aji,jl->ail", A, ch.F[k]).reshape(3 * r, 6)
        D[k:, :, k:, :] += (B @ A.transpose(1, 0, 2).reshape(6, 3 * r)).reshape(r, 3, r, 3)   # A^T F A, one GEMM
    D = D.reshape(3 * n, 3 * n)
    s = np.sqrt(np.repeat(m, 3))
    lam = np.linalg.eigvalsh(0.5 * (D + D.T) * s[:, None] * s[None, :])[::-1]
    lam = lam[lam > 0][:modes]
    return np.sqrt(1e3 / lam) / (2 * np.pi)                # D [mm/N] = 1e-3 m/N, m [kg]


def frame_frequencies(design: RodDesign, modes: int = 3, pieces: int = 40,
                      cal: FrameCalibration = CALIBRATION) -> np.ndarray:
    """The first ``modes`` natural frequencies [Hz] of ``design`` clamped at the flange face, ascending."""
    ball = ball_mass_properties(design)
    tip = np.asarray(design.tool_mm, float)
    return chain_frequencies(frame_segments(design, cal), tip, ball.mass_kg, ball.com_T_mm + tip, modes, pieces,
                             cal.shear, cal.torsion)
