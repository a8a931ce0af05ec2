"""Which mesh the solid model asks its mesher for, decided without the solver's imports.

:func:`solid_mesh_request` checks the element size and the model's size limit and returns the keywords the solid
model (:func:`fea.compute.solid_compliance`) calls its mesher with. It imports the core only (no scikit-fem,
scipy or PARDISO), so ``rodlab fea --model solid`` can start meshing in the background while those load
(:class:`rodlab.geometry.MeshPrefetch`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.massprops import part_mass_properties

from .errors import FeaError

__all__ = ["DEFAULT_GRADING", "MAX_DOFS", "MeshRequest", "default_solid_size_mm", "estimated_dofs",
           "solid_mesh_request"]

#: Element size at the section changes in the tubes as a fraction of the size, growth per mm of distance, and
#: the bend's size as a fraction of the size (see ``geometry.mesh_rod``).
DEFAULT_GRADING = (0.3, 0.3, 0.7)
#: largest solid model attempted (CHOLMOD fill ~12 GB at this size on 24 GB machines)
MAX_DOFS = 1.5e6


@dataclass(frozen=True)
class MeshRequest:
    """The mesh the solid model asks for: ``size_mm`` [mm] far from the section changes, ``grading`` (as
    ``geometry.mesh_rod`` takes it, or None for a uniform size), ``half``: the half ``y_T >= 0`` only."""

    size_mm: float
    grading: tuple[float, ...] | None
    half: bool

    def __post_init__(self):
        if not (np.isfinite(self.size_mm) and self.size_mm > 0):
            raise FeaError(f"size must be a positive number of mm, got {self.size_mm!r}", key="size")

    @property
    def kwargs(self) -> dict:
        """The mesher's keywords: ``mesher(design, **request.kwargs)``."""
        return {"size_mm": self.size_mm, "grading": self.grading, "half": self.half}


def default_solid_size_mm(design: RodDesign) -> float:
    """3 x the thinnest wall: graded down to 1.2 x wall at the section changes."""
    walls = [design.pipe_I.wall_mm, design.pipe_II.wall_mm] + ([design.bend.wall_mm] if design.has_bend else [])
    return 3.0 * min(walls)


def estimated_dofs(design: RodDesign, size_mm: float, grading=DEFAULT_GRADING, half: bool = True) -> float:
    """DOFs of the curved-P2 mesh, estimated from the parts' volume (empirical: within ~15 % on rods 1#-6# at
    the default grading, ~22 vol / h^3 for a uniform half mesh); the whole rod has twice as many."""
    vol = sum(m.mass_kg / (design.material_of(p).density_kg_m3 * 1e-9) for p, m in part_mass_properties(design).items())
    per_volume = 117.0 if grading else 21.6
    return per_volume * vol / size_mm ** 3 * (1.0 if half else 2.0)


def solid_mesh_request(design: RodDesign, size_mm: float | None = None, grading=DEFAULT_GRADING,
                       symmetry: bool = True) -> MeshRequest:
    """The mesh of ``design`` the solid model solves: ``size_mm`` (None: :func:`default_solid_size_mm`),
    ``grading``, the half mesh with ``symmetry``. Raises :class:`~fea.errors.FeaError` (key ``size``) for a size
    that is not a positive number or a model above :data:`MAX_DOFS`."""
    try:
        h = default_solid_size_mm(design) if size_mm is None else float(size_mm)
    except (TypeError, ValueError) as e:
        raise FeaError(f"size must be a positive number of mm, got {size_mm!r}", key="size") from e
    request = MeshRequest(h, None if grading is None else tuple(grading), bool(symmetry))
    est = estimated_dofs(design, h, grading, symmetry)
    if est > MAX_DOFS:
        raise FeaError(f"the solid model of {design.name!r} at size {h:g} mm would need ~{est / 1e6:.1f} M DOFs "
                       f"(limit {MAX_DOFS / 1e6:.1f} M, ~{est / 1e6 * 12:.0f} GB): the walls are thin for the rod's "
                       f"volume. Use a larger --size (error grows) or --model frame", key="size")
    return request
