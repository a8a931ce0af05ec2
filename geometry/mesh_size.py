"""The element size of a rod's mesh: the default from the thinnest wall, and the check that a size the user gives
does not ask for a mesh no machine finishes."""
from __future__ import annotations

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.massprops import part_mass_properties
from rodlab.core.units import kg_m3_to_kg_mm3

from .errors import GeometryError

__all__ = ["default_size_mm", "check_element_count", "MAX_ELEMENTS"]


def default_size_mm(design: RodDesign, order: int = 2) -> float:
    """Element size from the thinnest wall: 2 x wall for curved P2 (<= 0.15 % from converged), wall/2 for P1."""
    walls = [design.pipe_I.wall_mm, design.pipe_II.wall_mm]
    if design.has_bend:
        walls.append(design.bend.wall_mm)
    wall = min(walls)
    return 2.0 * wall if order == 2 else 0.5 * wall


#: meshes beyond this many tetrahedra (estimated from the rod's volume) are refused: gmsh would run for hours and
#: the solve needs tens of GB (rod 1#'s default mesh: ~16 000 tetrahedra whole)
MAX_ELEMENTS = 3_000_000


def check_element_count(design: RodDesign, h: float, order: int) -> None:
    """Refuse an element size that would give more than :data:`MAX_ELEMENTS` tetrahedra: the rod's volume (its
    parts' masses over their densities) over a regular tetrahedron's (h^3 / (6 sqrt 2)); a new user's ``--size
    0.01`` ran for ten minutes without a word."""
    volume = sum(mp.mass_kg / kg_m3_to_kg_mm3(design.material_of(part).density_kg_m3)
                 for part, mp in part_mass_properties(design).items())
    per = h ** 3 / (6 * np.sqrt(2))
    estimate = volume / per
    if estimate > MAX_ELEMENTS:
        least = (volume / MAX_ELEMENTS * 6 * np.sqrt(2)) ** (1 / 3)
        raise GeometryError(f"size {h:g} mm would make ~{estimate:.2g} tetrahedra of rod {design.name!r} "
                            f"({volume:.3g} mm^3; at most {MAX_ELEMENTS:.0e}: hours of meshing, tens of GB to "
                            f"solve); give --size {least:.2g} mm or more (the default, 2 x the thinnest wall for "
                            f"order 2: {default_size_mm(design, order):g} mm)", key="size")
