"""Offscreen orthographic rendering of coloured triangle sets to PNG: matplotlib (no OpenGL) or pyvista.

matplotlib: a painter's algorithm, flat Lambert shading, triangles sorted back to front, equal axes in mm, a
legend; runs anywhere. pyvista (``renderer="pyvista"``, the ``viz`` extra; the renderer of ``rodlab view``,
:mod:`rodlab.core.view3d`): smooth-shaded OpenGL, the same views, parts and legend. ``renderer="auto"`` takes
pyvista where it renders off-screen, else matplotlib. Used for the CAD views and the FEA deformed shapes.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .fileio import atomic_write_figure
from .view3d import RenderError, check_offscreen, render_triangle_sets

__all__ = ["TriangleSet", "VIEWS", "RENDERERS", "render_png", "pick_renderer"]

#: triangle-set renderers: auto (pyvista where it renders off-screen, else matplotlib), matplotlib, pyvista
RENDERERS = ("auto", "matplotlib", "pyvista")

#: name -> (direction from the scene towards the camera, up vector, axis labels or None)
VIEWS = {
    "iso": (np.array([1.0, -1.0, 0.8]), np.array([0.0, 0.0, 1.0]), None),
    "xz": (np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0]), ("x_T [mm]", "z_T [mm]")),
    "xy": (np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]), ("x_T [mm]", "y_T [mm]")),
    "yz": (np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), ("y_T [mm]", "z_T [mm]")),
}


@dataclass
class TriangleSet:
    """Triangles to draw: ``vertices`` shape=(n, 3) [mm], ``triangles`` shape=(m, 3) int, ``rgb`` in [0, 1],
    ``label`` for the legend, ``alpha`` opacity."""

    label: str
    vertices: np.ndarray
    triangles: np.ndarray
    rgb: tuple
    alpha: float = 1.0


def _camera(direction, up):
    w = direction / np.linalg.norm(direction)
    u = np.cross(up, w)
    if np.linalg.norm(u) < 1e-9:
        u = np.array([1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    return u, np.cross(w, u), w


def pick_renderer(renderer: str = "auto") -> str:
    """``matplotlib`` or ``pyvista`` for ``renderer`` (one of :data:`RENDERERS`); ``pyvista`` asked for where it
    cannot render raises :class:`rodlab.core.view3d.RenderError`."""
    if renderer not in RENDERERS:
        raise ValueError(f"renderer must be one of {', '.join(RENDERERS)}, got {renderer!r}")
    if renderer == "matplotlib":
        return renderer
    try:
        check_offscreen()
    except RenderError:
        if renderer == "pyvista":
            raise
        return "matplotlib"
    return "pyvista"


def render_png(sets: list[TriangleSet], path: str | Path, view: str = "iso", title: str = "",
               dpi: int = 130, note: str | None = None, renderer: str = "matplotlib") -> Path:
    """Render ``sets`` in ``view`` (a key of :data:`VIEWS`) to a PNG at ``path`` (written atomically) with
    ``renderer`` (:data:`RENDERERS`)."""
    if pick_renderer(renderer) == "pyvista":
        return render_triangle_sets(sets, path, VIEWS[view], title=title, note=note)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    direction, up, labels = VIEWS[view]
    u, v, w = _camera(direction, up)
    light = np.array([0.4, -0.5, 0.9]) / np.linalg.norm([0.4, -0.5, 0.9])
    polys, colours, depth = [], [], []
    for ts in sets:
        tri = ts.vertices[ts.triangles]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        nn = np.linalg.norm(n, axis=1)
        keep = nn > 1e-12
        tri, n = tri[keep], n[keep] / nn[keep, None]
        shade = 0.35 + 0.65 * np.abs(n @ light)
        rgba = np.empty((tri.shape[0], 4))
        rgba[:, :3] = np.clip(np.asarray(ts.rgb)[None, :] * shade[:, None], 0, 1)
        rgba[:, 3] = ts.alpha
        polys.append(np.stack([tri @ u, tri @ v], axis=-1))
        colours.append(rgba)
        depth.append((tri @ w).mean(axis=1))
    polys = np.concatenate(polys)
    colours = np.concatenate(colours)
    order = np.argsort(np.concatenate(depth))
    fig, ax = plt.subplots(figsize=(8, 6))
    ax.add_collection(PolyCollection(polys[order], facecolors=colours[order], edgecolors="none",
                                     antialiased=False))
    allp = polys.reshape(-1, 2)
    lo, hi = allp.min(0), allp.max(0)
    pad = 0.05 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    if labels:
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        ax.grid(True, lw=0.3, alpha=0.5)
    else:
        ax.set_axis_off()
    ax.set_title(title, fontsize=10)
    handles, seen = [], set()
    for ts in sets:
        if ts.label not in seen:
            seen.add(ts.label)
            handles.append(Patch(color=ts.rgb, alpha=ts.alpha, label=ts.label))
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), framealpha=0.8)
    if note:
        ax.text(0.0, -0.13 if labels else 0.0, note, transform=ax.transAxes, fontsize=8, va="top")
    return atomic_write_figure(path, fig, dpi, bbox_inches="tight")
