"""Natural frequencies of the solid rod clamped on the flange (scikit-fem): the check of :mod:`fea.modal`.

The generalised eigenproblem ``K phi = omega^2 M phi`` on the rod's 3-D mesh, with the same stiffness as the
static solve (:func:`fea.solve_compliance`: one material per part, carbon transversely isotropic) and the
consistent mass matrix ``M = int rho u . v`` of every part (the ball included, so its rotary inertia too).
The flange face is clamped. The lowest modes come from ARPACK in shift-invert mode about 0, the shift-invert
operator being the same sparse factorisation the static solve uses (PARDISO / CHOLMOD / SuperLU).

Held DOFs (clamp, symmetry plane) keep the stiffness pattern with a unit diagonal and get zero mass, so their
eigenvalues are infinite and never among the lowest. A half mesh (``RodMesh.is_half``) is solved as two
half-size problems, the modes symmetric about the bend plane (``u_y = 0`` on it) and the antisymmetric ones
(``u_x = u_z = 0``), and the two spectra merged: the same frequencies as the whole mesh.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from rodlab.core.design import RodDesign
from rodlab.core.units import kg_m3_to_kg_mm3

from .plan_cache import plan_for
from .stiffness_assembly import assemble_stiffness, scalar_basis
from .elasticity import element_tensors
from .errors import FeaError
from .solver import HeldSystem, PatternSolver, available_backend

__all__ = ["SolidModes", "solid_frequencies"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SolidModes:
    """The lowest natural frequencies of a solid rod on a rigid flange.

    frequencies_Hz : shape=(modes,), ascending; symmetric : shape=(modes,) bool, True for a mode symmetric
    about the bend plane (in-plane motion), False for an antisymmetric one (out of plane, torsion), all True
    on a whole mesh where the classes are not separated; dofs : of the mesh solved; mass_kg : of the whole
    rod; timings_s : per stage.
    """

    frequencies_Hz: np.ndarray
    symmetric: np.ndarray
    dofs: int
    mass_kg: float
    timings_s: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        f = np.asarray(self.frequencies_Hz, float)
        if f.ndim != 1 or np.asarray(self.symmetric).shape != f.shape:
            raise ValueError(f"frequencies_Hz and symmetric must be 1-D of one length, got {f.shape} and "
                             f"{np.asarray(self.symmetric).shape}")


def _mass_matrix(basis, density_kg_mm3: np.ndarray):
    """Consistent mass [kg], shape=(3N, 3N), DOFs ``3 node + component``; ``density_kg_mm3`` per element."""
    from skfem import BilinearForm

    @BilinearForm
    def mass(u, v, w):
        return w["rho"] * u * v

    rho = np.repeat(density_kg_mm3[:, None], basis.dx.shape[1], axis=1)
    return sp.kron(mass.assemble(basis, rho=rho), sp.identity(3), format="csr")


def _lowest(solve, M, held: np.ndarray, modes: int) -> np.ndarray:
    """The ``modes`` lowest eigenvalues ``lambda = omega^2`` [N/(mm kg)] of the held problem."""
    from scipy.sparse.linalg import LinearOperator, eigsh

    free = (~held).astype(float)
    n = held.size
    Mh = LinearOperator((n, n), matvec=lambda x: free * (M @ (free * np.ravel(x))), dtype=float)
    OPinv = LinearOperator((n, n), matvec=lambda x: solve((free * np.ravel(x))[:, None])[:, 0], dtype=float)
    # A is only read for its shape in shift-invert mode: the factorisation of K is OPinv
    lam = eigsh(Mh, k=modes, M=Mh, sigma=0.0, which="LM", OPinv=OPinv, return_eigenvectors=False)
    return np.sort(lam)


def solid_frequencies(design: RodDesign, rod_mesh, modes: int = 3, backend: str | None = None) -> SolidModes:
    """The first ``modes`` natural frequencies [Hz] of ``design`` on ``rod_mesh`` (a :class:`geometry.RodMesh`,
    whole or half) clamped at the flange face; see the module docstring."""
    if not isinstance(modes, (int, np.integer)) or modes < 1:
        raise FeaError(f"modes must be a positive integer, got {modes!r}", key="modes")
    t0 = time.perf_counter()
    timings = {}
    basis = scalar_basis(rod_mesh.mesh)
    materials = [design.material_of(p) for p in rod_mesh.parts]
    C = element_tensors(materials, rod_mesh.part_index, rod_mesh.tube_axis)
    dens = np.array([kg_m3_to_kg_mm3(m.density_kg_m3) for m in materials])[rod_mesh.part_index]
    backend = backend or available_backend()
    plan = plan_for(basis, backend)
    nodes = plan.node_order
    K = assemble_stiffness(basis, C, plan=plan)
    N = int(3 * basis.N)
    dof = np.arange(N) if nodes is None else (3 * nodes[:, None] + np.arange(3)).ravel()
    M = _mass_matrix(scalar_basis(rod_mesh.mesh, intorder=4), dens)[dof][:, dof]
    timings["assembly"] = time.perf_counter() - t0
    held0 = np.zeros(N, dtype=bool)
    clamp = basis.get_dofs(rod_mesh.flange_facets).all()
    if clamp.size == 0:
        raise FeaError("the flange face has no DOFs to clamp; the mesh lost its flange_face", key="flange_face")
    held0[(3 * clamp[:, None] + np.arange(3)).ravel()] = True
    classes = [(True, [1]), (False, [0, 2])] if rod_mesh.is_half else [(True, [])]
    plane = basis.get_dofs(rod_mesh.symmetry_facets).all() if rod_mesh.is_half else np.zeros(0, dtype=np.int64)
    system = HeldSystem(K)
    solver = PatternSolver(system.pattern, backend, ordering_method="amd" if nodes is None else "natural")
    t1 = time.perf_counter()
    found = []
    for symmetric, comps in classes:
        held = held0.copy()
        held[(3 * plane[:, None] + np.asarray(comps, dtype=np.int64)).ravel()] = True
        held = held[dof]
        solve = solver.factor(system.matrix(held))
        found += [(lam, symmetric) for lam in _lowest(solve, M, held, modes)]
    timings["eigen"] = time.perf_counter() - t1
    found.sort(key=lambda item: item[0])
    lam = np.array([item[0] for item in found[:modes]])
    if np.any(lam <= 0):
        raise FeaError(f"non-positive eigenvalue {lam.min():.3g}: the clamp does not hold the rod", key="flange_face")
    freqs = np.sqrt(lam * 1e3) / (2 * np.pi)              # K [N/mm] = 1e3 N/m, M [kg]
    mass = float((basis.dx * dens[:, None]).sum()) * (2.0 if rod_mesh.is_half else 1.0)
    timings["total"] = time.perf_counter() - t0
    log.info("solid modes %s: %s Hz, %d DOFs, %.1f s", design.name, np.round(freqs, 1), N, timings["total"])
    return SolidModes(freqs, np.array([item[1] for item in found[:modes]]), N, mass, timings)
