"""Offscreen PNG views of a rod's CAD (isometric and the three planes) via :mod:`rodlab.core.render3d` (pyvista, the
renderer of ``rodlab view``, where it renders off-screen; else matplotlib)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.render3d import VIEWS, TriangleSet, pick_renderer, render_png

from .parts import part_colours

__all__ = ["render_views", "tessellate"]


def tessellate(solids: dict, tolerance_mm: float = 0.1):
    """Triangles of every part: dict part -> (vertices (n, 3), triangles (m, 3))."""
    out = {}
    for part, solid in solids.items():
        verts, tris = solid.tessellate(tolerance_mm, 0.2)
        out[part] = (np.array([[v.X, v.Y, v.Z] for v in verts]), np.array(tris, dtype=int))
    return out


def render_views(cad, out_dir: str | Path, prefix: str = "view", dpi: int = 130, renderer: str = "auto") -> list[Path]:
    """Write ``{prefix}_iso.png``, ``_xz.png``, ``_xy.png``, ``_yz.png`` into ``out_dir``; return the paths.
    ``renderer``: one of :data:`rodlab.core.render3d.RENDERERS`."""
    colours = part_colours(cad.design)
    sets = [TriangleSet(str(p), v, t, colours[p]) for p, (v, t) in tessellate(cad.solids).items()]
    d = cad.design
    renderer = pick_renderer(renderer)
    return [render_png(sets, Path(out_dir) / f"{prefix}_{name}.png", name, dpi=dpi, renderer=renderer,
                       title=f"rod {d.name}: L1 = {d.L1_mm:g} mm, L2 = {d.L2_mm:g} mm, gamma = {d.gamma_deg:g} deg"
                             f" — {name} view")
            for name in VIEWS]
