"""The FEA mesh of a rod as the core type that ``geometry`` produces and ``fea`` consumes."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .enums import Part

__all__ = ["RodMesh", "LinearTopology"]


@dataclass
class RodMesh:
    """A rod's FEA mesh in {T} [mm].

    Attributes
    ----------
    mesh : ``skfem.MeshTet2`` (order 2) or ``skfem.MeshTet1`` (order 1)
    parts : the parts present, in tag order; ``parts[part_index[e]]`` is element e's part
    part_index : shape=(n_elements,) int, index into ``parts``
    tube_axis : shape=(n_elements, 3), unit local tube axis at each element (along the centreline,
        following the bend) for transversely-isotropic materials
    flange_facets, ball_facets : skfem facet indices of the clamped face and the ball's sphere
    size_mm, order : what was asked
    min_quality : worst element quality (gmsh minSICN; <= 0 means inverted)
    sha256 : hash of nodes and connectivity (determinism check)
    symmetry_facets : ``None`` for a whole rod; for a half mesh (``y_T >= 0``, the rod mirrored about its
        bend plane ``y_T = 0``) the facet indices on that plane

    The whole rod of a half mesh (:meth:`mirrored`) is made once and kept (its picture and its field file both
    need it: ~0.2 s each on rod 1#); a RodMesh is not changed after it is made.
    """

    mesh: object
    parts: tuple
    part_index: np.ndarray
    tube_axis: np.ndarray
    flange_facets: np.ndarray
    ball_facets: np.ndarray
    size_mm: float
    order: int
    min_quality: float
    sha256: str
    msh_path: Path | None = None
    stats: dict = field(default_factory=dict)
    symmetry_facets: np.ndarray | None = None
    #: the whole rod, once :meth:`mirrored` made it (not pickled: :meth:`__getstate__`; dataclasses.asdict would copy it)
    _whole: "RodMesh | None" = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n = self.mesh.t.shape[1]
        if self.part_index.shape != (n,) or self.tube_axis.shape != (n, 3):
            raise ValueError(f"part_index must have shape ({n},) and tube_axis ({n}, 3); got "
                             f"{self.part_index.shape}, {self.tube_axis.shape}")

    def __getstate__(self) -> dict:
        """Pickled (the mesh cache) without the whole rod kept by :meth:`mirrored`: it is made again."""
        return {k: v for k, v in self.__dict__.items() if k != "_whole"}

    @property
    def is_half(self) -> bool:
        """True for a half mesh (``y_T >= 0``) of a rod mirror-symmetric about ``y_T = 0``."""
        return self.symmetry_facets is not None

    def mirrored(self) -> "RodMesh":
        """The whole rod from a half mesh: the half and its mirror image about ``y_T = 0``, conforming on the
        plane (its nodes shared). Elements ``0..ne-1`` are the half's, ``ne..2ne-1`` their images in the same
        order, with local vertices 1 and 2 (and their edges) swapped so that every element stays positively
        oriented (CalculiX and VTK reject inverted tetrahedra). Made at the first call, the same object after."""
        if not self.is_half:
            raise ValueError("mirrored() needs a half mesh (symmetry_facets is None: this is a whole rod)")
        if self._whole is None:
            self._whole = self._mirror()
        return self._whole

    def _mirror(self) -> "RodMesh":
        """The whole rod, made anew (see :meth:`mirrored`)."""
        from skfem import Basis
        from skfem.element import ElementTetP1, ElementTetP2

        from .skfem_tet import MeshTet1Keyed, MeshTet2Keyed  # heavy: skfem (scikit-fem, ~0.2 s)

        elem = ElementTetP2() if self.order == 2 else ElementTetP1()
        basis = Basis(self.mesh, elem, intorder=1)
        x = basis.doflocs                                      # (3, n) every node, curved positions
        t = basis.element_dofs                                 # (10 or 4, ne)
        on_plane = np.abs(x[1]) < 1e-6
        image = np.arange(x.shape[1])
        off = np.nonzero(~on_plane)[0]
        image[off] = x.shape[1] + np.arange(off.size)
        xm = np.concatenate([x, x[:, off] * np.array([[1.0], [-1.0], [1.0]])], axis=1)
        swap = [0, 2, 1, 3, 6, 5, 4, 7, 9, 8] if t.shape[0] == 10 else [0, 2, 1, 3]   # edges 01 12 02 03 13 23
        tm = np.concatenate([t, image[t][swap]], axis=1)
        mesh = (MeshTet2Keyed if self.order == 2 else MeshTet1Keyed)(xm, tm)
        flip = np.array([1.0, -1.0, 1.0])
        z0 = float(self.mesh.p[2, self.mesh.facets[:, self.flange_facets]].mean())
        flange = mesh.facets_satisfying(lambda p: np.abs(p[2] - z0) < 1e-6, boundaries_only=True)
        ball_r = np.linalg.norm(self.mesh.p[:, self.mesh.facets[:, self.ball_facets]].mean(axis=1), axis=0)
        lo, hi = ball_r.min(), ball_r.max()
        ball = mesh.facets_satisfying(lambda p: (np.linalg.norm(p, axis=0) > lo - 1e-9)
                                      & (np.linalg.norm(p, axis=0) < hi + 1e-9), boundaries_only=True)
        return RodMesh(mesh, self.parts, np.concatenate([self.part_index, self.part_index]),
                       np.concatenate([self.tube_axis, self.tube_axis * flip]), flange, ball, self.size_mm,
                       self.order, self.min_quality, self.sha256 + "-mirrored", None,
                       dict(self.stats, half=False, mirrored_from_half=True))

    def elements_of(self, part: Part) -> np.ndarray:
        """Element indices of ``part``."""
        return np.nonzero(self.part_index == self.parts.index(part))[0]

    def volume_by_part(self) -> dict[Part, float]:
        """Mesh volume of each part [mm^3] (exact quadrature over the curved elements)."""
        from skfem import Basis, ElementTetP0, Functional
        basis = Basis(self.mesh, ElementTetP0(), intorder=2) if self.order == 2 else Basis(self.mesh, ElementTetP0())
        vol = Functional(lambda w: 1.0 + 0 * w.x[0]).elemental(basis)
        return {p: float(vol[self.elements_of(p)].sum()) for p in self.parts}


@dataclass(frozen=True)
class LinearTopology:
    """The tetrahedra of a mesh before its elements are curved: all that a solver's node ordering and assembly
    plan depend on, known while the mesher still places and optimises the edge nodes of an order-2 mesh.

    Attributes
    ----------
    t : shape=(4, n_elements) int64, each element's vertices in the finished mesh's vertex numbering and its
        element order (``RodMesh.mesh.t``; dimensionless indices)
    n_vertices : the finished mesh's vertex count (every vertex is some element's)
    """

    t: np.ndarray
    n_vertices: int

    def __post_init__(self) -> None:
        t = self.t
        if not isinstance(t, np.ndarray) or t.ndim != 2 or t.shape[0] != 4 or t.dtype != np.int64:
            raise ValueError(f"LinearTopology: t must be an int64 array of shape (4, n_elements), got "
                             f"{getattr(t, 'dtype', type(t).__name__)} {getattr(t, 'shape', '')}")
        if t.size and (t.min() < 0 or t.max() >= self.n_vertices):
            raise ValueError(f"LinearTopology: vertex indices must lie in 0..{self.n_vertices - 1}, got "
                             f"{t.min()}..{t.max()}")
