"""Sparse SPD solves with one factorisation for many right-hand sides.

Backends, in order of preference (:func:`available_backend`; ``RODLAB_SPARSE_SOLVER`` forces one):

- ``pardiso``: Intel MKL PARDISO through ``pypardiso`` (a default dependency on x86-64; the MKL wheels come
  from pip, no system library). Rod 1#'s two half problems: METIS analysis ~0.7 s once, ~0.3 s per
  factorisation on 2 cores (docs/benchmarks/solvers.md).
- ``cholmod``: CHOLMOD through ``scikit-sparse`` built against a system SuiteSparse (``libsuitesparse-dev``);
  ~2x slower than PARDISO here, used when it is installed and PARDISO is not.
- ``superlu``: SciPy's SuperLU with a symmetric ordering, the last fallback (~10x slower than PARDISO).

:class:`PatternSolver` factorises several matrices of one sparsity pattern (the two half problems of a
mirror-symmetric rod differ only in which DOFs of the plane are held) with one fill-reducing analysis.
"""
from __future__ import annotations

import ctypes
import functools
import glob
import logging
import os
import site
import sys

import numpy as np
import scipy.sparse as sp

from rodlab.core.cores import usable_cores
from rodlab.core.enums import SolverBackend

from .errors import FeaError

__all__ = ["SolverBackend", "available_backend", "backend_available", "PatternSolver", "HeldSystem",
           "node_ordering", "SOLVER_ENV"]

log = logging.getLogger(__name__)

#: environment variable that forces a backend (``pardiso``, ``cholmod`` or ``superlu``)
SOLVER_ENV = "RODLAB_SPARSE_SOLVER"


#: pypardiso finds ``mkl_rt`` by a recursive glob over the whole environment (``sys.prefix/lib*/**``) at its
#: import and at every solver it makes: ~1 s each in a venv with the cad extra, five times per ``rodlab fea``
_MKL_RT_ENV = "PYPARDISO_MKL_RT"


def _point_pypardiso_at_mkl() -> None:
    """Tell pypardiso where the mkl wheel put ``mkl_rt`` (``sys.prefix/lib``, or the user site's; Windows
    ``Library/bin``), unless the user already did: the same library its glob would find first (the
    shortest path), found with one directory listing."""
    if os.environ.get(_MKL_RT_ENV):
        return
    for root in (sys.prefix, getattr(site, "USER_BASE", None) or ""):
        for sub in ("lib", "Lib", "Library/bin", "lib64"):
            hits = sorted(glob.glob(os.path.join(root, sub, "*mkl_rt*")), key=len)
            if hits:
                os.environ[_MKL_RT_ENV] = hits[0]
                return


def _pardiso_library():
    """pypardiso's handle on MKL's ``mkl_rt``, or None when either is missing."""
    _point_pypardiso_at_mkl()
    try:
        import pypardiso
        return pypardiso.PyPardisoSolver(mtype=2)
    except Exception as e:  # ImportError, or mkl_rt not found / not loadable
        log.debug("PARDISO unavailable: %s", e)
        return None


@functools.lru_cache(maxsize=1)
def _pardiso_loads() -> bool:
    """Whether PARDISO runs here (asked once per process: each try makes a solver)."""
    return _pardiso_library() is not None


def backend_available(backend: SolverBackend | str) -> bool:
    """Whether ``backend`` can run on this machine."""
    b = SolverBackend(backend)
    if b is SolverBackend.PARDISO:
        return _pardiso_loads()
    if b is SolverBackend.CHOLMOD:
        try:
            from sksparse.cholmod import cholesky  # noqa: F401
            return True
        except Exception:  # ImportError, or a broken shared library
            return False
    return True


def available_backend() -> str:
    """The fastest backend that runs here (``pardiso``, ``cholmod``, ``superlu``), or the one named by the
    environment variable ``RODLAB_SPARSE_SOLVER`` (an error when it cannot run)."""
    forced = os.environ.get(SOLVER_ENV, "").strip().lower()
    if forced:
        try:
            b = SolverBackend(forced)
        except ValueError:
            raise FeaError(f"{SOLVER_ENV}={forced!r} is not a solver; expected one of "
                           f"{', '.join(m.value for m in SolverBackend)}", key=SOLVER_ENV) from None
        if not backend_available(b):
            raise FeaError(f"{SOLVER_ENV}={forced!r}: that solver is not installed here; unset the variable or "
                           f"install it (pardiso: pip install pypardiso)", key=SOLVER_ENV)
        return b.value
    for b in SolverBackend:
        if backend_available(b):
            return b.value
    return SolverBackend.SUPERLU.value


def _superlu(Kc: sp.csc_matrix):
    from scipy.sparse.linalg import splu
    lu = splu(Kc, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return lambda B: lu.solve(np.asarray(B))


def _graph_ordering(G: sp.csc_matrix, backend: str) -> np.ndarray:
    """Fill-reducing ordering (new -> old) of a symmetric graph: METIS nested dissection (PARDISO's, or CHOLMOD's;
    CHOLMOD's AMD when it was built without METIS)."""
    if backend == SolverBackend.PARDISO:
        return _pardiso_graph_ordering(G)
    from sksparse.cholmod import CholmodError, analyze
    try:
        return np.asarray(analyze(G, ordering_method="nesdis").P(), dtype=np.int64)
    except CholmodError as e:
        log.info("nested-dissection ordering unavailable (%s); using AMD", e)
        return np.asarray(analyze(G, ordering_method="amd").P(), dtype=np.int64)


def _configured_pardiso(iparm: dict, perm: np.ndarray):
    """A PARDISO handle (:func:`_pardiso_library`) with ``iparm`` {index: value} set over zeros, ``iparm[0] = 1``
    (given) and one-based indices (``iparm[34] = 0``: pypardiso adds 1), and the permutation array ``perm``."""
    ps = _pardiso_library()
    if ps is None:
        raise FeaError("the PARDISO solver is not available (pip install pypardiso)", key="solver")
    ps.iparm[:] = 0
    ps.iparm[0] = 1
    ps.iparm[34] = 0
    for k, v in iparm.items():
        ps.iparm[k] = v
    ps.perm = perm
    return ps


def _pardiso_graph_ordering(G: sp.csc_matrix) -> np.ndarray:
    """PARDISO's METIS nested dissection of the graph ``G`` (symmetric pattern with its diagonal), new -> old:
    the analysis phase alone, on a diagonally dominant (SPD) matrix of that pattern, returning its permutation
    (``iparm[4] = 2``). The array PARDISO fills is the new -> old order (read as its inverse, rod 1#'s
    factorisation took 200x longer); ``test_pardiso_node_ordering_keeps_the_fill_low`` checks the fill."""
    n = G.shape[0]
    U = sp.triu(sp.csr_matrix(G), format="csr")
    U.sort_indices()
    U.data[:] = -1.0
    U.setdiag(np.diff(G.indptr).astype(np.float64) + 1.0)
    U = sp.csr_matrix(U)
    ps = _configured_pardiso({1: 2,         # METIS nested dissection
                              4: 2},        # return the permutation
                             np.zeros(n, dtype=np.int32))
    from pypardiso.pardiso_wrapper import PyPardisoError
    try:
        ps.set_phase(11)
        ps._call_pardiso(U, np.zeros((n, 1), order="F"))
    except PyPardisoError as e:
        raise FeaError(f"PARDISO could not order the mesh's vertex graph ({e}); set RODLAB_SPARSE_SOLVER=superlu "
                       f"to solve without it", key="solver") from e
    finally:
        ps.set_phase(-1)                      # release PARDISO's memory (this solver object is not used again)
        ps._call_pardiso(U, np.zeros((n, 1), order="F"))
    return ps.perm.astype(np.int64) - 1


def node_ordering(basis, backend: str | None = None):
    """A fill-reducing permutation of the nodes of ``basis`` (new -> old), shape=(basis.N,), or None when the
    backend orders the matrix itself (SuperLU).

    The mesh's vertices are ordered on the vertex graph (the tetrahedra's edges); each edge node of a P2 mesh is
    placed right after the earlier of its two end vertices, i.e. in the subdomain of an interior end vertex, in
    the separator when both ends are on it. Ordering nodes instead of the 3x larger DOF graph keeps each node's
    three DOFs together (larger supernodes); ordering the vertices only (~1/6 of a P2 mesh's nodes) costs ~0.03 s
    on rod 1# instead of ~0.3 s for METIS on the whole node graph, for ~7 % fewer factorisation flops. With
    PARDISO the vertex graph goes through its own METIS and the matrix, assembled in this order, is given to it
    as ordered: its analysis then skips METIS on the DOF graph (rod 1#: 0.19 s -> 0.07 s, the same fill).
    """
    backend = backend or available_backend()
    if backend not in (SolverBackend.CHOLMOD, SolverBackend.PARDISO):
        return None
    mesh = basis.mesh
    nv = mesh.nvertices
    edges = mesh.edges                                           # (2, n_edges) vertex pairs
    G = sp.coo_matrix((np.ones(edges.shape[1]), (edges[0], edges[1])), shape=(nv, nv))
    G = (G + G.T + sp.identity(nv)).tocsc()
    if basis.N == nv:                                            # P1: the nodes are the vertices
        return _graph_ordering(G, backend)
    ed = basis.element_dofs
    if basis.N != nv + edges.shape[1] or ed.shape[0] != 10 or not np.array_equal(ed[4:], nv + mesh.t2e):
        raise FeaError(f"node_ordering: expected a P1 or P2 tetrahedral basis, got {ed.shape[0]} nodes per "
                       f"element and {basis.N} nodes on {nv} vertices", key="mesh")
    pos = np.empty(nv)
    pos[_graph_ordering(G, backend)] = np.arange(nv)
    key = np.concatenate([pos, np.minimum(pos[edges[0]], pos[edges[1]]) + 0.5])
    return np.argsort(key, kind="stable").astype(np.int64)


class HeldSystem:
    """A symmetric matrix with some DOFs held at zero, without slicing: the held rows and columns are zeroed
    and get 1 on the diagonal (explicit zeros stay stored), so every variant shares ``K``'s sparsity pattern,
    index arrays and one data buffer. A right-hand side must be zero on the held DOFs; their solution is then
    zero.

    K : symmetric sparse matrix, shape=(n, n); its CSR arrays are used as CSC (the transpose, = K). Or, for
    CHOLMOD only, its upper triangle as CSR (:func:`~fea.stiffness_assembly.assemble_stiffness` ``upper=True``): read
    as CSC that is the lower triangle, the only part CHOLMOD reads.
    """

    def __init__(self, K: sp.spmatrix):
        K = sp.csr_matrix(K)
        if not K.has_sorted_indices:
            K.sort_indices()
        n = K.shape[0]
        self.K = K
        self._row = np.repeat(np.arange(n, dtype=K.indices.dtype), np.diff(K.indptr))
        diag = np.nonzero(self._row == K.indices)[0]
        if diag.size != n:
            raise ValueError(f"the matrix has {n - diag.size} rows without a stored diagonal entry")
        self._diag = diag
        self._data = np.empty_like(K.data)

    def _csc(self, data) -> sp.csc_matrix:
        return sp.csc_matrix((data, self.K.indices, self.K.indptr), shape=self.K.shape, copy=False)

    @property
    def pattern(self) -> sp.csc_matrix:
        """The full matrix as CSC (zero-copy)."""
        return self._csc(self.K.data)

    def matrix(self, held: np.ndarray) -> sp.csc_matrix:
        """The matrix with the DOFs ``held`` (bool, shape=(n,)) held; valid until the next call (shared buffer)."""
        d = self._data
        np.copyto(d, self.K.data)
        d[held[self._row] | held[self.K.indices]] = 0.0
        d[self._diag[held]] = 1.0
        return self._csc(d)


def _mkl_threads(libmkl) -> None:
    """Let MKL use every core this process may run on (or ``MKL_NUM_THREADS``): gmsh's mesher sets the
    process-wide OpenMP thread count to 1, which MKL would otherwise inherit (2x slower on 2 cores)."""
    try:
        n = int(os.environ.get("MKL_NUM_THREADS", "0")) or usable_cores()
    except ValueError:                                   # not a number: every core of the machine, as before
        n = os.cpu_count() or 1
    try:
        libmkl.MKL_Set_Num_Threads(max(1, n))
    except AttributeError:  # an MKL without the entry point: keep its default
        pass


def _pardiso_call(ps, phase: int, U: sp.csr_matrix, ia: np.ndarray, ja: np.ndarray, B: np.ndarray,
                  X: np.ndarray) -> int:
    """MKL's ``pardiso`` through pypardiso's handle ``ps`` (its ``pt``, ``iparm``, ``perm``, ``mtype``), as its
    ``_call_pardiso`` makes it, with the one-based index arrays ``ia``, ``ja`` of ``U`` given; ``B`` and ``X``
    Fortran-ordered (n, nrhs) float64. Returns PARDISO's error code (0: success)."""
    i32, f64 = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)
    error = ctypes.c_int32(0)
    ps._mkl_pardiso(ps.pt.ctypes.data_as(ctypes.POINTER(ps._pt_type[0])), ctypes.byref(ctypes.c_int32(1)),
                    ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(ps.mtype)),
                    ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(U.shape[0])),
                    U.data.ctypes.data_as(f64), ia.ctypes.data_as(i32), ja.ctypes.data_as(i32),
                    ps.perm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(B.shape[1])),
                    ps.iparm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(ps.msglvl)),
                    B.ctypes.data_as(f64), X.ctypes.data_as(f64), ctypes.byref(error))
    return int(error.value)


class _Pardiso:
    """MKL PARDISO for a real SPD matrix given by its upper triangle in CSR (the arrays of a CSC lower
    triangle, as :class:`HeldSystem` stores it, are exactly that). The symbolic analysis (METIS) is done
    once for the pattern; each :meth:`factor` is PARDISO's numerical phase only."""

    def __init__(self, pattern: sp.csc_matrix, natural: bool = False):
        n = pattern.shape[0]
        row = np.repeat(np.arange(n, dtype=np.int64), np.diff(pattern.indptr))
        self._keep = pattern.indices >= row                     # strictly the upper triangle (CSR rows)
        cols = pattern.indices[self._keep]
        ptr = np.concatenate([[0], np.cumsum(np.bincount(row[self._keep], minlength=n))])
        self._U = sp.csr_matrix((pattern.data[self._keep].astype(np.float64), cols, ptr), shape=pattern.shape)
        iparm = {1: 3,         # METIS nested dissection, OpenMP-parallel (0.5 s instead of 0.7 s on rod 1#)
                 9: 8,         # pivot perturbation 1e-8 (SPD: unused)
                 17: -1}       # report the factor's nonzeros
        if natural:            # already ordered (:func:`node_ordering`): the identity as the user's permutation
            iparm[4] = 1
        self._ps = ps = _configured_pardiso(iparm, np.arange(1, n + 1, dtype=np.int32) if natural
                                            else np.zeros(0, dtype=np.int32))
        ps._check_A(self._U)   # sorted indices, no empty rows, CSR (no transpose)
        # one-based index arrays made once (pypardiso's own call converts them on every phase: ~5 ms each time)
        self._ia = self._U.indptr.astype(np.int32) + 1
        self._ja = self._U.indices.astype(np.int32) + 1
        self._call(11, np.zeros((n, 1)))
        self.factor_nonzeros = int(ps.iparm[17])               # the analysis's count of the factor's nonzeros

    def _call(self, phase: int, B: np.ndarray) -> np.ndarray:
        _mkl_threads(self._ps.libmkl)
        vector = np.ndim(B) == 1
        B = np.asfortranarray(B[:, None] if vector else B, dtype=np.float64)
        X = np.zeros_like(B)
        error = _pardiso_call(self._ps, phase, self._U, self._ia, self._ja, B, X)
        if error:
            raise FeaError(f"PARDISO failed in phase {phase} (error {error}); the stiffness matrix is singular or not "
                           f"positive definite: is every part connected to the clamp?", key="solver")
        return np.ascontiguousarray(X[:, 0] if vector else X)

    def factor(self, A: sp.spmatrix):
        Ac = sp.csc_matrix(A)
        self._U.data[:] = Ac.data[self._keep]
        self._call(22, np.zeros((Ac.shape[0], 1)))
        return lambda B: self._call(33, np.asarray(B))

    def __del__(self):
        try:
            self._ps.set_phase(-1)
            self._ps._call_pardiso(self._U, np.zeros((self._U.shape[0], 1), order="F"))
        except Exception:  # interpreter shutdown: nothing to release
            pass


class PatternSolver:
    """Factorise matrices that share one sparsity pattern with one fill-reducing analysis (done once by
    CHOLMOD or PARDISO; each :meth:`factor` reuses it and, for CHOLMOD after the first, the factor's
    memory). ``factor(A)`` returns ``solve(B)``, valid until the next ``factor`` call.

    PARDISO and CHOLMOD read one triangle only: ``pattern`` and every ``A`` may hold just the lower triangle
    as CSC (:func:`~fea.stiffness_assembly.assemble_stiffness` ``upper=True``); SuperLU needs the whole matrix."""

    def __init__(self, pattern: sp.spmatrix, backend: str | None = None, ordering_method: str = "amd"):
        self.backend = SolverBackend(backend or available_backend()).value
        self._symbolic = None
        self._factor = None
        self._pardiso = None
        if self.backend == SolverBackend.CHOLMOD:
            from sksparse.cholmod import analyze
            # "natural" for a matrix already ordered (:func:`node_ordering`); AMD on the DOF graph otherwise
            self._symbolic = analyze(sp.csc_matrix(pattern), ordering_method=ordering_method)
        elif self.backend == SolverBackend.PARDISO:
            self._pardiso = _Pardiso(sp.csc_matrix(pattern), natural=ordering_method == "natural")

    @property
    def factor_nonzeros(self) -> int | None:
        """The number of nonzeros of the factor, as PARDISO's analysis counts them (the fill a fill-reducing
        ordering keeps low), or None for the other backends."""
        return self._pardiso.factor_nonzeros if self._pardiso is not None else None

    def factor(self, A: sp.spmatrix):
        if self._pardiso is not None:
            return self._pardiso.factor(A)
        Ac = sp.csc_matrix(A)
        if self.backend != SolverBackend.CHOLMOD:
            return _superlu(Ac)
        if self._factor is None:
            self._factor = self._symbolic.cholesky(Ac)
        else:
            self._factor.cholesky_inplace(Ac)
        f = self._factor
        return lambda B: f(np.asarray(B))
