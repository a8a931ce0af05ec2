"""Analytic mass properties of a rod from its parts (the CAD cross-checks them).

Each part is integrated with a Gauss rule that is exact for the mass, first and second
moments of straight cylinders, annular sections swept along an arc, and the sphere, so the
results are exact to round-off. Positions are reported in the tool frame {T} [mm].
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .design import RodDesign
from .enums import Part
from .layout import Segment, SegmentKind, flange_to_tool, layout
from .units import kg_m3_to_kg_mm3

__all__ = ["MassProperties", "mass_properties", "part_mass_properties", "ball_mass_properties", "combine", "gauss_legendre",
           "distal_mass_properties"]


@dataclass(frozen=True)
class MassProperties:
    """Mass, centre of mass and inertia of a body.

    Attributes
    ----------
    mass_kg : mass [kg]
    com_T_mm : centre of mass in {T} [mm], shape=(3,)
    inertia_kg_mm2 : inertia tensor about the centre of mass, axes of {T} [kg mm^2], shape=(3, 3)
    """

    mass_kg: float
    com_T_mm: np.ndarray
    inertia_kg_mm2: np.ndarray

    def __post_init__(self) -> None:
        com = np.asarray(self.com_T_mm, dtype=float)
        inertia = np.asarray(self.inertia_kg_mm2, dtype=float)
        if com.shape != (3,) or inertia.shape != (3, 3):
            raise ValueError(f"com_T_mm must have shape (3,), inertia (3, 3); got {com.shape}, {inertia.shape}")
        object.__setattr__(self, "com_T_mm", com)
        object.__setattr__(self, "inertia_kg_mm2", inertia)

    def to_dict(self) -> dict:
        return {"mass_kg": float(self.mass_kg), "com_T_mm": [float(v) for v in self.com_T_mm],
                "inertia_kg_mm2": [[float(v) for v in row] for row in self.inertia_kg_mm2]}

    @staticmethod
    def from_points(pts_T: np.ndarray, w_kg: np.ndarray) -> "MassProperties":
        m = float(w_kg.sum())
        com = (w_kg[:, None] * pts_T).sum(axis=0) / m
        d = pts_T - com
        r2 = (d * d).sum(axis=1)
        inertia = (w_kg[:, None, None] * (r2[:, None, None] * np.eye(3)[None] - d[:, :, None] * d[:, None, :])).sum(0)
        return MassProperties(m, com, inertia)


@lru_cache(maxsize=None)
def gauss_legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [-1, 1], shape=(n,) each, read-only (cached: NumPy computes them
    by an eigenvalue problem each call, ~0.1 ms; a study's design used ~100 of them)."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = False
    w.flags.writeable = False
    return x, w


def _section_rule(d_out: float, d_in: float, n_r: int = 3, n_phi: int = 8):
    """Points (radius, angle) and area weights on an annulus, exact for low-order moments."""
    xg, wg = gauss_legendre(n_r)
    r_o, r_i = d_out / 2.0, d_in / 2.0
    r = 0.5 * (r_o - r_i) * xg + 0.5 * (r_o + r_i)
    wr = 0.5 * (r_o - r_i) * wg * r
    phi = 2 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    R, PHI = np.meshgrid(r, phi, indexing="ij")
    W = np.repeat(wr[:, None], n_phi, axis=1) * (2 * np.pi / n_phi)
    return R.ravel(), PHI.ravel(), W.ravel()


def _segment_points(seg: Segment, d_out: float, d_in: float, density_kg_mm3: float, n_s: int, u0: float = 0.0):
    """Quadrature points {F} and masses [kg] of one annular layer along one segment (from local arc length
    ``u0`` [mm] to its end)."""
    xg, wg = gauss_legendre(n_s)
    span = seg.length_mm - u0
    u = u0 + 0.5 * span * (xg + 1.0)
    wu = 0.5 * span * wg
    c = seg.point(u)
    t = seg.tangent(u)
    e1 = np.array([0.0, 1.0, 0.0])  # out-of-plane axis (the bend lies in x-z)
    e2 = np.cross(t, e1)            # in-plane normal, pointing away from an arc's centre
    r, phi, wa = _section_rule(d_out, d_in)
    off1 = r * np.cos(phi)
    off2 = r * np.sin(phi)
    pts = c[:, None, :] + off1[None, :, None] * e1[None, None, :] + off2[None, :, None] * e2[:, None, :]
    jac = np.ones((u.size, r.size))
    if seg.kind is SegmentKind.ARC:
        # volume element (R + x) dtheta dA, x measured away from the arc centre
        jac = 1.0 + off2[None, :] / seg.radius_mm
    w = density_kg_mm3 * wu[:, None] * wa[None, :] * jac
    return pts.reshape(-1, 3), w.ravel()


def _part_clouds(design: RodDesign, s_from_mm: float = 0.0):
    """{part: [(points {T}, masses)]} of the rod from arc length ``s_from_mm`` (from the flange face) on."""
    clouds: dict[Part, list] = {}
    for seg in layout(design):
        u0 = min(max(s_from_mm - seg.s0_mm, 0.0), seg.length_mm)
        if u0 >= seg.length_mm:
            continue
        n_s = 24 if seg.kind is SegmentKind.ARC else 3
        for layer in seg.layers:
            pts, w = _segment_points(seg, layer.d_out_mm, layer.d_in_mm,
                                     kg_m3_to_kg_mm3(layer.material.density_kg_m3), n_s, u0)
            clouds.setdefault(layer.part, []).append((flange_to_tool(pts, design), w))
    return clouds


def part_mass_properties(design: RodDesign) -> dict[Part, MassProperties]:
    """Mass properties of each part present in ``design`` (ball included), in {T}."""
    out: dict[Part, MassProperties] = {}
    for part, items in _part_clouds(design).items():
        pts = np.concatenate([p for p, _ in items])
        w = np.concatenate([w for _, w in items])
        out[part] = MassProperties.from_points(pts, w)
    out[Part.BALL] = ball_mass_properties(design)
    return {p: out[p] for p in Part if p in out}


def ball_mass_properties(design: RodDesign) -> MassProperties:
    """The ball: a sphere truncated by its flat seat (exact slice quadrature), in {T}."""
    r = design.ball.radius_mm
    zc = design.seat_offset_mm
    rho = kg_m3_to_kg_mm3(design.ball.material.density_kg_m3)
    # axial coordinate a along the seat direction (-pipe II), disks of radius^2 = r^2 - a^2, a in [-r, zc]
    xg, wg = gauss_legendre(6)
    a = 0.5 * (zc + r) * xg + 0.5 * (zc - r)
    w = 0.5 * (zc + r) * wg
    rad2 = r * r - a * a
    dm = rho * np.pi * rad2 * w
    m = dm.sum()
    a_c = (dm * a).sum() / m
    i_axis = (dm * rad2 / 2).sum()
    i_tr = (dm * (rad2 / 4 + (a - a_c) ** 2)).sum()
    u = -design.pipe_II_direction          # from the centre towards the seat
    com = a_c * u
    inertia = i_tr * np.eye(3) + (i_axis - i_tr) * np.outer(u, u)
    return MassProperties(float(m), com, inertia)


def combine(parts) -> MassProperties:
    """Mass properties of a body made of ``parts`` (parallel-axis theorem), same frame."""
    parts = list(parts)
    m = sum(p.mass_kg for p in parts)
    com = sum(p.mass_kg * p.com_T_mm for p in parts) / m
    inertia = np.zeros((3, 3))
    for p in parts:
        d = p.com_T_mm - com
        inertia += p.inertia_kg_mm2 + p.mass_kg * (d @ d * np.eye(3) - np.outer(d, d))
    return MassProperties(m, com, inertia)


def distal_mass_properties(design: RodDesign, s_mm: float) -> MassProperties:
    """Mass properties in {T} of the rod beyond arc length ``s_mm`` from the flange face (the ball included): what a
    joint there carries."""
    items = [it for its in _part_clouds(design, s_mm).values() for it in its]
    parts = [MassProperties.from_points(p, w) for p, w in items if w.sum() > 0]
    return combine(parts + [ball_mass_properties(design)])


def mass_properties(design: RodDesign) -> MassProperties:
    """Mass properties of the whole rod in {T} (parallel-axis sum of the parts)."""
    return combine(part_mass_properties(design).values())
