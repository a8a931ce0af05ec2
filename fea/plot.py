"""Deformed shape of a solid FEA result (scaled), rendered offscreen to PNG."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.render3d import TriangleSet, render_png

from .solid import mirror_displacements
from .stiffness_assembly import scalar_basis

__all__ = ["render_deformed", "LOAD_CASES"]

#: column of the displacement matrix -> description
LOAD_CASES = {0: "unit force +x_T on the ball", 1: "unit force +y_T on the ball", 2: "unit force +z_T on the ball",
              3: "self-weight, 1 g0 along +x_T", 4: "self-weight, 1 g0 along +y_T", 5: "self-weight, 1 g0 along +z_T"}

_PART_RGB = [(0.62, 0.64, 0.70), (0.2, 0.2, 0.24), (0.80, 0.80, 0.84), (0.55, 0.57, 0.60), (0.80, 0.80, 0.84),
             (0.2, 0.2, 0.24), (0.70, 0.72, 0.78), (0.95, 0.93, 0.86)]


def render_deformed(rod_mesh, U: np.ndarray, path: str | Path, case: int = 5, scale: float | None = None,
                    view: str = "xz", title: str = "", load_label: str | None = None) -> Path:
    """Draw the undeformed rod (translucent) and the deformed one, displacements ``U[:, case]`` x ``scale``.

    ``U`` has shape (3 N, 6) in the vector DOF numbering of :mod:`fea.stiffness_assembly` (on a half mesh: drawn
    with its mirror image); the default scale makes the largest displacement 10 % of the rod's size.
    """
    if rod_mesh.is_half:                                        # draw the whole rod
        whole = rod_mesh.mirrored()
        U, rod_mesh = mirror_displacements(rod_mesh, U, whole), whole
    mesh = rod_mesh.mesh
    basis = scalar_basis(mesh)
    bf = mesh.boundary_facets()
    tri = mesh.facets[:, bf].T                                  # vertex indices
    elem = mesh.f2t[0, bf]
    vdof = basis.nodal_dofs[0]                                  # scalar DOF of each vertex
    u = U[:, case].reshape(-1, 3)[vdof]                         # (n_vertices, 3)
    p = mesh.doflocs[:, :vdof.size].T                           # vertices come first in skfem's numbering
    size = np.ptp(p, axis=0).max()
    umax = np.linalg.norm(u, axis=1).max()
    if scale is None:
        scale = 0.1 * size / umax if umax > 0 else 1.0
    sets = [TriangleSet("undeformed", p, tri, (0.6, 0.6, 0.6), alpha=0.25)]
    for k, part in enumerate(rod_mesh.parts):
        sel = rod_mesh.part_index[elem] == k
        if sel.any():
            sets.append(TriangleSet(str(part), p + scale * u, tri[sel], _PART_RGB[k % len(_PART_RGB)]))
    note = (f"{load_label or LOAD_CASES[case]}; displacements x {scale:.3g} (largest {umax * 1e3:.2f} um"
            f"{' per N' if case < 3 else ''})")
    return render_png(sets, path, view, title=title or "deformed shape", note=note)
