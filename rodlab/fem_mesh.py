"""The FEA mesh of a rod as the core type that ``geometry`` produces and ``fea`` consumes."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .enums import Part

__all__ = ["RodMesh"]


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

    def __post_init__(self) -> None:
        n = self.mesh.t.shape[1]
        if self.part_index.shape != (n,) or self.tube_axis.shape != (n, 3):
            raise ValueError(f"part_index must have shape ({n},) and tube_axis ({n}, 3); got "
                             f"{self.part_index.shape}, {self.tube_axis.shape}")

    def elements_of(self, part: Part) -> np.ndarray:
        """Element indices of ``part``."""
        return np.nonzero(self.part_index == self.parts.index(part))[0]

    def volume_by_part(self) -> dict[Part, float]:
        """Mesh volume of each part [mm^3] (exact quadrature over the curved elements)."""
        from skfem import Basis, ElementTetP0, Functional
        basis = Basis(self.mesh, ElementTetP0(), intorder=2) if self.order == 2 else Basis(self.mesh, ElementTetP0())
        vol = Functional(lambda w: 1.0 + 0 * w.x[0]).elemental(basis)
        return {p: float(vol[self.elements_of(p)].sum()) for p in self.parts}
