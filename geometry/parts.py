"""build123d solids of each part of a rod, placed in the tool frame {T} from the shared layout.

Every solid is built from :func:`rodlab.core.layout.layout`, so the CAD places the parts exactly as
the analytic mass properties and the closed form do: tubes and sleeves are annular cylinders
along straight segments, the bend pipe is an annulus revolved about the bend centre, the ball
holder is a solid stud (with its plug in pipe II's bore), the ball a sphere truncated by its seat.
"""
from __future__ import annotations

import math

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.layout import Layer, Segment, SegmentKind, layout

from .cadlib import build123d
from .errors import GeometryError

__all__ = ["part_solids", "half_solids", "PART_COLOURS", "part_colours"]

#: RGB colours of the parts in STEP files and renderings.
PART_COLOURS: dict[Part, tuple[float, float, float]] = {
    Part.PIPE_HOLDER: (0.62, 0.64, 0.70),
    Part.PIPE_I: (0.15, 0.15, 0.17),
    Part.RING_1: (0.80, 0.80, 0.84),
    Part.BEND: (0.55, 0.57, 0.60),
    Part.RING_2: (0.80, 0.80, 0.84),
    Part.PIPE_II: (0.15, 0.15, 0.17),
    Part.BALL_HOLDER: (0.70, 0.72, 0.78),
    Part.BALL: (0.95, 0.93, 0.86),
}

#: RGB colours of a tube by its material's kind (the first name prefix that matches), so that a steel pipe I or an
#: aluminium pipe II is not drawn black like carbon (a new user's trial); other materials keep the part's colour
#: tube colours by material name (steel a blue-grey and aluminium a light silver, told apart in one rod: a designer
#: trial's steel bend had been the aluminium tubes' grey)
_MATERIAL_COLOURS = (("cfrp", (0.15, 0.15, 0.17)), ("carbon", (0.15, 0.15, 0.17)), ("steel", (0.45, 0.50, 0.60)),
                     ("al_", (0.80, 0.81, 0.84)), ("ti_", (0.58, 0.56, 0.53)))


def part_colours(design) -> dict:
    """RGB colour of each part of ``design`` [0-1]: the tubes (pipes I, II and the bend) by their material's kind
    (carbon dark, steel and aluminium metallic; an anisotropic material not named so, a user's laminate, as
    carbon), the sleeves, holders and ball in :data:`PART_COLOURS` (their shades tell them apart)."""
    out = dict(PART_COLOURS)
    for part in (Part.PIPE_I, Part.BEND, Part.PIPE_II):
        default = PART_COLOURS[part]
        m = design.material_of(part)
        name = m.name.lower()
        found = next((rgb for prefix, rgb in _MATERIAL_COLOURS if name.startswith(prefix)), None)
        if found is None and m.E_transverse_GPa is not None and m.E_transverse_GPa < 0.5 * m.E_GPa:
            found = _MATERIAL_COLOURS[0][1]
        out[part] = found or default
    return out


def _annulus_solid(bd, layer: Layer, seg: Segment, offset_T: np.ndarray):
    """An annular (or solid) cylinder along a straight segment."""
    start = seg.start_F + offset_T
    plane = bd.Plane(origin=tuple(start), z_dir=tuple(seg.direction))
    outer = bd.Solid.make_cylinder(layer.d_out_mm / 2.0, seg.length_mm, plane)
    if layer.d_in_mm > 0:
        outer = outer - bd.Solid.make_cylinder(layer.d_in_mm / 2.0, seg.length_mm, plane)
    return outer


def _arc_solid(bd, layer: Layer, seg: Segment, offset_T: np.ndarray):
    """The bend pipe: an annulus in the start plane revolved about the bend axis (parallel to y)."""
    start = seg.start_F + offset_T
    t0 = seg.direction
    n = np.array([t0[2], 0.0, -t0[0]])                  # towards the bend centre
    centre = start + seg.radius_mm * n
    plane = bd.Plane(origin=tuple(start), x_dir=tuple(n), z_dir=tuple(t0))
    face = bd.Face(bd.Wire.make_circle(layer.d_out_mm / 2.0, plane))
    if layer.d_in_mm > 0:
        face = face - bd.Face(bd.Wire.make_circle(layer.d_in_mm / 2.0, plane))
    angle = math.degrees(seg.length_mm / seg.radius_mm)
    axis = bd.Axis(tuple(centre), (0.0, 1.0, 0.0))       # right-handed about +y turns t0 towards n
    solid = bd.Solid.revolve(face, angle, axis)
    return solid


def _ball_solid(bd, design: RodDesign, offset_T: np.ndarray):
    r = design.ball.radius_mm
    ball = bd.Solid.make_sphere(r, bd.Plane(origin=tuple(design.tool_mm + offset_T)))
    zc = design.seat_offset_mm
    if r - zc > 1e-9:
        u = -design.pipe_II_direction
        cut_plane = bd.Plane(origin=tuple(design.tool_mm + offset_T + zc * u), z_dir=tuple(u))
        ball = ball - bd.Solid.make_cylinder(r, r, cut_plane)
    return ball


def part_solids(design: RodDesign) -> dict[Part, "object"]:
    """Solids of every present part, in {T} [mm], keyed by :class:`~rodlab.core.enums.Part`.

    Several layout layers of one part (a sleeve over two segments, the ball holder's plug and stud)
    are fused into one solid.
    """
    bd = build123d()

    offset_T = -design.tool_mm          # {F} -> {T}
    pieces: dict[Part, list] = {}
    try:
        for seg in layout(design):
            for layer in seg.layers:
                if seg.kind is SegmentKind.ARC:
                    solid = _arc_solid(bd, layer, seg, offset_T)
                else:
                    solid = _annulus_solid(bd, layer, seg, offset_T)
                pieces.setdefault(layer.part, []).append(solid)
        pieces[Part.BALL] = [_ball_solid(bd, design, offset_T)]
    except Exception as e:  # OCC raises bare exceptions for impossible geometry
        raise GeometryError(f"design {design.name!r}: the CAD kernel could not build the parts ({e}); "
                            f"check the dimensions of the bend and the tubes") from e
    out = {}
    for part in Part:
        if part not in pieces:
            continue
        items = pieces[part]
        solid = items[0] if len(items) == 1 else bd.Solid.fuse(*items).clean()
        if isinstance(solid, bd.Compound) and len(solid.solids()) == 1:
            solid = solid.solids()[0]
        out[part] = solid
    _check_clearances(design, out)
    return out


def _check_clearances(design: RodDesign, solids: dict) -> None:
    """Parts that should not touch must not overlap (a bend that folds pipe II back onto pipe I)."""
    far = {Part.PIPE_HOLDER: [Part.PIPE_II, Part.BALL_HOLDER, Part.BALL, Part.RING_2],
           Part.PIPE_I: [Part.PIPE_II, Part.BALL_HOLDER, Part.BALL],
           Part.RING_1: [Part.PIPE_II, Part.BALL_HOLDER, Part.BALL]}
    for a, others in far.items():
        if a not in solids:
            continue
        for b in others:
            if b not in solids:
                continue
            common = solids[a].intersect(solids[b])
            vol = 0.0 if common is None else sum(s.volume for s in common.solids())
            if vol > 1e-6:
                raise GeometryError(
                    f"design {design.name!r}: {b} overlaps {a} ({vol:.1f} mm^3): with gamma = "
                    f"{design.gamma_deg:g} deg the far end of the rod folds back onto the flange end; increase "
                    f"gamma_deg or L1_mm, shorten L2_mm, or make {a} smaller", key="gamma_deg")


def half_solids(solids: dict) -> dict:
    """Each part cut to the half-space ``y_T >= 0``."""
    bd = build123d()

    big = 1e4
    keep = bd.Solid.make_box(2 * big, big, 2 * big, bd.Plane(origin=(-big, 0.0, -big)))
    out = {}
    for part, solid in solids.items():
        cut = solid.intersect(keep)
        pieces = [] if cut is None else cut.solids()
        if not pieces:
            raise GeometryError(f"part {part} has nothing on the side y_T >= 0 of its bend plane", key=str(part))
        out[part] = pieces[0] if len(pieces) == 1 else bd.Compound(pieces)
    return out
