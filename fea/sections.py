"""Beam kinematics of cross-sections of a solid FEA solution: where the joint fit cuts the rod.

A solid tube section does not move rigidly (shear warping, ovalisation, Poisson contraction). What a beam
model calls its motion is the centroid's translation and the plane sections' rotation; :func:`sectional_motion`
fits exactly those over a stretch of tube (polynomials along the axis, evaluated at the cut), so that the
solid's section motions are comparable with the frame's (:mod:`fea.joints`).
"""
from __future__ import annotations

import numpy as np

from rodlab.core.frames import skew as _skew
from rodlab.core.design import RodDesign
from rodlab.core.enums import Part

from .errors import FeaError
from .solid import mirror_nodes
from .stiffness_assembly import scalar_basis

__all__ = ["sectional_motion", "solid_section_motions"]


def sectional_motion(X: np.ndarray, U: np.ndarray, centre: np.ndarray, axis: np.ndarray,
                     degree: int = 3) -> np.ndarray:
    """Beam kinematics of a stretch of tube: ``u(x) = t(xi) + phi(xi) x rho`` fitted by least squares to nodes
    ``X`` shape=(n, 3) [mm] with displacements ``U`` shape=(n, 3, n_cases), where ``xi`` is the axial and
    ``rho`` the in-section position relative to ``centre`` and ``t``, ``phi`` are polynomials of ``degree``
    in ``xi``. Returns ``(t(0), phi(0))`` [mm, rad], shape=(6, n_cases).

    The rotation is the plane sections' (from the displacement *across* the section), the translation the
    centroid's, both at the cut itself: a rigid fit of the same nodes mixes in the slope along the axis,
    which differs from the section rotation by the shear strain, and depends on where the mesh's node layers
    fall (seen as 0.1-1 % noise in the calibrated members)."""
    t = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    rel = X - centre
    xi = rel @ t
    rho = rel - xi[:, None] * t
    scale = max(np.abs(xi).max(), 1e-9)
    powers = (xi / scale)[:, None] ** np.arange(degree + 1)                # (n, degree + 1)
    # u = sum_k p_k (t_k + phi_k x rho) = sum_k p_k (t_k - skew(rho) phi_k)
    n = len(X)
    A = np.zeros((n, 3, degree + 1, 6))
    A[:, :, :, :3] = powers[:, None, :, None] * np.eye(3)[None, :, None, :]
    A[:, :, :, 3:] = -powers[:, None, :, None] * _skew(rho)[:, :, None, :]
    sol, *_ = np.linalg.lstsq(A.reshape(3 * n, -1), U.reshape(3 * n, -1), rcond=None)
    return sol.reshape(degree + 1, 6, -1)[0]


def solid_section_motions(design: RodDesign, rod_mesh, U: np.ndarray, cuts, centres_F: np.ndarray,
                          axes: np.ndarray, reach_mm: dict[Part, float]) -> np.ndarray:
    """Section motion (:func:`sectional_motion`) at each cut ``(tube part, arc length [mm])`` with its centre
    ``centres_F`` [mm] in {F} and axis, shape=(n, 3) each, from the tube's nodes within ``reach_mm[part]`` of
    it; ``U`` shape=(3 N, n_cases) on ``rod_mesh`` (a :class:`rodlab.core.fem_mesh.RodMesh`, whole or half).
    Returns shape=(n_cuts, 6, n_cases) [mm, rad], {F} axes (= {T} axes)."""
    basis = scalar_basis(rod_mesh.mesh, intorder=1)
    X = basis.doflocs.T                                          # {T} [mm]
    out = []
    for (part, s_cut), p_F, t in zip(cuts, centres_F, axes):
        nodes = np.unique(basis.element_dofs[:, rod_mesh.elements_of(part)])
        centre = p_F - design.tool_mm
        xi = (X[nodes] - centre) @ t
        sel = nodes[np.abs(xi) <= reach_mm[part]]
        if sel.size < 30:
            raise FeaError(f"only {sel.size} mesh nodes near the section at s = {s_cut:.1f} mm of {part.value}: "
                           f"the mesh is too coarse for the joint calibration", key="size")
        Xs, Us = X[sel], U[(3 * sel[:, None] + np.arange(3)).ravel()]
        if rod_mesh.is_half:
            Xs, Us = mirror_nodes(Xs, Us)
        out.append(sectional_motion(Xs, Us.reshape(len(Xs), 3, -1), centre, t))
    return np.array(out)
