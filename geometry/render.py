"""Offscreen PNG views of a rod (isometric and the three planes) with matplotlib.

A small painter's-algorithm renderer over the CAD tessellation: flat Lambert shading, triangles
sorted back to front, orthographic projection, equal axes in mm, a legend of the parts. It needs
no display and no OpenGL, so it runs on a headless rig PC or CI.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.fileio import atomic_write_bytes

from .parts import PART_COLOURS

__all__ = ["VIEWS", "render_views", "tessellate"]

#: name -> (view direction from the scene towards the camera, up vector, axis labels)
VIEWS = {
    "iso": (np.array([1.0, -1.0, 0.8]), np.array([0.0, 0.0, 1.0]), None),
    "xz": (np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0]), ("x_T [mm]", "z_T [mm]")),
    "xy": (np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0]), ("x_T [mm]", "y_T [mm]")),
    "yz": (np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), ("y_T [mm]", "z_T [mm]")),
}


def tessellate(solids: dict, tolerance_mm: float = 0.1):
    """Triangles of every part: dict part -> (vertices (n, 3), triangles (m, 3))."""
    out = {}
    for part, solid in solids.items():
        verts, tris = solid.tessellate(tolerance_mm, 0.2)
        out[part] = (np.array([[v.X, v.Y, v.Z] for v in verts]), np.array(tris, dtype=int))
    return out


def _camera(direction, up):
    w = direction / np.linalg.norm(direction)
    u = np.cross(up, w)
    if np.linalg.norm(u) < 1e-9:
        u = np.array([1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    return u, v, w


def render_views(cad, out_dir: str | Path, prefix: str = "view", dpi: int = 130) -> list[Path]:
    """Write ``{prefix}_iso.png``, ``_xz.png``, ``_xy.png``, ``_yz.png`` into ``out_dir``; return the paths."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    mesh = tessellate(cad.solids)
    light = np.array([0.4, -0.5, 0.9])
    paths = []
    for name, (direction, up, labels) in VIEWS.items():
        u, v, w = _camera(direction, up)
        polys, colours, depth = [], [], []
        for part, (verts, tris) in mesh.items():
            tri = verts[tris]                                    # (m, 3, 3)
            n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
            nn = np.linalg.norm(n, axis=1)
            keep = nn > 1e-12
            tri, n = tri[keep], n[keep] / nn[keep, None]
            facing = n @ w
            shade = 0.35 + 0.65 * np.abs(n @ (light / np.linalg.norm(light)))
            base = np.array(PART_COLOURS[part])
            col = np.clip(base[None, :] * shade[:, None] + 0.08 * (facing[:, None] < 0), 0, 1)
            polys.append(np.stack([tri @ u, tri @ v], axis=-1))
            colours.append(col)
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
        d = cad.design
        ax.set_title(f"rod {d.name}: L1 = {d.L1_mm:g} mm, L2 = {d.L2_mm:g} mm, gamma = {d.gamma_deg:g} deg "
                     f"— {name} view", fontsize=10)
        ax.legend(handles=[Patch(color=PART_COLOURS[p], label=str(p)) for p in mesh], fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0), framealpha=0.8)
        buf = io.BytesIO()
        fig.savefig(buf, dpi=dpi, bbox_inches="tight")
        plt.close(fig)
        paths.append(atomic_write_bytes(Path(out_dir) / f"{prefix}_{name}.png", buf.getvalue()))
    return paths
