"""The rod's parts built directly in gmsh's own OpenCASCADE kernel, for the mesh.

The same solids as :mod:`geometry.parts` (build123d), from the same :func:`rodlab.core.layout.layout`: tubes and
sleeves annular cylinders along straight segments, the bend pipe an annulus revolved about the bend axis, the
ball holder's layers fused, the ball a sphere truncated by its seat. Building them in gmsh skips build123d's
import (~2 s of ``rodlab fea --model solid``) and the BREP round trip through files; the CAD exports (STEP,
STL, views) still use build123d. ``tests/test_geometry.py`` checks that both kernels give the same part
volumes.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.layout import Layer, Segment, SegmentKind, layout

from .errors import GeometryError

__all__ = ["add_part_volumes"]

#: parts that must not overlap (a bend that folds pipe II back onto pipe I), as in :mod:`geometry.parts`
_FAR = {Part.PIPE_HOLDER: [Part.PIPE_II, Part.BALL_HOLDER, Part.BALL, Part.RING_2],
        Part.PIPE_I: [Part.PIPE_II, Part.BALL_HOLDER, Part.BALL],
        Part.RING_1: [Part.PIPE_II, Part.BALL_HOLDER, Part.BALL]}


def _annulus(occ, layer: Layer, seg: Segment, offset_T: np.ndarray) -> list:
    start = seg.start_F + offset_T
    axis = np.asarray(seg.direction, float) * seg.length_mm
    outer = occ.addCylinder(*start, *axis, layer.d_out_mm / 2.0)
    if layer.d_in_mm <= 0:
        return [(3, outer)]
    inner = occ.addCylinder(*start, *axis, layer.d_in_mm / 2.0)
    out, _ = occ.cut([(3, outer)], [(3, inner)])
    return out


def _arc(occ, layer: Layer, seg: Segment, offset_T: np.ndarray) -> list:
    """The bend pipe: an annulus in the start plane revolved about the bend axis (parallel to y)."""
    start = seg.start_F + offset_T
    t0 = np.asarray(seg.direction, float)
    n = np.array([t0[2], 0.0, -t0[0]])                  # towards the bend centre
    centre = start + seg.radius_mm * n
    r_out = layer.d_out_mm / 2.0
    face = [(2, occ.addDisk(*start, r_out, r_out, zAxis=list(t0), xAxis=list(n)))]
    if layer.d_in_mm > 0:
        r_in = layer.d_in_mm / 2.0
        hole = [(2, occ.addDisk(*start, r_in, r_in, zAxis=list(t0), xAxis=list(n)))]
        face, _ = occ.cut(face, hole)
    out = occ.revolve(face, *centre, 0.0, 1.0, 0.0, seg.length_mm / seg.radius_mm)
    return [dt for dt in out if dt[0] == 3]


def _ball(occ, design: RodDesign, offset_T: np.ndarray) -> list:
    r = design.ball.radius_mm
    c = np.asarray(design.tool_mm, float) + offset_T
    ball = [(3, occ.addSphere(*c, r))]
    zc = design.seat_offset_mm
    if r - zc > 1e-9:
        u = -np.asarray(design.pipe_II_direction, float)
        cut = occ.addCylinder(*(c + zc * u), *(r * u), r)
        ball, _ = occ.cut(ball, [(3, cut)])
    return ball


def _build(occ, design: RodDesign) -> dict:
    offset_T = -np.asarray(design.tool_mm, float)          # {F} -> {T}
    pieces: dict[Part, list] = {}
    for seg in layout(design):
        for layer in seg.layers:
            make = _arc if seg.kind is SegmentKind.ARC else _annulus
            pieces.setdefault(layer.part, []).extend(make(occ, layer, seg, offset_T))
    pieces[Part.BALL] = _ball(occ, design, offset_T)
    out = {}
    for part in Part:
        if part not in pieces:
            continue
        items = pieces[part]
        if len(items) > 1:
            items, _ = occ.fuse(items[:1], items[1:])
        out[part] = items
    return out


def _check_clearances(occ, design: RodDesign, parts: dict) -> None:
    for a, others in _FAR.items():
        for b in others:
            if a not in parts or b not in parts:
                continue
            common, _ = occ.intersect(parts[a], parts[b], removeObject=False, removeTool=False)
            vol = sum(occ.getMass(d, t) for d, t in common if d == 3)
            if common:
                occ.remove(common, recursive=True)
            if vol > 1e-6:
                raise GeometryError(
                    f"design {design.name!r}: {b} overlaps {a} ({vol:.1f} mm^3): with gamma = "
                    f"{design.gamma_deg:g} deg the far end of the rod folds back onto the flange end; increase "
                    f"gamma_deg or L1_mm, shorten L2_mm, or make {a} smaller", key="gamma_deg")


def _halve(occ, parts: dict) -> dict:
    """Each part cut to the half-space ``y_T >= 0``."""
    big = 1e4
    out = {}
    for part, dts in parts.items():
        box = occ.addBox(-big, 0.0, -big, 2 * big, big, 2 * big)
        cut, _ = occ.intersect(dts, [(3, box)])
        cut = [dt for dt in cut if dt[0] == 3]
        if not cut:
            raise GeometryError(f"part {part} has nothing on the side y_T >= 0 of its bend plane", key=str(part))
        out[part] = cut
    return out


def add_part_volumes(design: RodDesign, half: bool = False) -> dict:
    """Build every present part in the current gmsh model's OCC kernel (not yet synchronised, not
    fragmented): {Part: [(3, tag), ...]} in {T} [mm], in :class:`~rodlab.core.enums.Part` order; ``half``: only
    ``y_T >= 0``. Raises :class:`~geometry.errors.GeometryError` for impossible geometry or parts that
    overlap."""
    import gmsh

    occ = gmsh.model.occ
    try:
        parts = _build(occ, design)
    except GeometryError:
        raise
    except Exception as e:  # OCC raises bare exceptions for impossible geometry
        raise GeometryError(f"design {design.name!r}: the CAD kernel could not build the parts ({e}); "
                            f"check the dimensions of the bend and the tubes") from e
    _check_clearances(occ, design, parts)
    return _halve(occ, parts) if half else parts
