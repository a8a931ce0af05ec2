"""3-D solid FEA of a rod: C_F and C_g (paper Eqs. 16, 18) with scikit-fem on the geometry mesh.

- One material per part; carbon transversely isotropic about the local tube axis (also along the bend).
- Clamp: every DOF on ``flange_face`` fixed.
- Tip force: a unit force *at the ball centre*, introduced as a body-force field on the (stiff, ceramic)
  ball whose resultant is the force and whose moment about the ball centre is zero, so the load is
  statically a point force at the centre without constraints (the system stays SPD).
- Ball-centre displacement: a least-squares rigid-body fit ``u = t + theta x (x - 0)`` of the ball's
  nodes ({T} origin = ball centre), ``t`` is the centre's displacement.
- C_g: self-weight of every part, 1 g0 along x, y, z of {T}.
- One factorisation serves all six load cases (one per symmetry class on a half mesh, below).
- A half mesh (``RodMesh.is_half``: ``y_T >= 0`` of a rod mirror-symmetric about its bend plane) is solved as
  two half-size problems sharing one ordering: loads in the plane (F_x, F_z, g_x, g_z) with ``u_y = 0`` on the
  plane, loads across it (F_y, g_y) with ``u_x = u_z = 0`` there. Same answer as the mirrored whole mesh
  (~5e-9 relative, tested to 1e-7) in about half the solve time of the whole mesh (rod 1#: 5.2 s vs 9.9 s).
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.units import G0, kg_m3_to_kg_mm3

from .ahead import SolveAhead
from .plan_cache import PlanCache
from .stiffness_assembly import assemble_body_force, assemble_stiffness, scalar_basis, scalar_element
from .elasticity import element_tensors
from .error_estimate import node_basis, recovery_error_matrix
from .errors import FeaError
from .solver import HeldSystem, PatternSolver, available_backend

__all__ = ["SolidResult", "solve_compliance", "mirror_displacements", "section_rigid_motion", "mirror_nodes",
           "ANTISYMMETRIC_CASES"]

log = logging.getLogger(__name__)

#: load cases (columns F_x, F_y, F_z, g_x, g_y, g_z and, with ``tip_moments``, M_x, M_y, M_z) across the bend
#: plane y_T = 0: antisymmetric fields (F_y, g_y; the moments about x and z are pseudo-vectors: M_x, M_z)
ANTISYMMETRIC_CASES = (1, 4, 6, 8)
_FLIP = {False: np.array([1.0, -1.0, 1.0]), True: np.array([-1.0, 1.0, -1.0])}  # image of (u_x, u_y, u_z)


@dataclass
class SolidResult:
    """Compliance from one solid solve.

    C_F [mm/N] and C_g [mm/g0], shape=(3, 3), in {T}; ``symmetry_defect`` = max|C_F - C_F^T| / max|C_F|;
    ``dofs``; ``timings_s`` per stage; ``backend`` of the linear solver; ``mass_kg`` of the mesh;
    ``ball_rotation`` [rad per unit load], shape=(3, n_cases); ``displacements`` (optional, shape=(3N, n_cases),
    on the mesh solved: the half for a half mesh, see :func:`mirror_displacements`); ``mass_kg`` is the whole
    rod's. ``n_cases`` = 6 (F_x, F_y, F_z [N], g_x, g_y, g_z [g0]), or 9 with ``tip_moments`` (+ M_x, M_y, M_z
    [N mm] about the ball centre); ``ball_motion`` = ball-centre translation [mm] and rotation [rad] per unit
    load, shape=(6, n_cases); ``error_matrix`` (with ``error_estimate``) the recovery estimate of the
    compliance's discretisation error between the load cases, shape=(n_cases, n_cases), exact minus computed
    (:func:`fea.error_estimate.recovery_error_matrix`: C_F's error is ``[:3, :3]``, C_g's ``[:3, 3:6]``).
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
    ball_motion: np.ndarray | None = None
    error_matrix: np.ndarray | None = None


def _rigid_fit(X: np.ndarray, U: np.ndarray):
    """Least-squares rigid motion of points X (n, 3) with displacements U (n, 3, k): returns t (3, k), theta (3, k).

    About the points' centroid ``c`` the translation and rotation decouple (``sum r = 0``): the centroid moves by
    the mean displacement and ``J theta = sum r x u`` with ``J = sum (|r|^2 I - r r^T)``; then ``t = t_c - theta x c``.
    (A 6-column ``lstsq`` of the same problem took ~45 ms in LAPACK's SVD for a ball's ~700 nodes.)"""
    c = X.mean(axis=0)
    r = X - c                                                    # (n, 3)
    t_c = U.mean(axis=0)                                         # (3, k)
    J = np.eye(3) * (r * r).sum() - r.T @ r
    moment = np.cross(r[:, :, None], U, axis=1).sum(axis=0)     # sum r x u, (3, k)
    theta = np.linalg.solve(J, moment)
    return t_c - np.cross(theta, c[:, None], axis=0), theta


def _ball_loads(x_q: np.ndarray, w: np.ndarray, half: bool, moments: bool = False):
    """Body-force densities on the ball (quadrature points ``x_q`` (3, nb, nq) [mm], weights ``w`` (nb, nq)) whose
    resultant is a unit force along x, y, z and whose moment about the ball centre (the {T} origin) is zero;
    with ``moments`` three more: zero resultant, a unit moment [N mm] about x, y, z (``omega x (x - c)``,
    ``J omega = e_j``). A half ball's volume, centroid and inertia are those of the whole ball (the half and its
    mirror image)."""
    pts = [(x_q, w)] + ([(x_q * np.array([1.0, -1.0, 1.0])[:, None, None], w)] if half else [])
    V = sum(ww.sum() for _, ww in pts)
    c = sum((xx * ww).sum(axis=(1, 2)) for xx, ww in pts) / V    # the seat shifts it off the centre
    J = np.zeros((3, 3))
    for xx, ww in pts:
        r = xx - c[:, None, None]
        J += np.eye(3) * ((r * r).sum(0) * ww).sum() - np.einsum("ieq,jeq,eq->ij", r, r, ww)
    r = x_q - c[:, None, None]
    out = []
    for j in range(3):
        F = np.eye(3)[j]
        omega = -np.linalg.solve(J, np.cross(c, F))         # cancels the moment of F/V about the centre
        out.append(F[:, None, None] / V + np.cross(omega[:, None, None], r, axis=0))
    for j in range(3 if moments else 0):
        omega = np.linalg.solve(J, np.eye(3)[j])
        out.append(np.cross(omega[:, None, None], r, axis=0))
    return out


def solve_compliance(design: RodDesign, rod_mesh, keep_displacements: bool = False,
                     backend: str | None = None, tip_moments: bool = False, error_estimate: bool = False,
                     plans: PlanCache | None = None, ahead: SolveAhead | None = None) -> SolidResult:
    """Solve the six load cases on ``rod_mesh`` (a :class:`geometry.RodMesh` of ``design``, whole or half);
    ``tip_moments`` adds three unit moments at the ball centre (columns 6-8; same factorisations), which the
    joint fit of the frame model needs (:mod:`fea.joints`); ``error_estimate`` adds the stress-recovery
    estimate of the discretisation error (``SolidResult.error_matrix``, from this solve alone); ``plans``: where
    the mesh's assembly plan (node ordering, block pattern) is kept between runs (:class:`~fea.plan_cache.PlanCache`;
    None makes it anew); ``ahead``: the plan and the solver's analysis made from the mesh's straight tetrahedra
    while it was curved (:func:`~fea.ahead.solve_ahead`), each used where it fits this mesh."""
    t0 = time.perf_counter()
    timings = {}
    half = rod_mesh.is_half
    basis = scalar_basis(rod_mesh.mesh)
    materials = [design.material_of(p) for p in rod_mesh.parts]
    C = element_tensors(materials, rod_mesh.part_index, rod_mesh.tube_axis)
    timings["basis_and_materials"] = time.perf_counter() - t0
    t1 = time.perf_counter()
    backend = backend or available_backend()
    plan = (plans or PlanCache(None)).plan(basis, rod_mesh.sha256, backend, made=ahead.plan if ahead else None)
    plan_ahead = ahead is not None and plan is ahead.plan
    nodes = plan.node_order                                # None: the solver orders (SuperLU)
    timings["ordering"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    # in the solver's numbering; CHOLMOD and PARDISO read one triangle only: half the memory
    K = assemble_stiffness(basis, C, plan=plan)
    del plan
    timings["assembly"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    n_cases = 9 if tip_moments else 6
    loads, mass = _load_cases(basis, rod_mesh, materials, n_cases)
    timings["loads"] = time.perf_counter() - t1
    analysed = ahead.solver_for(K) if plan_ahead else None
    used_ahead = plan_ahead and (analysed is not None or ahead.indptr is None)
    U, solver_backend = _clamped_solve(basis, rod_mesh, K, loads, backend, nodes, timings, analysed)
    del K
    # ball-centre displacement
    ball = np.nonzero(rod_mesh.part_index == rod_mesh.parts.index(Part.BALL))[0]
    bdofs = np.unique(basis.element_dofs[:, ball])
    X = basis.doflocs[:, bdofs].T
    t, theta = section_rigid_motion(X, U[(3 * bdofs[:, None] + np.arange(3)).ravel()], half)
    CF = t[:, :3]
    Cg = t[:, 3:6]
    defect = float(np.abs(CF - CF.T).max() / np.abs(CF).max())
    E = None
    if error_estimate:
        t1 = time.perf_counter()
        E = _recovery_estimate(rod_mesh, C, U)
        timings["error_estimate"] = time.perf_counter() - t1
    timings["total"] = time.perf_counter() - t0
    if used_ahead:
        timings["ahead_beside_mesher"] = ahead.seconds       # not in the total: done while the mesh was curved
    log.info("solid FEA %s: %d DOFs%s, %s, %s", design.name, U.shape[0], " (half mesh, two solves)" if half else "",
             solver_backend, ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    return SolidResult(CF, Cg, defect, U.shape[0], mass, timings, solver_backend, theta,
                       U if keep_displacements else None, rod_mesh, np.vstack([t, theta]), E)


def _recovery_estimate(rod_mesh, C: np.ndarray, U: np.ndarray) -> np.ndarray:
    """The recovery estimate of the error between the load cases (:mod:`fea.error_estimate`)."""
    nodes = node_basis(rod_mesh.mesh, scalar_element(rod_mesh.mesh), doflocs=False)
    return recovery_error_matrix(nodes, C, rod_mesh.part_index, U, rod_mesh.is_half, ANTISYMMETRIC_CASES)


def _load_cases(basis, rod_mesh, materials, n_cases: int) -> tuple[np.ndarray, float]:
    """Load vectors (mesh numbering, shape=(3N, n_cases)): unit forces at the ball centre, self-weight of 1 g0
    along x, y, z, and (9 cases) unit moments at the ball centre; and the rod's mass [kg] (the whole rod's
    on a half mesh)."""
    half = rod_mesh.is_half
    N = int(3 * basis.N)
    dens = np.array([kg_m3_to_kg_mm3(m.density_kg_m3) for m in materials])[rod_mesh.part_index]
    ne, nq = basis.dx.shape
    loads = np.zeros((N, n_cases))
    ball = np.nonzero(rod_mesh.part_index == rod_mesh.parts.index(Part.BALL))[0]
    x_q = basis.mapping.F(basis.X, tind=ball)               # (3, nb, nq) the ball's quadrature points
    on_ball = np.stack(_ball_loads(x_q, basis.dx[ball], half, n_cases == 9))   # (3 or 6, 3, nb, nq)
    loads[:, [j if j < 3 else j + 3 for j in range(on_ball.shape[0])]] = assemble_body_force(basis, on_ball, ball)
    weight = np.zeros((3, 3, ne, nq))
    for j in range(3):
        weight[j, j] = (dens * G0)[:, None]
    loads[:, 3:6] = assemble_body_force(basis, weight)
    mass = float((basis.dx * dens[:, None]).sum()) * (2.0 if half else 1.0)
    return loads, mass


def _clamped_solve(basis, rod_mesh, K, loads: np.ndarray, backend, nodes, timings: dict,
                   analysed: PatternSolver | None = None) -> tuple[np.ndarray, str]:
    """Clamp the flange face and solve every load case (``K`` in the solver's numbering ``nodes``): one
    problem, or on a half mesh the symmetric and the antisymmetric half with the plane held accordingly;
    ``analysed``: a solver already analysed for ``K``'s pattern.
    Returns the displacements (mesh numbering, shape of ``loads``) and the solver backend used; adds the
    analyse / factorise / solve times to ``timings``."""
    t1 = time.perf_counter()
    N, n_cases = loads.shape
    # solver numbering -> mesh numbering of the DOFs
    dof = np.arange(N) if nodes is None else (3 * nodes[:, None] + np.arange(3)).ravel()
    fixed_scalar = basis.get_dofs(rod_mesh.flange_facets).all()
    if fixed_scalar.size == 0:
        raise FeaError("the flange face has no DOFs to clamp; the mesh lost its flange_face", key="flange_face")
    fixed = np.zeros(N, dtype=bool)
    fixed[(3 * fixed_scalar[:, None] + np.arange(3)).ravel()] = True
    system = HeldSystem(K)                                  # clamp and plane held in place: no sliced copies
    solver = analysed or PatternSolver(system.pattern, backend, ordering_method="amd" if nodes is None else "natural")
    timings["analyze"] = time.perf_counter() - t1
    if rod_mesh.is_half:
        plane = basis.get_dofs(rod_mesh.symmetry_facets).all()
        anti = [k for k in ANTISYMMETRIC_CASES if k < n_cases]
        groups = [([k for k in range(n_cases) if k not in anti], [1]), (anti, [0, 2])]   # (cases, held comps)
    else:
        plane = np.zeros(0, dtype=np.int64)
        groups = [(list(range(n_cases)), [])]
    U = np.zeros((N, n_cases))
    timings["factorize"] = timings["solve"] = 0.0
    for cases, comps in groups:
        held = fixed.copy()
        held[(3 * plane[:, None] + np.asarray(comps, dtype=np.int64)).ravel()] = True
        held = held[dof]
        t1 = time.perf_counter()
        solve = solver.factor(system.matrix(held))
        timings["factorize"] += time.perf_counter() - t1
        t1 = time.perf_counter()
        B = loads[np.ix_(dof, cases)]
        B[held] = 0.0
        U[np.ix_(dof, cases)] = solve(B)
        timings["solve"] += time.perf_counter() - t1
    return U, solver.backend


def _flips(n_cases: int) -> np.ndarray:
    """Image of (u_x, u_y, u_z) across y_T = 0 for each load case's field, shape=(3, n_cases)."""
    return np.stack([_FLIP[k in ANTISYMMETRIC_CASES] for k in range(n_cases)], axis=1)


def mirror_nodes(X: np.ndarray, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes of a half mesh and their mirror images about y_T = 0: positions ``X`` shape=(n, 3) [mm] and
    displacements ``U`` shape=(3 n, n_cases) -> shapes (2 n, 3) and (2 n, 3, n_cases), each load case's
    field symmetric or antisymmetric (:data:`ANTISYMMETRIC_CASES`)."""
    n_cases = U.shape[1]
    Ub = U.reshape(len(X), 3, n_cases)
    return np.concatenate([X, X * _FLIP[False]]), np.concatenate([Ub, Ub * _flips(n_cases)])


def section_rigid_motion(X: np.ndarray, U: np.ndarray, half: bool):
    """Least-squares rigid motion of a set of nodes: positions ``X`` shape=(n, 3) [mm] in {T}, displacements
    ``U`` shape=(3 n, n_cases) (x, y, z per node) -> translation of the {T} origin [mm] and rotation [rad],
    each shape=(3, n_cases). On a half mesh the nodes' mirror images count too."""
    if half:
        X, Ub = mirror_nodes(X, U)
    else:
        Ub = U.reshape(len(X), 3, U.shape[1])
    return _rigid_fit(X, Ub)


def mirror_displacements(rod_mesh, U: np.ndarray, whole) -> np.ndarray:
    """Displacements ``U`` (3 N_half, n_cases) of a half mesh carried onto ``whole = rod_mesh.mirrored()``
    (3 N_whole, n_cases): each node takes its own value (y_T >= 0) or its image's, flipped as its load case's field
    is symmetric or antisymmetric about ``y_T = 0``."""
    from scipy.spatial import cKDTree

    xh, xw = scalar_basis(rod_mesh.mesh, intorder=1).doflocs, scalar_basis(whole.mesh, intorder=1).doflocs
    dist, src = cKDTree(xh.T).query((xw * np.array([[1.0], [-1.0], [1.0]]) ** (xw[1] < 0)).T)
    if dist.max() > 1e-6 * np.ptp(xh).max():
        raise FeaError("the whole mesh is not the mirror image of the half mesh", key="whole")
    n_cases = U.shape[1]
    Uw = U.reshape(-1, 3, n_cases)[src]
    Uw[xw[1] < 0] *= _flips(n_cases)
    return Uw.reshape(-1, n_cases)
