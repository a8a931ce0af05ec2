"""What the solid model can do on a mesh's connectivity before the mesh is finished.

gmsh makes an order-2 mesh straight first and then curves it: places the edge nodes on the CAD surfaces and
optimises them (rod 1#: ~0.15-0.3 s with the scikit-fem mesh made after it). The node ordering, the assembly plan
(:class:`~fea.stiffness_assembly.AssemblyPlan`) and PARDISO's or CHOLMOD's symbolic analysis depend on the
connectivity only, which the straight tetrahedra (:class:`~rodlab.core.fem_mesh.LinearTopology`) already fix:
:func:`solve_ahead` does that work meanwhile, when the mesher hands them over (:class:`rodlab.geometry.MeshPrefetch`
for ``rodlab fea --model solid``). The finished mesh uses it only after a check: the plan block by block against its
basis (:meth:`~fea.plan_cache.PlanCache.plan`), the analysis against the assembled matrix's pattern
(:meth:`SolveAhead.solver_for`); anything that does not match is made again.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from rodlab.core.fem_mesh import LinearTopology

from .plan_cache import plan_for
from .solver import PatternSolver, SolverBackend, available_backend
from .stiffness_assembly import AssemblyPlan, plan_matrix

__all__ = ["SolveAhead", "solve_ahead", "topology_plan", "plan_pattern"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class _TopologyDofs:
    """What a plan reads of a scalar P2 (or P1) basis, from the straight tetrahedra alone: the mesh's topology
    (``nvertices``, ``edges``, ``t2e``), ``element_dofs`` (vertices, then ``nvertices`` + the element's edges) and
    ``N``, as scikit-fem numbers them on the finished mesh."""

    mesh: object
    element_dofs: np.ndarray
    N: int


def topology_plan(topology: LinearTopology, order: int = 2, backend: str | None = None) -> AssemblyPlan:
    """The plan (:func:`~fea.plan_cache.plan_for`) of the order-``order`` mesh whose straight tetrahedra are
    ``topology``: the plan the finished mesh's basis gives, as the node numbering depends on the vertices alone."""
    from skfem import ElementTetP1, ElementTetP2  # heavy: scikit-fem (~0.2 s), loaded by the solver anyway
    from skfem.assembly import Dofs

    from rodlab.core.skfem_tet import MeshTet1Keyed  # heavy: skfem (scikit-fem, ~0.2 s)

    mesh = MeshTet1Keyed(np.zeros((3, topology.n_vertices)), topology.t)
    dofs = Dofs(mesh, ElementTetP2() if order == 2 else ElementTetP1())
    return plan_for(_TopologyDofs(mesh, dofs.element_dofs, int(dofs.N)), backend)


def plan_pattern(plan: AssemblyPlan) -> sp.csr_matrix:
    """The sparsity pattern of the matrix :func:`~fea.stiffness_assembly.assemble_stiffness` makes with ``plan``
    (every entry of each stored 3x3 block, ones), shape=(3N, 3N)."""
    return plan_matrix(plan, np.ones((plan.n_blocks, 3, 3)))


@dataclass
class SolveAhead:
    """The work done on the straight tetrahedra: the assembly ``plan`` and, for PARDISO and CHOLMOD, the
    ``solver`` with its symbolic analysis of the plan's pattern (None for SuperLU, which analyses as it factorises),
    the pattern's CSR ``indptr`` and ``indices`` (None without an analysis); ``seconds``: the time it took (beside
    the mesher)."""

    plan: AssemblyPlan
    solver: PatternSolver | None
    indptr: np.ndarray | None
    indices: np.ndarray | None
    seconds: float

    def solver_for(self, K: sp.spmatrix) -> PatternSolver | None:
        """The solver analysed ahead, when ``K`` (CSR, as assembled) has the pattern it was analysed for; else
        None (the caller analyses ``K``), and the analysis is let go (PARDISO's memory)."""
        if self.solver is None or self.indptr is None:
            return None
        same = np.array_equal(K.indptr, self.indptr) and np.array_equal(K.indices, self.indices)
        if same:
            return self.solver
        log.warning("the solver's analysis made from the straight mesh does not fit the matrix; analysing again")
        self.solver = None
        return None


def solve_ahead(topology: LinearTopology, backend: str | None = None) -> SolveAhead:
    """The plan of the order-2 mesh whose straight tetrahedra are ``topology``, and the solver's symbolic analysis
    of its pattern (:class:`SolveAhead`)."""
    t0 = time.perf_counter()
    backend = SolverBackend(backend or available_backend()).value
    plan = topology_plan(topology, 2, backend)
    solver = indptr = indices = None
    if plan.node_order is not None:                      # PARDISO, CHOLMOD: analysed in this (natural) order
        pattern = plan_pattern(plan)
        solver = PatternSolver(pattern.T, backend, ordering_method="natural")
        indptr, indices = pattern.indptr, pattern.indices     # the ones of its data let go
    return SolveAhead(plan, solver, indptr, indices, time.perf_counter() - t0)
