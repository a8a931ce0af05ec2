"""Strength margins and thermal growth of a rod: what a designer checks beside its compliance.

Strength: the peak stresses under a load case (a contact force of given magnitude at the ball, in any
direction, plus the rod's own weight under one g0 in any direction), bounded over 26 x 26 load directions:

- tube: von Mises ``sqrt((N/A + M_b r/I)^2 + 3 (T r/J + 2 V/A)^2)`` at both ends of every bare tube length
  (pipe I past its holder, the bend, pipe II past ring 2 — where the section drops to the tube alone);
- bond: the adhesive's mean shear over each bonded overlap (pipe holder, each ring (half its length on the tube), the ball
  holder's plug) from the wrench at the overlap's inner end, ``M_b/(pi r^2 L) + T/(2 pi r^2 L) + V/(pi r L)
  + |N|/(2 pi r L)`` (``r`` the tube's outer radius, ``L`` the overlap); the shear-lag peak of a real bond
  is higher, so the margin is a screening value.

Margins are allowable / stress (``Material.strength_MPa``, the adhesive's ``shear_strength_MPa``); NaN where
a material has no allowable.

Thermal growth: the ball centre's shift per kelvin in {T} [um/K], each centreline piece growing along its
chord with its tube's axial CTE (the sleeves ride on the tubes; the ball radius grows with the ball's).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .chain import centreline_points, distal_weight_wrench
from .design import RodDesign
from .enums import Part
from .layout import Segment, layout
from .massprops import mass_properties
from .materials import BUILTIN_MATERIALS, Material

__all__ = ["StrengthMargins", "strength_margins", "thermal_growth_um_per_K", "ADHESIVE"]

#: the bond adhesive assumed at the rings, holders and plug (its lap-shear strength is the bond allowable)
ADHESIVE: Material = BUILTIN_MATERIALS["epoxy"]
_TUBES = (Part.PIPE_I, Part.BEND, Part.PIPE_II)


@dataclass(frozen=True)
class StrengthMargins:
    """Peak stresses [MPa] and margins (allowable / stress) [-] under :attr:`force_N` at the ball and 1 g0.

    tube_stress_MPa, tube_margin, tube_at : the highest tube von Mises stress, its margin and the part;
    bond_stress_MPa, bond_margin, bond_at : the same for the adhesive's shear
    """

    force_N: float
    tube_stress_MPa: float
    tube_margin: float
    tube_at: str
    bond_stress_MPa: float
    bond_margin: float
    bond_at: str


def _directions() -> np.ndarray:
    g = np.array([-1.0, 0.0, 1.0])
    d = np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T
    d = d[np.any(d != 0, axis=1)]
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _section_loads(design: RodDesign, segs: list[Segment], s_mm: np.ndarray, force_N: float):
    """Worst (over load directions) axial force N, shear V [N], bending M_b and torque T [N mm] at ``s_mm``,
    each shape=(k, 26 * 26) (force direction x gravity direction)."""
    mp = mass_properties(design)
    ball = mp.mass_kg - sum(seg.mass_per_mm * seg.length_mm for seg in segs)
    tip = np.asarray(design.tool_mm, float)
    p, t = centreline_points(segs, s_mm)
    Gw = distal_weight_wrench(segs, s_mm, max(ball, 0.0), tip)          # (k, 6, 3) per g0
    dirs = _directions()
    F = force_N * dirs                                                   # (26, 3)
    f_lin = F[None, :, None, :] + np.einsum("kij,gj->kgi", Gw[:, :3], dirs)[:, None, :, :]
    m_F = np.cross((tip - p)[:, None, :], F[None, :, :])                 # (k, 26, 3)
    m_lin = m_F[:, :, None, :] + np.einsum("kij,gj->kgi", Gw[:, 3:], dirs)[:, None, :, :]
    tt = t[:, None, None, :]
    N = np.einsum("kfgi,kfgi->kfg", f_lin, np.broadcast_to(tt, f_lin.shape))
    V = np.linalg.norm(f_lin - N[..., None] * tt, axis=-1)
    T = np.einsum("kfgi,kfgi->kfg", m_lin, np.broadcast_to(tt, m_lin.shape))
    Mb = np.linalg.norm(m_lin - T[..., None] * tt, axis=-1)
    k = len(s_mm)
    return N.reshape(k, -1), V.reshape(k, -1), Mb.reshape(k, -1), T.reshape(k, -1)


def _tube_layer(seg: Segment):
    return next(layer for layer in seg.layers if layer.part in _TUBES)


def _tube_stresses(design, segs, force_N):
    bare = [g for g in segs if len(g.layers) == 1 and g.layers[0].part in _TUBES]
    ends = [(g, s) for g in bare for s in (g.s0_mm + 1e-6, g.s0_mm + g.length_mm - 1e-6)]
    if not ends:
        return float("nan"), float("nan"), ""
    N, V, Mb, T = _section_loads(design, segs, np.array([s for _, s in ends]), force_N)
    best = (0.0, float("nan"), "")
    for i, (g, _) in enumerate(ends):
        layer = g.layers[0]
        r, A, I, J = 0.5 * layer.d_out_mm, layer.area_mm2, layer.I_mm4, layer.J_mm4
        vm = float(np.max(np.sqrt((np.abs(N[i]) / A + Mb[i] * r / I) ** 2 + 3 * (np.abs(T[i]) * r / J
                                                                                   + 2 * V[i] / A) ** 2)))
        allow = layer.material.strength_MPa
        if vm > best[0]:
            best = (vm, (allow / vm) if allow else float("nan"), str(layer.part))
    return best


def _bonds(segs: list[Segment]):
    """(name, s at the overlap's inner end [mm], overlap [mm], bonded tube outer radius [mm]) of each bond."""
    out = []
    for g in segs:
        parts = g.parts
        if Part.PIPE_HOLDER in parts:
            out.append(("pipe_holder", g.s0_mm + g.length_mm - 1e-6, g.length_mm, 0.5 * _tube_layer(g).d_out_mm))
        for ring in (Part.RING_1, Part.RING_2):
            if ring in parts:
                r = 0.5 * _tube_layer(g).d_out_mm
                s_in = g.s0_mm + 1e-6 if ring is Part.RING_1 else g.s0_mm + g.length_mm - 1e-6
                out.append((str(ring), s_in, 0.5 * g.length_mm, r))      # half the ring on each member
        if Part.BALL_HOLDER in parts and Part.PIPE_II in parts:
            out.append(("ball_holder plug", g.s0_mm + 1e-6, g.length_mm,
                        0.5 * next(x for x in g.layers if x.part is Part.BALL_HOLDER).d_out_mm))
    return out


def _bond_stresses(design, segs, force_N):
    bonds = _bonds(segs)
    if not bonds:
        return float("nan"), float("nan"), ""
    N, V, Mb, T = _section_loads(design, segs, np.array([b[1] for b in bonds]), force_N)
    best = (0.0, float("nan"), "")
    for i, (name, _, L, r) in enumerate(bonds):
        tau = float(np.max(Mb[i] / (math.pi * r ** 2 * L) + np.abs(T[i]) / (2 * math.pi * r ** 2 * L)
                           + V[i] / (math.pi * r * L) + np.abs(N[i]) / (2 * math.pi * r * L)))
        if tau > best[0]:
            allow = ADHESIVE.shear_strength_MPa
            best = (tau, allow / tau if allow else float("nan"), name)
    return best


def strength_margins(design: RodDesign, force_N: float) -> StrengthMargins:
    """Peak tube and bond stresses of ``design`` under a ``force_N`` contact force at the ball and its own
    weight (see the module docstring)."""
    if not (math.isfinite(force_N) and force_N >= 0):
        raise ValueError(f"force_N must be a finite number >= 0, got {force_N!r}")
    segs = layout(design)
    return StrengthMargins(float(force_N), *_tube_stresses(design, segs, force_N),
                           *_bond_stresses(design, segs, force_N))


def thermal_growth_um_per_K(design: RodDesign) -> np.ndarray:
    """Shift of the ball centre per kelvin in {T} [um/K], shape=(3,); NaN if a tube material has no CTE."""
    total = np.zeros(3)
    for seg in layout(design):
        tube = next((layer for layer in seg.layers if layer.part in _TUBES), seg.layers[-1])
        cte = tube.material.cte_ppm_K
        if cte is None:
            return np.full(3, np.nan)
        total += cte * (seg.end_F - seg.start_F)
    tip_F = np.asarray(design.tool_mm, float)
    last = layout(design)[-1].end_F
    ball_cte = design.ball.material.cte_ppm_K
    if ball_cte is None:
        return np.full(3, np.nan)
    total += ball_cte * (tip_F - last)
    return total * 1e-3                                                  # ppm * mm = 1e-6 mm = 1e-3 um
