"""The discretisation error of a solid solve from that solve alone: stress recovery (Zienkiewicz-Zhu).

For unit loads ``f_i`` with exact displacements ``u_i`` and finite-element ones ``u_h,i``, Galerkin
orthogonality gives the compliance error exactly as the energy inner product of the errors
``e_i = u_i - u_h,i``::

    f_j^T u_i - f_j^T u_h,i = a(e_i, e_j)          (a Gram matrix: the FE compliance is too small, C - C_h >= 0)

The recovery estimator replaces the unknown error stress ``sigma(e_i)`` by ``sigma*_i - sigma_h,i``, where
``sigma*_i`` is the finite-element stress averaged at the nodes (volume-weighted, separately in each part: the
stress jumps across a bond between materials) and interpolated with the displacement's own P2 functions::

    E_ij = integral (sigma*_i - sigma_h,i) : S : (sigma*_j - sigma_h,j) dV          (S = C^-1 of the element)

So ``E[0:3, 0:3]`` estimates the error of C_F [mm/N] and ``E[0:3, 3:6]`` that of C_g [mm/g0] (the ball-centre
displacement is, to the ball's own tiny deformation, the work conjugate of the unit ball loads). On a half mesh
the whole rod's energy is twice the half's, and a symmetric and an antisymmetric field are orthogonal over the
whole rod (their pairs are 0).

It needs no second mesh and no second factorisation, unlike the Richardson estimate of two solves
(``rodlab fea --error-estimate richardson``); docs/benchmarks/fea_error_estimate.md compares both with the
error against a much finer solve.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem.quadrature import get_quadrature

from .mapping import lagrange_basis

__all__ = ["recovery_error_matrix", "node_basis", "mandel"]

_PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
#: elements per chunk of the vectorised steps
CHUNK = 1024
_SQ2 = np.sqrt(2.0)


def mandel(C: np.ndarray) -> np.ndarray:
    """Stiffness tensors, shape=(n, 3, 3, 3, 3) -> their Mandel matrices, shape=(n, 6, 6) (energy-preserving:
    ``sigma_M = C_M eps_M`` and ``sigma : eps = sigma_M . eps_M``)."""
    w = np.array([1.0, 1.0, 1.0, _SQ2, _SQ2, _SQ2])
    out = np.empty((C.shape[0], 6, 6))
    for I, (i, j) in enumerate(_PAIRS):
        for J, (k, l) in enumerate(_PAIRS):
            out[:, I, J] = C[:, i, j, k, l] * w[I] * w[J]
    return out


def _mandel_strain_map() -> np.ndarray:
    """The Mandel strain from the displacement gradient, shape=(6, 9): ``eps_M = P @ du`` with ``du[3 k + i] =
    du_i/dx_k`` (the shear pairs symmetrised and weighted by sqrt 2, as :func:`mandel` weights the stiffness)."""
    P = np.zeros((6, 9))
    for I, (i, j) in enumerate(_PAIRS):
        if i == j:
            P[I, 4 * i] = 1.0
        else:
            P[I, 3 * j + i] = P[I, 3 * i + j] = 1.0 / _SQ2
    return P


#: :func:`_mandel_strain_map`
_MANDEL_STRAIN = _mandel_strain_map()


def _nodal_average(stress_nodes: np.ndarray, element_dofs: np.ndarray, part_index: np.ndarray,
                   volume: np.ndarray) -> np.ndarray:
    """Volume-weighted average of the element stresses at each (part, node): ``stress_nodes`` shape=(ne, nloc, 6,
    nc) -> the averaged value at each (element, node), same shape (a node shared by two parts keeps one value per
    part)."""
    ne, nloc = element_dofs.shape
    key = (part_index[:, None].astype(np.int64) * (element_dofs.max() + 1) + element_dofs).ravel()
    _, slot = np.unique(key, return_inverse=True)
    # the weighted sums of every (part, node) as one sparse product: (slots x element-nodes) @ (element-nodes x 36)
    A = sp.csr_matrix((np.repeat(volume, nloc), (slot, np.arange(slot.size))), shape=(int(slot.max()) + 1, slot.size))
    total = A @ stress_nodes.reshape(ne * nloc, -1)
    weight = np.asarray(A.sum(axis=1)).ravel()
    return (total / weight[:, None])[slot].reshape(stress_nodes.shape)


def _chunks(n: int, size: int = CHUNK):
    return (slice(s, min(s + size, n)) for s in range(0, n, size))


def recovery_error_matrix(nodes, C: np.ndarray, part_index: np.ndarray, U: np.ndarray,
                          half: bool = False, antisymmetric: tuple = ()) -> np.ndarray:
    """The estimated compliance error ``E`` (``C_exact - C_h`` to the estimator's accuracy), shape=(nc, nc),
    in the units of ``U^T f``.

    nodes : the solve's scalar element and mesh with one point at each of the element's nodes
    (:func:`node_basis`); C : stiffness tensors, shape=(ne, 3, 3, 3, 3)
    [N/mm^2]; part_index : part of each element, shape=(ne,); U : displacements, shape=(3 N, nc) [mm per unit
    load] (x, y, z per node); half / antisymmetric : a half mesh and the load cases whose fields are
    antisymmetric about its plane.
    """
    ed = nodes.element_dofs.T                                                    # (ne, nloc)
    Cm = mandel(C)
    mass, ref_volume = _reference_mass(nodes.elem)
    volume = nodes.dx.sum(axis=1) * ref_volume                                  # mean |det J| at the nodes x ref.
    s_nodes = _nodal_stresses(nodes, Cm, U)
    E = _difference_energy(_nodal_average(s_nodes, ed, part_index, volume), s_nodes, Cm, mass, volume)
    if half:
        E *= 2.0
        anti = np.isin(np.arange(E.shape[0]), antisymmetric)
        E[anti[:, None] != anti[None, :]] = 0.0
    return 0.5 * (E + E.T)


def _nodal_stresses(nodes, Cm: np.ndarray, U: np.ndarray) -> np.ndarray:
    """The FE stress (Mandel) at each element's nodes, shape=(ne, nloc, 6, nc), element chunk by chunk (the
    temporaries stay small: fresh memory is slow on a VM)."""
    ed = nodes.element_dofs.T
    ne, nloc = ed.shape
    nc = U.shape[1]
    U3 = U.reshape(-1, 3, nc)
    grads = np.stack([nodes.basis[a][0].grad for a in range(nloc)], axis=-1)    # (k, ne, nq, a)
    nq = grads.shape[2]
    CP = Cm @ _MANDEL_STRAIN                                                    # stress from du: (ne, 6, 9)
    out = np.empty((ne, nq, 6, nc))
    for c in _chunks(ne):
        G = np.ascontiguousarray(grads[:, c].transpose(1, 2, 0, 3)).reshape(-1, nq * 3, nloc)   # [e, (q, k), a]
        du = (G @ U3[ed[c]].reshape(-1, nloc, 3 * nc)).reshape(-1, nq, 9, nc)  # du_i/dx_k at 3 k + i
        out[c] = CP[c, None] @ du
    return out


def _difference_energy(s_star: np.ndarray, s_nodes: np.ndarray, Cm: np.ndarray, mass: np.ndarray,
                       volume: np.ndarray) -> np.ndarray:
    """``E_ij = int d_i : S : d_j`` of the nodal differences ``d = s_star - s_nodes``: the FE stress is linear in a
    (straight) element, so the P2 interpolant of the nodal values is exact and the energy is the element's P2
    mass matrix (its volume x the reference one) between its nodes."""
    ne, nloc, _, nc = s_nodes.shape
    S = np.linalg.inv(Cm)
    E = np.zeros((nc, nc))
    for c in _chunks(ne):
        d = s_star[c] - s_nodes[c]
        MSd = (mass @ (S[c, None] @ d).reshape(-1, nloc, 6 * nc)) * volume[c, None, None]
        E += d.reshape(-1, nc).T @ MSd.reshape(-1, nc)                          # sum over e, nodes, components
    return E


def _reference_mass(elem) -> tuple[np.ndarray, float]:
    """The element's mass matrix on the reference simplex divided by its volume, shape=(nloc, nloc), and that
    volume."""
    X, W = get_quadrature(elem.refdom, 2 * elem.maxdeg)
    phi = np.array([elem.lbasis(X, a)[0] for a in range(elem.doflocs.shape[0])])     # (nloc, nq)
    return (phi * W) @ phi.T / W.sum(), float(W.sum())


def node_basis(mesh, elem, doflocs: bool = True):
    """The element ``elem`` on ``mesh`` with one point at each of its nodes (the local DOFs' reference
    locations, equal weights), where :func:`recovery_error_matrix` takes the stresses it averages; ``doflocs``:
    with the nodes' global positions (``basis.doflocs``; the estimate does not need them)."""
    X = np.asarray(elem.doflocs, dtype=float).T
    return lagrange_basis(mesh, elem, quadrature=(X, np.full(X.shape[1], 1.0 / X.shape[1])), doflocs=doflocs)
