"""3-D solid FEA of a rod: C_F and C_g (paper Eqs. 16, 18) with scikit-fem on the geometry mesh.

- One material per part; carbon transversely isotropic about the local tube axis (also along the bend).
- Clamp: every DOF on ``flange_face`` fixed.
- Tip force: a unit force *at the ball centre*, introduced as a body-force field on the (stiff, ceramic)
  ball whose resultant is the force and whose moment about the ball centre is zero, so the load is
  statically a point force at the centre without constraints (the system stays SPD).
- Ball-centre displacement: a least-squares rigid-body fit ``u = t + theta x (x - 0)`` of the ball's
  nodes ({T} origin = ball centre), ``t`` is the centre's displacement.
- C_g: self-weight of every part, 1 g0 along x, y, z of {T}.
- One factorisation serves all six load cases.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from rodlab.design import RodDesign
from rodlab.enums import Part
from rodlab.units import G0, kg_m3_to_kg_mm3

from .assembly import assemble_body_force, assemble_stiffness, scalar_basis, vector_dofs
from .elasticity import element_tensors
from .errors import FeaError
from .solver import factorize

__all__ = ["SolidResult", "solve_compliance"]

log = logging.getLogger(__name__)


@dataclass
class SolidResult:
    """Compliance from one solid solve.

    C_F [mm/N] and C_g [mm/g0], shape=(3, 3), in {T}; ``symmetry_defect`` = max|C_F - C_F^T| / max|C_F|;
    ``dofs``; ``timings_s`` per stage; ``backend`` of the linear solver; ``mass_kg`` of the mesh;
    ``ball_rotation`` [rad per unit load], shape=(3, 6); ``displacements`` (optional, shape=(3N, 6)).
    """

    C_F: np.ndarray
    C_g: np.ndarray
    symmetry_defect: float
    dofs: int
    mass_kg: float
    timings_s: dict = field(default_factory=dict)
    backend: str = ""
    ball_rotation: np.ndarray | None = None
    displacements: np.ndarray | None = None
    rod_mesh: object | None = None


def _rigid_fit(X: np.ndarray, U: np.ndarray):
    """Least-squares rigid motion of points X (n, 3) with displacements U (n, 3, k): returns t (3, k), theta (3, k)."""
    n = X.shape[0]
    A = np.zeros((3 * n, 6))
    A[:, :3] = np.tile(np.eye(3), (n, 1))
    # theta x x = -[x]x theta
    sk = np.zeros((n, 3, 3))
    sk[:, 0, 1], sk[:, 0, 2] = X[:, 2], -X[:, 1]
    sk[:, 1, 0], sk[:, 1, 2] = -X[:, 2], X[:, 0]
    sk[:, 2, 0], sk[:, 2, 1] = X[:, 1], -X[:, 0]
    A[:, 3:] = sk.reshape(3 * n, 3)
    sol, *_ = np.linalg.lstsq(A, U.reshape(3 * n, -1), rcond=None)
    return sol[:3], sol[3:]


def solve_compliance(design: RodDesign, rod_mesh, keep_displacements: bool = False,
                     backend: str | None = None) -> SolidResult:
    """Solve the six load cases on ``rod_mesh`` (a :class:`geometry.RodMesh` of ``design``)."""
    t0 = time.perf_counter()
    timings = {}
    mesh = rod_mesh.mesh
    basis = scalar_basis(mesh)
    materials = [design.material_of(p) for p in rod_mesh.parts]
    C = element_tensors(materials, rod_mesh.part_index, rod_mesh.tube_axis)
    timings["basis_and_materials"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    K = assemble_stiffness(basis, C)
    timings["assembly"] = time.perf_counter() - t1
    N = int(3 * basis.N)

    # loads -------------------------------------------------------------------------------
    t1 = time.perf_counter()
    x_q = basis.mapping.F(basis.X)                          # (3, ne, nq) global quadrature points
    dens = np.array([kg_m3_to_kg_mm3(m.density_kg_m3) for m in materials])[rod_mesh.part_index]
    ne, nq = basis.dx.shape
    loads = np.zeros((N, 6))
    ball = np.nonzero(rod_mesh.part_index == rod_mesh.parts.index(Part.BALL))[0]
    w_ball = basis.dx[ball]                                 # (nb, nq)
    xb = x_q[:, ball, :]                                    # (3, nb, nq)
    V = w_ball.sum()
    c = (xb * w_ball).sum(axis=(1, 2)) / V                  # ball centroid (the seat shifts it off the centre)
    r = xb - c[:, None, None]
    J = np.einsum("ij,...->ij", np.eye(3), ((r * r).sum(0) * w_ball).sum()) - np.einsum("ieq,jeq,eq->ij", r, r,
                                                                                         w_ball)
    for j in range(3):
        F = np.eye(3)[j]
        omega = -np.linalg.solve(J, np.cross(c, F))         # cancels the moment of F/V about the centre
        f = np.zeros((3, ne, nq))
        f[:, ball, :] = F[:, None, None] / V + np.cross(omega[:, None, None], r, axis=0)
        loads[:, j] = assemble_body_force(basis, f)
        g = np.zeros((3, ne, nq))
        g[j] = (dens * G0)[:, None]
        loads[:, 3 + j] = assemble_body_force(basis, g)
    mass = float((basis.dx * dens[:, None]).sum())
    timings["loads"] = time.perf_counter() - t1

    # clamp and solve ---------------------------------------------------------------------
    t1 = time.perf_counter()
    fixed_scalar = basis.get_dofs(rod_mesh.flange_facets).all()
    if fixed_scalar.size == 0:
        raise FeaError("the flange face has no DOFs to clamp; the mesh lost its flange_face", key="flange_face")
    fixed = (3 * fixed_scalar[:, None] + np.arange(3)).ravel()
    free = np.setdiff1d(np.arange(N), fixed)
    Kff = K[free][:, free]
    solve, used = factorize(Kff, backend)
    timings["factorize"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    U = np.zeros((N, 6))
    U[free] = solve(loads[free])
    timings["solve"] = time.perf_counter() - t1

    # ball-centre displacement ----------------------------------------------------------------
    bdofs = np.unique(basis.element_dofs[:, ball])
    X = basis.doflocs[:, bdofs].T
    Ub = U[(3 * bdofs[:, None] + np.arange(3)).ravel()].reshape(len(bdofs), 3, 6)
    t, theta = _rigid_fit(X, Ub)
    CF = t[:, :3]
    Cg = t[:, 3:]
    defect = float(np.abs(CF - CF.T).max() / np.abs(CF).max())
    timings["total"] = time.perf_counter() - t0
    log.info("solid FEA %s: %d DOFs, %s, %s", design.name, N, used,
             ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    return SolidResult(CF, Cg, defect, N, mass, timings, used, theta,
                       U if keep_displacements else None, rod_mesh)
