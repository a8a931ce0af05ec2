"""3-D views of FEA fields for the reports: the field file (``.vtu`` of the solid model, ``.vtp`` of the frame's
centreline) written, then one picture per load case (:func:`rodlab.core.view3d.render_view`). Where pyvista is
absent or cannot render off-screen a report goes on without them (said in the log and in the returned note)."""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodlab.fea.fields import solid_fields, write_solid_fields, write_frame_fields
from ...core.design import RodDesign
from ...core.view3d import RenderError, read_field_view, render_view

__all__ = ["FieldViews", "solid_views", "frame_views", "render_field_pngs", "VIEW_LOADS"]

log = logging.getLogger(__name__)

#: the load cases a report shows: the three unit forces (the columns of C_F)
VIEW_LOADS = ("Fx", "Fy", "Fz")


@dataclass
class FieldViews:
    """The field file written, the pictures rendered from it (in :data:`VIEW_LOADS` order), and why there are
    none when rendering was impossible (empty when they were drawn)."""

    fields: Path
    pngs: list[Path] = field(default_factory=list)
    note: str = ""


def render_field_pngs(fields: str | Path, prefix: str | Path, loads=VIEW_LOADS, colour: str = "stress") -> list[Path]:
    """``PREFIX.3d_<load>.png`` for each load case of a field file (``loads="weakest"``: the unit force that
    moves the ball most); raises :class:`~rodlab.core.view3d.RenderError`."""
    view = read_field_view(fields)
    if loads == "weakest":
        loads = (VIEW_LOADS[int(np.argmax(np.linalg.norm(view.ball_displacement[:3], axis=1)))],)
    return [render_view(view, f"{prefix}.3d_{load}.png", load=load, colour=colour) for load in loads]


def _render(fields: Path, prefix: Path, colour: str, loads=VIEW_LOADS) -> FieldViews:
    try:
        return FieldViews(fields, render_field_pngs(fields, prefix, loads, colour))
    except RenderError as e:
        log.warning("no 3-D views of %s: %s", fields, e)
        return FieldViews(fields, [], str(e))


def solid_views(design: RodDesign, result, fields: str | Path, prefix: str | Path | None = None) -> FieldViews:
    """Write the solid ``result``'s fields (solved with ``keep_displacements``) to ``fields`` (``.vtu``) and
    render them, coloured by von Mises stress, to ``prefix_<load>.png`` (default: beside the field file)."""
    path = write_solid_fields(fields, solid_fields(design, result))
    return _render(path, Path(prefix) if prefix else path.with_suffix(""), "stress")


def frame_views(design: RodDesign, fields: str | Path, prefix: str | Path | None = None, loads=VIEW_LOADS) -> FieldViews:
    """The frame model's centreline fields (``.vtp``) and their pictures (``loads``: load cases, or
    ``"weakest"``), coloured by the sections' outer-fibre von Mises stress (from the beam's section forces)."""
    path = write_frame_fields(fields, design)
    return _render(path, Path(prefix) if prefix else path.with_suffix(""), "stress", loads)
