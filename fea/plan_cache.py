"""A per-user cache of assembly plans: a rerun of ``rodlab fea`` on a cached mesh skips the node ordering and the
block pattern (rod 1#'s default half mesh: ~0.05 s of a ~0.8 s command).

A plan (:class:`~fea.stiffness_assembly.AssemblyPlan`: the fill-reducing node ordering and where every element
block goes in the ordered, triangular matrix) depends only on the mesh's connectivity and the solver backend. The
key is the SHA-256 of the mesh's own hash (nodes and connectivity), the node and element counts, the backend, the
sources of the ``fea`` package, the versions of NumPy, scikit-fem, the MKL wheel and scikit-sparse (PARDISO's or
CHOLMOD's METIS orders the graph), and :data:`PLAN_REVISION`. An entry is a NumPy ``.npz`` of plain arrays, read
without pickle and only when the user owns it; before it is used it is checked against the mesh, block by block
(:func:`_fits`): one that cannot be read or is not this mesh's plan is made again and replaced. Files are written
atomically; the folder (``plans`` in :func:`rodlab.core.cache.cache_root`) is pruned to :data:`MAX_BYTES`, least
recently used first.

A first run's plan can be made before its mesh is finished (:mod:`fea.ahead`, from the straight tetrahedra while
gmsh curves them): :meth:`PlanCache.plan` takes it (``made``) after the same check against the finished mesh.
"""
from __future__ import annotations

import hashlib
import io
import json
import logging
from functools import lru_cache
from pathlib import Path

import numpy as np

from rodlab.core.cache import cache_subfolder, code_digest, load, store

from .solver import SolverBackend, available_backend, node_ordering
from .stiffness_assembly import AssemblyPlan, assembly_plan, upper_pairs

__all__ = ["PlanCache", "PLAN_REVISION", "MAX_BYTES", "plan_for"]

log = logging.getLogger(__name__)

#: raise when a plan changes for a reason the key cannot see
PLAN_REVISION = 2
#: the folder's size limit [bytes] (rod 1#'s default half mesh: ~6 MB a plan)
MAX_BYTES = 200_000_000
_ARRAYS = ("brow", "bcol", "local", "slot")


def plan_for(basis, backend: str | None = None) -> AssemblyPlan:
    """The assembly plan of ``basis`` for ``backend`` (made anew, uncached): PARDISO and CHOLMOD get the matrix in
    a fill-reducing node ordering and store its upper block triangle; SuperLU the whole matrix as numbered."""
    backend = SolverBackend(backend or available_backend())
    return assembly_plan(basis, node_ordering(basis, backend.value), upper=backend is not SolverBackend.SUPERLU)


@lru_cache(maxsize=1)
def _code_and_versions() -> str:
    return code_digest(__name__, dists=("numpy", "scikit-fem", "mkl", "scikit-sparse"))


class PlanCache:
    """Assembly plans kept on disk: ``PlanCache().plan(basis, mesh_sha256, backend)`` reads the plan of that mesh
    and backend, or makes (:func:`plan_for`), stores and returns it. ``folder=None`` keeps nothing; ``hits`` /
    ``misses`` count calls, ``ahead`` the plans made beforehand that were used."""

    def __init__(self, folder: Path | str | None = "default") -> None:
        self.folder = cache_subfolder("plans") if folder == "default" else (Path(folder) if folder else None)
        self.hits = self.misses = self.ahead = 0

    def key(self, basis, mesh_sha256: str, backend: str) -> str:
        """The SHA-256 naming the plan of the mesh ``mesh_sha256`` (its basis ``basis``) for ``backend``."""
        text = json.dumps({"mesh": mesh_sha256, "nodes": int(basis.N), "elements": int(basis.dx.shape[0]),
                           "backend": backend, "code": _code_and_versions(), "revision": PLAN_REVISION}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()

    def plan(self, basis, mesh_sha256: str, backend: str | None = None, made: AssemblyPlan | None = None) -> AssemblyPlan:
        """The plan of ``basis`` (the mesh whose hash is ``mesh_sha256``) for ``backend`` (default: the one that
        runs here): from the cache when an entry there is this mesh's plan (:func:`_fits`), else ``made`` (a plan
        made beforehand for ``backend``, :func:`fea.ahead.solve_ahead`) when it is this mesh's, else made anew; stored."""
        backend = SolverBackend(backend or available_backend()).value
        if self.folder is None or not mesh_sha256:
            return self._made_or_new(basis, backend, made)
        path = self.folder / f"{self.key(basis, mesh_sha256, backend)}.npz"
        found = self._read(path, basis)
        if found is not None:
            self.hits += 1
            log.info("assembly plan from the cache (%s)", path)
            return found
        self.misses += 1
        plan = self._made_or_new(basis, backend, made)
        self._write(path, plan)
        return plan

    def _made_or_new(self, basis, backend: str, made: AssemblyPlan | None) -> AssemblyPlan:
        if made is not None:
            if _fits(made, basis):
                self.ahead += 1
                return made
            log.warning("the assembly plan made from the straight mesh does not fit the finished one; making it again")
        return plan_for(basis, backend)

    def _read(self, path: Path, basis) -> AssemblyPlan | None:
        return load(path, lambda p: _unpack(p, basis.N), lambda plan: _fits(plan, basis), "assembly plan")

    def _write(self, path: Path, plan: AssemblyPlan) -> None:
        buf = io.BytesIO()
        order = plan.node_order if plan.node_order is not None else np.zeros(0, dtype=np.int64)
        np.savez(buf, brow=plan.brow, bcol=plan.bcol, local=plan.local, slot=plan.slot, node_order=order,
                 upper=np.array(plan.upper))
        store(path, buf.getvalue(), "*.npz", MAX_BYTES, "assembly plan")


def _unpack(path: Path, n_nodes: int) -> AssemblyPlan:
    """The plan stored in ``path`` (plain arrays, no pickle)."""
    with np.load(path, allow_pickle=False) as z:
        arrays = {k: z[k] for k in (*_ARRAYS, "node_order", "upper")}
    order = arrays["node_order"]
    return AssemblyPlan(int(n_nodes), order if order.size else None, bool(arrays["upper"]), *(arrays[k] for k in _ARRAYS))


def _fits(plan: AssemblyPlan, basis) -> bool:
    """Whether ``plan`` is the plan of ``basis``'s mesh: integer arrays of the right shapes, the node order a
    permutation, the stored blocks distinct, row-major sorted (and on or above the diagonal with ``upper``), and
    every element block (a, b) it scatters pointing at the block (node a, node b) of the new numbering. A damaged
    or foreign file whose arrays still load is then never used (~10 ms on rod 1#)."""
    nloc, ne = basis.element_dofs.shape
    n, nb = basis.N, plan.n_blocks
    m = nloc * (nloc + 1) // 2 if plan.upper else nloc * nloc
    arrays = (plan.brow, plan.bcol, plan.local, plan.slot) + (() if plan.node_order is None else (plan.node_order,))
    if (not all(np.issubdtype(a.dtype, np.integer) for a in arrays) or plan.slot.shape != (ne, m)
            or plan.brow.ndim != 1 or nb == 0):
        return False
    if plan.node_order is not None and not np.array_equal(np.sort(plan.node_order), np.arange(n)):
        return False
    if not (((plan.slot >= 0) & (plan.slot < nb)).all() and ((plan.local >= 0) & (plan.local < nloc * nloc)).all()
            and ((plan.brow >= 0) & (plan.brow < n) & (plan.bcol >= 0) & (plan.bcol < n)).all()):
        return False
    key = plan.brow.astype(np.int64) * n + plan.bcol
    if not (np.diff(key) > 0).all() or (plan.upper and not (plan.brow <= plan.bcol).all()):
        return False
    new = np.arange(n) if plan.node_order is None else np.argsort(plan.node_order)    # old -> new node
    ed = new[basis.element_dofs.T]                                                    # (ne, nloc), new numbering
    local = plan.local.astype(np.intp)
    if plan.upper:                                  # column t is the pair upper_pairs()[t], either way round
        ia, ib = upper_pairs(nloc)
        lo, hi = np.minimum(local // nloc, local % nloc), np.maximum(local // nloc, local % nloc)
        if not (np.array_equal(lo, np.broadcast_to(ia, lo.shape)) and np.array_equal(hi, np.broadcast_to(ib, hi.shape))):
            return False
    a = np.take_along_axis(ed, local // nloc, axis=1)
    b = np.take_along_axis(ed, local % nloc, axis=1)
    return bool(np.array_equal(plan.brow[plan.slot], a) and np.array_equal(plan.bcol[plan.slot], b))
