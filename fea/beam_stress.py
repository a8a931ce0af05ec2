"""The frame model's stress: von Mises at the outer fibre of each section from the beam's section forces.

The rod is a statically determinate cantilever, so the section forces at a centreline point are those of
everything beyond it: a unit force at the ball centre reaches the section at ``p`` as the wrench
``(F, (p_ball - p) x F)``, and the weight beyond ``p`` as :func:`rodlab.core.chain.distal_weight_wrench`. Along the
local tangent ``t`` the wrench splits into the axial force ``N = F . t``, the torque ``T = M . t`` and the
bending moment ``M_b = |M - T t|``. A section is concentric layers (a tube, a bonded sleeve over it) that
deform together (plane sections), so the fibre at radius ``r`` of layer ``l`` carries

    sigma_l = E_l (N / EA + (M x y) . t / EI),        tau_l = G_l (T r / GJ + 2 V . e_theta / GA)

at the fibre ``y`` (``|y| = r``, circumferential direction ``e_theta = t x y / r``)
(for one isotropic tube ``sigma = N / A + M_b r_o / I``, ``tau = T r_o / J``), plus the transverse force's
shear flow, ``2 V . e_theta / A`` in a thin tube (zero at the fibre where the bending stress peaks, largest
on the neutral axis). The section's von Mises stress is the largest ``sqrt(sigma^2 + 3 tau^2)`` around the
circumference of the load-carrying layers at their outer radius (the parts the frame counts as stiff there;
a sleeve's load-transfer zone carries none). Not modelled: the
bend's stress intensification (ovalisation) and the stress concentrations at the joints, which only the solid
model shows (``rodlab fea --model solid --fields``).
"""
from __future__ import annotations

import numpy as np

from rodlab.core.chain import centreline_points, distal_weight_wrench, transport
from rodlab.core.layout import Segment
from rodlab.core.units import gpa_to_mpa

__all__ = ["section_wrenches", "section_von_mises", "section_index"]


def section_wrenches(segs: list[Segment], s_mm, tip_F: np.ndarray, tip_mass_kg: float,
                     tip_com_F: np.ndarray) -> np.ndarray:
    """Wrench (force [N], moment [N mm]) that the part beyond each centreline point ``s_mm`` [mm from the
    flange] puts on the section there, in {F}, for the six unit load cases (unit force along x, y, z at
    ``tip_F``; 1 g0 along x, y, z on the segments' and the tip mass's weight), shape=(n, 6, 6)."""
    s = np.atleast_1d(np.asarray(s_mm, dtype=float))
    p, _ = centreline_points(segs, s)
    W = np.zeros((s.size, 6, 6))
    W[:, :, :3] = transport(np.asarray(tip_F, dtype=float)[None, :] - p)[:, :, :3]
    W[:, :, 3:] = distal_weight_wrench(segs, s, tip_mass_kg, np.asarray(tip_com_F, dtype=float))
    return W


def section_index(segs: list[Segment], s: np.ndarray) -> np.ndarray:
    """Index of the segment holding each arc length (at a boundary: the one that starts there)."""
    starts = np.array([g.s0_mm for g in segs])
    return np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(segs) - 1)


def _layers(seg: Segment) -> np.ndarray:
    """Per layer: (outer radius [mm], E / EA [1/mm^2], E / EI [1/mm^4], G / GJ [1/mm^4], 2 G / GA [1/mm^2]);
    zeros for a part the frame counts as slack there, shape=(k, 5)."""
    slack_t = seg.slack if seg.slack_torsion is None else seg.slack_torsion
    GA = sum(gpa_to_mpa(l.material.G_axial_GPa) * l.area_mm2 for l in seg.layers if l.part not in seg.slack)
    rows = []
    for layer in seg.layers:
        E, G = gpa_to_mpa(layer.material.E_GPa), gpa_to_mpa(layer.material.G_axial_GPa)
        bend, twist = layer.part not in seg.slack, layer.part not in slack_t
        rows.append((0.5 * layer.d_out_mm, E / seg.EA if bend else 0.0, E / seg.EI if bend else 0.0,
                     G / seg.GJ if twist else 0.0, 2.0 * G / GA if bend else 0.0))
    return np.array(rows, dtype=float)


#: fibres around the circumference where the stress is evaluated (every 2.5 degrees)
_ANGLES = np.linspace(0.0, 2.0 * np.pi, 144, endpoint=False)


def section_von_mises(segs: list[Segment], s_mm, wrenches: np.ndarray) -> np.ndarray:
    """Largest outer-fibre von Mises stress [MPa per unit load] of the sections at ``s_mm`` [mm from the
    flange] under ``wrenches`` (shape=(n, 6, n_cases) [N, N mm] in {F}, e.g. :func:`section_wrenches`),
    shape=(n, n_cases): at the fibres every 2.5 degrees around each layer's outer radius, the axial stress
    ``E_l (N / EA + (M x y) . t / EI)`` and the shear ``G_l (T r / GJ + 2 V . e_theta / GA)`` (torsion and the
    transverse force's thin-wall shear flow), the largest ``sqrt(sigma^2 + 3 tau^2)`` over fibres and layers."""
    s = np.atleast_1d(np.asarray(s_mm, dtype=float))
    _, t = centreline_points(segs, s)
    e1 = np.cross(t, [0.0, 1.0, 0.0])
    e1[np.linalg.norm(e1, axis=1) < 1e-9] = [1.0, 0.0, 0.0]             # a tangent along y (not in rodlab's rods)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(t, e1)
    u = np.cos(_ANGLES)[None, :, None] * e1[:, None, :] + np.sin(_ANGLES)[None, :, None] * e2[:, None, :]
    e_theta = np.cross(t[:, None, :], u)                                 # (n, fibres, 3)
    F, M = wrenches[:, :3, :], wrenches[:, 3:, :]
    N = np.einsum("ni,nic->nc", t, F)[:, None, :]                        # (n, 1, cases)
    T = np.einsum("ni,nic->nc", t, M)[:, None, :]
    Mu = np.einsum("nfi,nic->nfc", e_theta, M)                           # (M x u) . t = M . (u x t) = -M . e_theta
    V = np.einsum("nfi,nic->nfc", e_theta, F)
    idx = section_index(segs, s)
    out = np.zeros((s.size, wrenches.shape[2]))
    for k in np.unique(idx):
        sel = idx == k
        best = np.zeros((sel.sum(), wrenches.shape[2]))
        for r, a, b, g, q in _layers(segs[k]):
            sigma = a * N[sel] - b * r * Mu[sel]
            tau = g * r * T[sel] + q * V[sel]
            best = np.maximum(best, np.sqrt(sigma ** 2 + 3.0 * tau ** 2).max(axis=1))
        out[sel] = best
    return out
