"""Centreline layout of a rod: straight and curved segments, each with its section layers.

Coordinates are those of the *flange frame* {F}: origin at the centre of the flange face, axes
parallel to {6} and {T} (the contract's tool frame), so a point ``p_F`` is ``p_T = p_F - tool_mm``
in {T}. Pipe I runs along +z; the bend turns in the x-z plane towards +x.

The layout is shared by the mass properties, the closed-form compliance, the beam-frame model
and the CAD, so that all of them place the parts identically.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .design import RodDesign
from .enums import Part, SegmentKind
from .materials import Material
from .units import gpa_to_mpa, kg_m3_to_kg_mm3

__all__ = ["Layer", "SegmentKind", "Segment", "layout", "flange_to_tool"]

#: Timoshenko shear coefficients (Cowper 1966): thin-walled tube, solid circle.
_K_SHEAR_TUBE = 0.53
_K_SHEAR_SOLID = 0.89


@dataclass(frozen=True)
class Layer:
    """One concentric annulus of a section: a part, its material and diameters [mm]."""

    part: Part
    material: Material
    d_out_mm: float
    d_in_mm: float = 0.0

    @property
    def area_mm2(self) -> float:
        return math.pi / 4.0 * (self.d_out_mm ** 2 - self.d_in_mm ** 2)

    @property
    def I_mm4(self) -> float:
        """Second moment of area about a diameter [mm^4]."""
        return math.pi / 64.0 * (self.d_out_mm ** 4 - self.d_in_mm ** 4)

    @property
    def J_mm4(self) -> float:
        """Polar moment of area [mm^4]."""
        return 2.0 * self.I_mm4

    @property
    def mass_per_mm(self) -> float:
        """Line mass [kg/mm]."""
        return self.area_mm2 * kg_m3_to_kg_mm3(self.material.density_kg_m3)

    @property
    def shear_coefficient(self) -> float:
        return _K_SHEAR_SOLID if self.d_in_mm <= 0 else _K_SHEAR_TUBE


@dataclass(frozen=True)
class Segment:
    """A piece of centreline with a constant section.

    Attributes
    ----------
    kind : LINE or ARC
    s0_mm : arc length at the segment start, from the flange face [mm]
    length_mm : arc length of the segment [mm]
    start_F : start point in {F} [mm], shape=(3,)
    direction : unit tangent (LINE) or start tangent (ARC), shape=(3,)
    radius_mm : centreline radius (ARC only) [mm]
    layers : section layers, innermost first
    """

    kind: SegmentKind
    s0_mm: float
    length_mm: float
    start_F: np.ndarray
    direction: np.ndarray
    layers: tuple[Layer, ...]
    radius_mm: float = 0.0
    slack: tuple[Part, ...] = ()   #: parts whose mass counts but not their stiffness here (load-transfer zones)
    slack_torsion: tuple[Part, ...] | None = None   #: the same for torsion alone (None: as ``slack``)
    #: ARC only: factors (in-plane, out-of-plane) on the bending compliance here (pipe-bend ovalisation);
    #: None = the factors the caller passes for all arcs
    bend_flex: tuple[float, float] | None = None

    def _stiff(self):
        return [l for l in self.layers if l.part not in self.slack]

    # -- section properties (composite, axial modulus for bending) -------------------------
    @property
    def EA(self) -> float:
        """Axial stiffness [N]."""
        return sum(gpa_to_mpa(l.material.E_GPa) * l.area_mm2 for l in self._stiff())

    @property
    def EI(self) -> float:
        """Bending stiffness [N mm^2]."""
        return sum(gpa_to_mpa(l.material.E_GPa) * l.I_mm4 for l in self._stiff())

    @property
    def GJ(self) -> float:
        """Torsional stiffness [N mm^2] (axial shear modulus)."""
        slack = self.slack if self.slack_torsion is None else self.slack_torsion
        return sum(gpa_to_mpa(l.material.G_axial_GPa) * l.J_mm4 for l in self.layers if l.part not in slack)

    @property
    def kGA(self) -> float:
        """Shear stiffness [N] (Timoshenko)."""
        return sum(l.shear_coefficient * gpa_to_mpa(l.material.G_axial_GPa) * l.area_mm2 for l in self._stiff())

    @property
    def mass_per_mm(self) -> float:
        """Line mass [kg/mm]."""
        return sum(l.mass_per_mm for l in self.layers)

    @property
    def parts(self) -> tuple[Part, ...]:
        return tuple(l.part for l in self.layers)

    # -- geometry ------------------------------------------------------------------------
    def _arc_frame(self):
        # in-plane normal: from the start point towards the arc centre (turning towards +x)
        t0 = self.direction
        n = np.array([t0[2], 0.0, -t0[0]])  # t0 rotated by -90 deg about y in the x-z plane
        return t0, n

    def point(self, u) -> np.ndarray:
        """Positions at local arc length ``u`` [mm] (array), shape=(n, 3) in {F}."""
        u = np.atleast_1d(np.asarray(u, dtype=float))
        if self.kind is SegmentKind.LINE:
            return self.start_F[None, :] + u[:, None] * self.direction[None, :]
        t0, n = self._arc_frame()
        th = u / self.radius_mm
        return (self.start_F[None, :] + self.radius_mm * np.sin(th)[:, None] * t0[None, :]
                + self.radius_mm * (1.0 - np.cos(th))[:, None] * n[None, :])

    def tangent(self, u) -> np.ndarray:
        """Unit tangents at local arc length ``u`` [mm], shape=(n, 3)."""
        u = np.atleast_1d(np.asarray(u, dtype=float))
        if self.kind is SegmentKind.LINE:
            return np.repeat(self.direction[None, :], u.size, axis=0)
        t0, n = self._arc_frame()
        th = u / self.radius_mm
        return np.cos(th)[:, None] * t0[None, :] + np.sin(th)[:, None] * n[None, :]

    @property
    def end_F(self) -> np.ndarray:
        return self.point([self.length_mm])[0]


def flange_to_tool(points_F, design: RodDesign) -> np.ndarray:
    """Convert points from the flange frame {F} to the tool frame {T} [mm]."""
    return np.asarray(points_F, dtype=float) - design.tool_mm


def layout(design: RodDesign) -> list[Segment]:
    """Segments of ``design`` from the flange face to the ball's flat seat, in order.

    The ball itself (a rigid, truncated sphere centred on the tool point) is not a segment; the part
    of the centreline inside the ball is rigid.
    """
    d = design
    segs: list[Segment] = []
    ez = np.array([0.0, 0.0, 1.0])
    u2 = d.pipe_II_direction
    tube1 = Layer(Part.PIPE_I, d.pipe_I.material, d.pipe_I.outer_diameter_mm, d.pipe_I.inner_diameter_mm)
    tube2 = Layer(Part.PIPE_II, d.pipe_II.material, d.pipe_II.outer_diameter_mm, d.pipe_II.inner_diameter_mm)

    def add_line(start, direction, length, layers):
        if length <= 1e-12:
            return start
        s0 = segs[-1].s0_mm + segs[-1].length_mm if segs else 0.0
        seg = Segment(SegmentKind.LINE, s0, float(length), np.asarray(start, float), np.asarray(direction, float),
                      tuple(layers))
        segs.append(seg)
        return seg.end_F

    p = np.zeros(3)
    # pipe I: holder, free tube, ring 1
    ph = d.pipe_holder
    if ph.present:
        p = add_line(p, ez, ph.length_mm,
                     [tube1, Layer(Part.PIPE_HOLDER, ph.material, ph.outer_diameter_mm, d.pipe_I.outer_diameter_mm)])
    p = add_line(p, ez, d.pipe_I_free_mm(), [tube1])
    if d.rings.present:
        p = add_line(p, ez, d.rings.length_mm,
                     [tube1, Layer(Part.RING_1, d.rings.material, d.rings.outer_diameter_mm, d.pipe_I.outer_diameter_mm)])
    # bend
    if d.has_bend:
        b = d.bend
        s0 = segs[-1].s0_mm + segs[-1].length_mm if segs else 0.0
        arc = Segment(SegmentKind.ARC, s0, b.radius_mm * d.deflection_rad, p.copy(), ez,
                      (Layer(Part.BEND, b.material, b.outer_diameter_mm, b.inner_diameter_mm),), b.radius_mm)
        segs.append(arc)
        p = arc.end_F
    # pipe II: ring 2, free tube; then the ball holder
    if d.rings.present:
        p = add_line(p, u2, d.rings.length_mm,
                     [tube2, Layer(Part.RING_2, d.rings.material, d.rings.outer_diameter_mm, d.pipe_II.outer_diameter_mm)])
    p = add_line(p, u2, d.pipe_II_free_mm(), [tube2])
    bh = d.ball_holder
    if bh.present:
        p = add_line(p, u2, d.plug_mm,
                     [tube2, Layer(Part.BALL_HOLDER, bh.material, d.pipe_II.inner_diameter_mm, 0.0)])
        seat = d.ball.radius_mm - d.seat_offset_mm   # the stud reaches into the ball's flat seat
        p = add_line(p, u2, bh.length_mm + seat, [Layer(Part.BALL_HOLDER, bh.material, bh.outer_diameter_mm, 0.0)])
    return segs
