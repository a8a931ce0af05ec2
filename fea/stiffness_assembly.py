"""Vectorised assembly of linear elasticity on scikit-fem meshes with per-element stiffness tensors.

scikit-fem supplies the mesh, the Lagrange basis (shape functions, gradients, quadrature weights on
curved P2 elements) and the DOF numbering; the element matrices are contracted with batched BLAS:
``K_e[(a,i),(b,j)] = sum_q dx_q sum_kl dphi_a/dx_k C_ikjl dphi_b/dx_l``. Vector DOF numbering:
``3 * scalar_dof + component``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from rodlab.core.cores import in_parts

__all__ = ["scalar_element", "scalar_basis", "block_pattern", "AssemblyPlan", "assembly_plan", "assemble_stiffness",
           "assemble_body_force", "vector_dofs", "plan_matrix", "upper_pairs"]


def scalar_element(mesh):
    """The scalar Lagrange element of the mesh's order (P2 on MeshTet2, P1 on MeshTet1)."""
    from skfem import ElementTetP1, ElementTetP2, MeshTet2
    return ElementTetP2() if isinstance(mesh, MeshTet2) else ElementTetP1()


def scalar_basis(mesh, intorder: int | None = None):
    """The scalar Lagrange basis of the mesh's order (P2 on MeshTet2, P1 on MeshTet1)."""
    from .mapping import lagrange_basis  # heavy: skfem (fea.mapping imports scikit-fem, ~208 ms)
    elem = scalar_element(mesh)
    return lagrange_basis(mesh, elem, intorder=(3 if elem.maxdeg == 2 else 2) if intorder is None else intorder)


def vector_dofs(basis) -> np.ndarray:
    """Vector DOFs of every element, shape=(n_elements, n_local * 3), ordered (node a, component i)."""
    ed = basis.element_dofs.T                               # (ne, nloc)
    return (3 * ed[:, :, None] + np.arange(3)[None, None, :]).reshape(ed.shape[0], -1)


def block_pattern(basis):
    """Scalar (node) sparsity pattern: block rows and columns, shape=(nb,) each, row-major sorted, and for every
    (element, a, b) the index of its 3x3 block, shape=(ne, nloc, nloc).

    One sort of the element keys (``np.unique`` with ``return_inverse`` sorts again: ~3x slower here)."""
    ed = basis.element_dofs.T.astype(np.int64)                     # (ne, nloc)
    ne, nloc = ed.shape
    keys = (ed[:, :, None] * basis.N + ed[:, None, :]).ravel()
    order = np.argsort(keys)
    sk = keys[order]
    del keys
    first = np.empty(sk.size, dtype=bool)
    first[0] = True
    np.not_equal(sk[1:], sk[:-1], out=first[1:])
    uniq = sk[first]
    inv = np.empty(sk.size, dtype=np.int32 if uniq.size < 2**31 else np.int64)
    inv[order] = np.cumsum(first) - 1
    return uniq // basis.N, uniq % basis.N, inv.reshape(ne, nloc, nloc)


@dataclass(frozen=True)
class AssemblyPlan:
    """Where every element's 3x3 stiffness blocks go in the global matrix: a function of the mesh's connectivity,
    the node ordering and whether one triangle is stored (:func:`assembly_plan`; kept per mesh by
    :mod:`fea.plan_cache`).

    n_nodes : N, the nodes of the scalar basis (the matrix is 3N x 3N)
    node_order : shape=(N,) int, the matrix's numbering (new -> old node: node ``node_order[i]`` is node i, its DOFs
        ``3 i + c``), or None for the basis's own
    upper : only the blocks on and above the block diagonal are stored (the diagonal blocks whole)
    brow, bcol : shape=(nb,) int, block row and column of each stored block, row-major sorted
    local : shape=(ne, m) int, the element blocks that are stored, as ``a * nloc + b`` (all nloc^2 of them, or with
        ``upper`` the m = nloc (nloc + 1) / 2 whose nodes come in that order in the new numbering: column t holds
        the pair :func:`upper_pairs` ``(a_t, b_t)`` or its transpose, whichever is stored)
    slot : shape=(ne, m) int, the stored block each of them adds into
    """

    n_nodes: int
    node_order: np.ndarray | None
    upper: bool
    brow: np.ndarray
    bcol: np.ndarray
    local: np.ndarray
    slot: np.ndarray

    def __post_init__(self) -> None:
        fix = "make a plan with assembly_plan(basis, node_order, upper)"
        arrays = {"brow": self.brow, "bcol": self.bcol, "local": self.local, "slot": self.slot}
        if self.node_order is not None:
            arrays["node_order"] = self.node_order
        wrong = [k for k, a in arrays.items() if not np.issubdtype(np.asarray(a).dtype, np.integer)]
        if wrong:
            raise ValueError(f"AssemblyPlan: {', '.join(wrong)} must be integer arrays; {fix}")
        nb = self.brow.shape[0] if self.brow.ndim == 1 else -1
        if nb < 0 or self.bcol.shape != (nb,) or self.slot.ndim != 2 or self.local.shape != self.slot.shape:
            raise ValueError(f"AssemblyPlan: brow and bcol must have one shape (nb,), local and slot one shape "
                             f"(ne, m); got {self.brow.shape}, {self.bcol.shape}, {self.local.shape}, {self.slot.shape}; "
                             f"{fix}")
        if self.node_order is not None and self.node_order.shape != (self.n_nodes,):
            raise ValueError(f"AssemblyPlan: node_order must have shape ({self.n_nodes},), got {self.node_order.shape}; "
                             f"{fix}")

    @property
    def n_blocks(self) -> int:
        """The number of stored 3x3 blocks."""
        return int(self.brow.shape[0])


def assembly_plan(basis, node_order: np.ndarray | None = None, upper: bool = False) -> AssemblyPlan:
    """The :class:`AssemblyPlan` of ``basis``'s mesh in the numbering ``node_order`` (new -> old, or None), storing
    the upper block triangle only with ``upper`` (:func:`_upper_plan`: one sort of the stored pairs); else the
    :func:`block_pattern` renumbered."""
    if upper:
        return _upper_plan(basis, node_order)
    brow, bcol, inv = block_pattern(basis)
    ne, nloc = inv.shape[:2]
    inv = inv.reshape(ne, nloc * nloc)
    local = np.broadcast_to(np.arange(nloc * nloc, dtype=_local_dtype(nloc)), inv.shape)
    if node_order is not None:
        node_order = np.asarray(node_order, dtype=np.int64)
        iperm = np.empty_like(node_order)
        iperm[node_order] = np.arange(node_order.size, dtype=node_order.dtype)
        brow, bcol = iperm[brow], iperm[bcol]
        # every block's place in the final list (sorted row-major in the new numbering)
        order = np.argsort(brow.astype(np.int64) * basis.N + bcol)
        new = np.empty(brow.size, dtype=inv.dtype)
        new[order] = np.arange(order.size, dtype=inv.dtype)
        brow, bcol, inv = brow[order], bcol[order], new[inv]
    return AssemblyPlan(int(basis.N), node_order, False, brow, bcol, np.ascontiguousarray(local), inv)


def upper_pairs(nloc: int) -> tuple[np.ndarray, np.ndarray]:
    """The element's node pairs ``a <= b`` in a fixed order (``np.triu_indices``): the columns of an upper plan."""
    return np.triu_indices(nloc)


def _upper_plan(basis, node_order: np.ndarray | None) -> AssemblyPlan:
    """The plan storing the upper block triangle in the numbering ``node_order``: of each element's node pairs
    (:func:`upper_pairs`, the diagonal and one of each pair: ``nloc (nloc + 1) / 2``) the orientation whose new
    numbers come in order, their (row, column) sorted once, row-major (:func:`_row_major_order`: a radix sort on
    16-bit numbers, ~3x faster than sorting every pair's key and then renumbering the blocks)."""
    N = int(basis.N)
    ed = basis.element_dofs.T.astype(np.int64)                     # (ne, nloc)
    ne, nloc = ed.shape
    if node_order is not None:
        node_order = np.asarray(node_order, dtype=np.int64)
        iperm = np.empty_like(node_order)
        iperm[node_order] = np.arange(N, dtype=np.int64)
        ed = iperm[ed]
    ia, ib = upper_pairs(nloc)
    ea, eb = ed[:, ia], ed[:, ib]                                  # (ne, m)
    in_order = ea <= eb
    local = np.where(in_order, ia * nloc + ib, ib * nloc + ia).astype(_local_dtype(nloc))
    rows, cols = np.minimum(ea, eb).ravel(), np.maximum(ea, eb).ravel()
    order = _row_major_order(rows, cols, N)
    rows, cols = rows[order], cols[order]
    first = np.empty(order.size, dtype=bool)
    first[:1] = True
    np.logical_or(rows[1:] != rows[:-1], cols[1:] != cols[:-1], out=first[1:])
    slot = np.empty(order.size, dtype=np.int32 if order.size < 2**31 else np.int64)
    slot[order] = np.cumsum(first) - 1
    return AssemblyPlan(N, node_order, True, rows[first], cols[first], local, slot.reshape(ne, ia.size))


def _row_major_order(rows: np.ndarray, cols: np.ndarray, n: int) -> np.ndarray:
    """The permutation sorting the pairs (``rows``, ``cols``) row-major (stable): two radix passes when the
    numbers fit 16 bits (``n`` < 65536; numpy's stable sort of 16-bit integers is a radix sort), else one sort of
    the combined keys."""
    if n < 2**16:
        order = np.argsort(cols.astype(np.uint16), kind="stable")
        return order[np.argsort(rows[order].astype(np.uint16), kind="stable")]
    return np.argsort(rows * n + cols, kind="stable")


def _local_dtype(nloc: int):
    return np.int8 if nloc * nloc < 128 else np.int16


def assemble_stiffness(basis, C: np.ndarray, chunk: int = 2000, plan: AssemblyPlan | None = None,
                       node_order: np.ndarray | None = None, upper: bool = False) -> sp.csr_matrix:
    """Global stiffness [N/mm], shape=(3N, 3N), from element tensors C, shape=(ne, 3, 3, 3, 3).

    ``plan``: the basis's :class:`AssemblyPlan`, if already made; else one is made from ``node_order`` and
    ``upper``. ``node_order``: a fill-reducing node permutation, shape=(N,) (new -> old node): K is then assembled
    in that numbering (node ``node_order[i]`` becomes node i, its DOFs ``3 i + c``). ``upper``: only the 3x3 blocks
    on and above the block diagonal (the diagonal blocks whole): read as CSC, this is the lower triangle CHOLMOD
    and PARDISO factorise (they ignore the rest), in half the memory of the full matrix.

    Element blocks ``K_e[a, b]`` (3x3 per pair of nodes; the gradient products as one batched matrix product per
    chunk) are summed straight into their place in the final (ordered, optionally triangular) block list with
    ``bincount`` (with ``upper`` only the 55 of 100 that are stored), and the block matrix is expanded once
    (BSR -> CSR): ~10x less sorting than a COO build. ``chunk`` elements at a time (~15 MB of element matrices
    per 1000 elements): on a VM whose host backs guest memory lazily, fresh memory costs ~3-4 s per GB, so
    small chunks are faster as well as leaner. The elements are summed in two parts, in two threads where two
    cores are free (:func:`_summed_blocks`).
    """
    if plan is None:
        plan = assembly_plan(basis, node_order, upper)
    elif node_order is not None or upper:
        raise ValueError("assemble_stiffness: give a plan or node_order / upper, not both (the plan has its own); "
                         "make the plan with assembly_plan(basis, node_order, upper)")
    nloc = len(basis.basis)
    dx = basis.dx                                                  # (ne, nq)
    ne, nq = dx.shape
    widths = (nloc * (nloc + 1) // 2,) if plan.upper else (nloc * nloc,)
    if plan.n_nodes != basis.N or plan.slot.shape[0] != ne or plan.slot.shape[1] not in widths:
        raise ValueError(f"assemble_stiffness: the plan is for {plan.n_nodes} nodes and {plan.slot.shape[0]} elements "
                         f"of {plan.slot.shape[1]} blocks, the basis has {basis.N} nodes, {ne} elements of {nloc} nodes: "
                         f"make the plan with assembly_plan(basis)")
    # gradients as [e, (k, a), q]: the element's gradient products are one (3 nloc x nq) @ (nq x 3 nloc) product
    G = np.stack([basis.basis[a][0].grad for a in range(nloc)], axis=1).transpose(2, 0, 1, 3).reshape(ne, 3 * nloc, nq)
    blocks = _summed_blocks(G, dx, C, plan, chunk)
    return plan_matrix(plan, blocks.T.reshape(plan.n_blocks, 3, 3))


def plan_matrix(plan: AssemblyPlan, blocks: np.ndarray) -> sp.csr_matrix:
    """The matrix, shape=(3N, 3N), whose stored 3x3 blocks, shape=(n_blocks, 3, 3), go where ``plan`` puts them:
    BSR (rows of blocks sorted: the plan's keys are row-major) expanded once to CSR."""
    n = plan.n_nodes
    indptr = np.concatenate([[0], np.cumsum(np.bincount(plan.brow, minlength=n))])
    return sp.bsr_matrix((blocks, plan.bcol, indptr), shape=(3 * n, 3 * n)).tocsr()


def _summed_blocks(G: np.ndarray, dx: np.ndarray, C: np.ndarray, plan: AssemblyPlan, chunk: int) -> np.ndarray:
    """The stored 3x3 blocks, shape=(9, n_blocks): the elements' blocks summed into their slots, the elements in
    two parts (:func:`~rodlab.core.cores.in_parts`: two threads on two free cores, ~40 % less time) added in order."""
    sums = in_parts(G.shape[0], lambda lo, hi: _part_blocks(G, dx, C, plan, lo, hi, chunk))
    total = sums[0]
    for s in sums[1:]:
        total += s
    return total


def _part_blocks(G: np.ndarray, dx: np.ndarray, C: np.ndarray, plan: AssemblyPlan, lo: int, hi: int,
                 chunk: int) -> np.ndarray:
    """The blocks of elements ``lo:hi`` summed into the plan's slots, shape=(9, n_blocks), ``chunk`` elements at a
    time: ``K_e = C_e : (sum_q dx_q grad grad)`` as batched matrix products, then one ``bincount`` per component.
    An upper plan's blocks are those of :func:`upper_pairs`, each ``K_ab`` or, where the plan stores the pair the
    other way, ``K_ba = K_ab^T`` (its components ij read as ji): 55 of the 100 pairs computed, none gathered."""
    nloc = G.shape[1] // 3
    if plan.upper:
        ia, ib = upper_pairs(nloc)
        pairs = (slice(None), slice(None), ia, slice(None), ib)
    else:
        pairs = None
    nb = plan.n_blocks
    blocks = np.zeros((9, nb))
    for s in range(lo, hi, chunk):
        e = slice(s, min(s + chunk, hi))
        g = G[e]
        M = ((g * dx[e][:, None, :]) @ g.transpose(0, 2, 1)).reshape(-1, 3, nloc, 3, nloc)   # [e, k, a, l, b]
        if pairs is None:
            M = M.transpose(0, 1, 3, 2, 4).reshape(-1, 9, nloc * nloc)                     # [e, (k,l), (a,b)]
        else:
            M = M[pairs].transpose(1, 2, 3, 0).reshape(-1, 9, ia.size)                     # [e, (k,l), t]
        Cm = C[e].transpose(0, 1, 3, 2, 4).reshape(-1, 9, 9)      # [e, (i,j), (k,l)]
        K = np.matmul(Cm, M)                                       # [e, (i,j), pair]
        idx = plan.slot[e].ravel()
        flip = plan.local[e] != (ia * nloc + ib)[None, :] if pairs is not None else None
        for ij in range(9):
            w = K[:, ij, :] if flip is None else np.where(flip, K[:, _TRANSPOSED[ij], :], K[:, ij, :])
            blocks[ij] += np.bincount(idx, weights=w.ravel(), minlength=nb)
    return blocks


#: the component ji of a 3x3 block's component ij (row-major)
_TRANSPOSED = np.array([0, 3, 6, 1, 4, 7, 2, 5, 8])


def assemble_body_force(basis, f_q: np.ndarray, elements: np.ndarray | None = None) -> np.ndarray:
    """Load vector [N], shape=(3N,), of a body force density f [N/mm^3] given at quadrature points,
    shape=(3, ne, nq); or the load vectors, shape=(3N, m), of a stack of them, shape=(m, 3, ne, nq).
    ``elements``: the indices of the elements ``f_q`` is given on (ne of them; zero on the others)."""
    F = f_q if f_q.ndim == 4 else f_q[None]
    e = slice(None) if elements is None else np.asarray(elements)
    nloc = len(basis.basis)
    w = np.stack([np.asarray(basis.basis[a][0])[e] for a in range(nloc)]) * basis.dx[e][None]   # (nloc, ne, nq)
    fe = np.einsum("aeq,mieq->meai", w, F, optimize=True)          # (m, ne, nloc, 3)
    idx = vector_dofs(basis)[e].ravel()
    out = np.stack([np.bincount(idx, weights=fe[k].ravel(), minlength=3 * basis.N) for k in range(F.shape[0])],
                   axis=1)
    return out if f_q.ndim == 4 else out[:, 0]
